"""`euler-vector` solver: the paper's axial + transverse Euler-vector formulation (seed 000).

State y = [K (3), γ (3), φ, A]: angular momentum about O in the fixed frame, the transverse
Euler vector γ ⊥ e (e = e_z), the axial turn φ and the drive work A. The rotation is split as
L = L(γ)·L(φ e); then
    ω = I⁻¹K,  I = L I₀ Lᵀ
    φ' = (e·Z⁻¹·ω)/(e·Z⁻¹·L(γ)·e),   γ' = Z⁻¹·(ω − φ' L(γ)·e)      (γ'·e = 0 by construction)
    K' = −kγ + r_c × m g + M e,   A' = M ω·e.
The denominator e·Z⁻¹·L(γ)·e equals (θ/2)·cot(θ/2), θ = |γ|: the split is singular at tilt π,
which `rotor.tilt_guard_z` reports.
"""
import numba as nb
import numpy as np

from compare.physics.rotation import (
    all_finite,
    cross_t,
    mat_tvec_t,
    mat_vec_t,
    rotation_tensor,
    rotation_z,
    rotation_zhilin_inverse_t,
    transverse_vector,
)
from compare.physics.trig import sincos

from ..integrators.lanes import LANES, nine
from . import batch
from . import model as rotor
from .model import (  # noqa: F401  (re-exported: the leaf's settings)
    ADAPTIVE,
    CHEAP_RTOL,
    DEFAULT_SETTINGS,
    I0INV,
    INTEGRATORS,
    K_,
    M_,
    RC0,
    TORQUE,
    G,
    check_settings,
)

E_Z = np.array([0.0, 0.0, 1.0])
_I0INV, _RC0, _G = I0INV.start, RC0.start, G.start


@nb.njit(cache=True)
def rotation(y):
    return rotation_tensor(y[3:6]) @ rotation_z(y[6])


@nb.njit(cache=True)
def rotations(Y):
    """(n, 3, 3) rotations of the state rows; NaN rows give NaN."""
    out = np.full((Y.shape[0], 3, 3), np.nan)
    for i in range(Y.shape[0]):
        if all_finite(Y[i]):
            R = rotation(Y[i])
            for a in range(3):
                for b in range(3):
                    out[i, a, b] = R[a, b]
    return out


@nb.njit(cache=True, inline="always")
def _axes(g0, g1, g2, phi):
    """L = L(γ)·L(φ e_z) and Z⁻¹(γ) as 9-tuples, and L(γ) itself."""
    Lg, Zi = rotation_zhilin_inverse_t(g0, g1, g2)
    s, c = sincos(phi)
    L = (c * Lg[0] + s * Lg[1], c * Lg[1] - s * Lg[0], Lg[2],
         c * Lg[3] + s * Lg[4], c * Lg[4] - s * Lg[3], Lg[5],
         c * Lg[6] + s * Lg[7], c * Lg[7] - s * Lg[6], Lg[8])
    return L, Zi, Lg


@nb.njit(cache=True, inline="always")
def _omega(L, K0, K1, K2, p, po, st):
    """ω = L I₀⁻¹ Lᵀ K, I₀⁻¹'s entry k at p[po + (I0INV + k)·st]."""
    u = mat_tvec_t(L, K0, K1, K2)                                   # body-frame momentum
    J = nine(p, po + _I0INV * st, st)
    return mat_vec_t(L, J[0] * u[0] + J[1] * u[1] + J[2] * u[2],
                     J[3] * u[0] + J[4] * u[1] + J[5] * u[2],
                     J[6] * u[0] + J[7] * u[1] + J[8] * u[2])


@nb.njit(cache=True, inline="always")
def _derivatives(y, yo, p, po, st):
    """The equations above as an 8-tuple (3×3 matrices as 9-tuples: no allocation); entry k of
    the state and of the parameters is y[yo + k·st], p[po + k·st]: st = 1 for one point,
    LANES for a lane of the lanes' workspace."""
    g0, g1, g2 = y[yo + 3 * st], y[yo + 4 * st], y[yo + 5 * st]
    L, Zi, Lg = _axes(g0, g1, g2, y[yo + 6 * st])
    om = _omega(L, y[yo], y[yo + st], y[yo + 2 * st], p, po, st)
    a0, a1, a2 = Lg[2], Lg[5], Lg[8]                                # L(γ)·e, the spin axis
    phi_dot = ((Zi[6] * om[0] + Zi[7] * om[1] + Zi[8] * om[2])
               / (Zi[6] * a0 + Zi[7] * a1 + Zi[8] * a2))
    dg = mat_vec_t(Zi, om[0] - phi_dot * a0, om[1] - phi_dot * a1, om[2] - phi_dot * a2)
    rc = mat_vec_t(L, p[po + _RC0 * st], p[po + (_RC0 + 1) * st], p[po + (_RC0 + 2) * st])
    cg = cross_t(rc[0], rc[1], rc[2], p[po + _G * st], p[po + (_G + 1) * st],
                 p[po + (_G + 2) * st])
    k, m, torque = p[po + K_ * st], p[po + M_ * st], p[po + TORQUE * st]
    return (-k * g0 + m * cg[0], -k * g1 + m * cg[1], -k * g2 + m * cg[2] + torque,
            dg[0], dg[1], dg[2], phi_dot, torque * om[2])


@nb.njit(cache=True)
def rhs_into(t, y, p, dy):
    d = _derivatives(y, 0, p, 0, 1)
    for k in range(8):
        dy[k] = d[k]


@nb.njit(cache=True, error_model="numpy")
def rhs_lanes(T, Z):
    """`rhs_into` on every lane of the lanes' workspace (`batch`'s layout)."""
    for lane in range(LANES):
        d = _derivatives(Z, lane, Z, batch.Z_P + lane, LANES)
        for k in range(8):
            Z[batch.Z_DY + k * LANES + lane] = d[k]


@nb.njit(cache=True)
def rhs(t, y, p):
    """The right-hand side as a new array (for the whirl linearisation and tests)."""
    dy = np.empty(8)
    rhs_into(t, y, p, dy)
    return dy


@nb.njit(cache=True)
def guard(t, y, p):
    # the tilt is |γ| (γ ⊥ e_z). Tested on |γ| itself, not on the axis' z component cos|γ|: a
    # step free of the output grid can carry |γ| past π, where cos|γ| comes back up
    th = np.sqrt(y[3] * y[3] + y[4] * y[4] + y[5] * y[5])
    return rotor.FAIL_TILT if th > rotor.TILT_LIMIT else 0


@nb.njit(cache=True, inline="always")
def _motion(y, o, p, po, st):
    """One row of `motion` as a 13-tuple (rotation row-major, fixed-frame ω, work); L and ω as
    `rhs_into` forms them."""
    L, _, _ = _axes(y[o + 3 * st], y[o + 4 * st], y[o + 5 * st], y[o + 6 * st])
    return L + _omega(L, y[o], y[o + st], y[o + 2 * st], p, po, st) + (y[o + 7 * st],)


@nb.njit(cache=True)
def kinematics(Y, p, out):
    """The rows of `motion` for the batch path."""
    for i in range(Y.shape[0]):
        m = _motion(Y[i], 0, p, 0, 1)
        for k in range(13):
            out[i, k] = m[k]


@nb.njit(cache=True, error_model="numpy")
def row_lanes(Z):
    """The batch's row reduce on every lane (`batch.reduce_lanes`)."""
    for lane in range(LANES):
        m = _motion(Z, lane, Z, batch.Z_P + lane, LANES)
        for k in range(13):
            Z[batch.Z_O + k * LANES + lane] = m[k]
    batch.reduce_lanes(Z)


def motion(Y, p):
    Rs = rotations(Y)
    I0inv = p[I0INV].reshape(3, 3)
    omegas = np.einsum("nij,jk,nlk,nl->ni", Rs, I0inv, Rs, Y[:, 0:3])
    return Rs, omegas, Y[:, 7]


def initial_state(params, p):
    R0, omega0 = rotor.initial_motion(params, p)
    gamma0 = transverse_vector(R0[:, 2])
    # R0 = L(γ0)·L(φ0): the axial part is what is left after the transverse turn
    Rphi = rotation_tensor(-gamma0) @ R0
    phi0 = np.arctan2(Rphi[1, 0], Rphi[0, 0])
    K0 = R0 @ p[rotor.I0].reshape(3, 3) @ R0.T @ omega0
    return np.concatenate([K0, gamma0, [phi0, 0.0]])


def simulate(params, t_out, settings):
    p = rotor.pack(params)
    Y, stats, t_fail, reason, used = rotor.integrate(rhs_into, guard, initial_state(params, p), p,
                                                     t_out, settings)
    gamma_axial = np.nanmax(np.abs(Y[:, 5]))
    return rotor.result(params, t_out, Y, stats, t_fail, reason, used, motion, p,
                        {"gamma_axial": float(gamma_axial)})


def regimes(params_list, t_out, settings, channel, levels, window):
    """Many points in one compiled call, each reduced to its regime (`batch.regimes`)."""
    return batch.regimes(rhs_into, guard, kinematics, initial_state, params_list, t_out,
                         settings, channel, levels, window, (rhs_lanes, row_lanes))
