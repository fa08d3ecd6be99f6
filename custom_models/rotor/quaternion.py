"""`quaternion` solver: an independent formulation of the rotor (cf. seed 001).

Unit quaternion q (Rodrigues–Hamilton parameters, body → fixed) with the body-frame angular
velocity Ω and Euler's equations about the fixed point O in body axes:
    q' = ½ q ⊗ Ω,   I₀ Ω' + Ω × I₀ Ω = Rᵀ(−kγ + r_c × m g + M e_z),   A' = M (RΩ)·e_z.
Nothing of the Euler-vector split is used; γ comes only into the spring law. |q| is left free
(no renormalisation) so its drift is an honest accuracy measure, reported as an invariant.

The right-hand side is fused scalar code writing into `dy` (no allocation per evaluation).
"""
import numba as nb
import numpy as np

from compare.physics.rotation import (
    cross_t,
    mat_tvec_t,
    mat_vec_t,
    matrix_to_quat,
    quat_matrix_t,
    quats_to_matrices,
    transverse_t,
)

from ..integrators.lanes import LANES, nine
from . import batch
from . import model as rotor
from .model import (  # noqa: F401  (re-exported: the leaf's settings)
    ADAPTIVE,
    CHEAP_RTOL,
    DEFAULT_SETTINGS,
    I0,
    I0INV,
    INTEGRATORS,
    K_,
    M_,
    RC0,
    TORQUE,
    G,
    check_settings,
)

_I0, _I0INV, _RC0, _G = I0.start, I0INV.start, RC0.start, G.start


@nb.njit(cache=True, inline="always")
def _derivatives(y, yo, p, po, st):
    """The right-hand side as an 8-tuple; entry k of the state and of the parameters is
    y[yo + k·st], p[po + k·st]: st = 1 for one point, LANES for a lane of the lanes' workspace."""
    w, x, qy, z = y[yo], y[yo + st], y[yo + 2 * st], y[yo + 3 * st]
    W0, W1, W2 = y[yo + 4 * st], y[yo + 5 * st], y[yo + 6 * st]
    R = quat_matrix_t(w, x, qy, z)
    # fixed-frame moment: spring −kγ (γ of the body axis R·e_z), gravity r_c × m g, drive M e_z
    gx, gy = transverse_t(R[2], R[5], R[8])
    rc = mat_vec_t(R, p[po + _RC0 * st], p[po + (_RC0 + 1) * st], p[po + (_RC0 + 2) * st])
    cg = cross_t(rc[0], rc[1], rc[2], p[po + _G * st], p[po + (_G + 1) * st],
                 p[po + (_G + 2) * st])
    k, m, torque = p[po + K_ * st], p[po + M_ * st], p[po + TORQUE * st]
    mb = mat_tvec_t(R, -k * gx + m * cg[0], -k * gy + m * cg[1], m * cg[2] + torque)
    # Euler's equations in body axes: Ω' = I₀⁻¹ (Rᵀ M − Ω × I₀Ω)
    I0_, I1, I2, I3, I4, I5, I6, I7, I8 = nine(p, po + _I0 * st, st)
    IW = (I0_ * W0 + I1 * W1 + I2 * W2, I3 * W0 + I4 * W1 + I5 * W2,
          I6 * W0 + I7 * W1 + I8 * W2)
    gyro = cross_t(W0, W1, W2, IW[0], IW[1], IW[2])
    b0, b1, b2 = mb[0] - gyro[0], mb[1] - gyro[1], mb[2] - gyro[2]
    J0, J1, J2, J3, J4, J5, J6, J7, J8 = nine(p, po + _I0INV * st, st)
    # q' = ½ q ⊗ (0, Ω) with the unnormalised q
    return (0.5 * (-x * W0 - qy * W1 - z * W2), 0.5 * (w * W0 + qy * W2 - z * W1),
            0.5 * (w * W1 + z * W0 - x * W2), 0.5 * (w * W2 + x * W1 - qy * W0),
            J0 * b0 + J1 * b1 + J2 * b2, J3 * b0 + J4 * b1 + J5 * b2,
            J6 * b0 + J7 * b1 + J8 * b2, torque * (R[6] * W0 + R[7] * W1 + R[8] * W2))


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
    """The right-hand side as a new array (for linearisations and tests)."""
    dy = np.empty(8)
    rhs_into(t, y, p, dy)
    return dy


@nb.njit(cache=True)
def guard(t, y, p):
    w, x, qy, z = y[0], y[1], y[2], y[3]
    return rotor.tilt_guard_z(1.0 - 2.0 * (x * x + qy * qy) / (w * w + x * x + qy * qy + z * z))


@nb.njit(cache=True, inline="always")
def _motion(y, o, st):
    """One row of `motion` as a 13-tuple (rotation row-major, fixed-frame ω, work), entry k of
    the state at y[o + k·st]."""
    R = quat_matrix_t(y[o], y[o + st], y[o + 2 * st], y[o + 3 * st])
    w = mat_vec_t(R, y[o + 4 * st], y[o + 5 * st], y[o + 6 * st])
    return R + w + (y[o + 7 * st],)


@nb.njit(cache=True)
def kinematics(Y, p, out):
    """The rows of `motion` for the batch path."""
    for i in range(Y.shape[0]):
        m = _motion(Y[i], 0, 1)
        for k in range(13):
            out[i, k] = m[k]


@nb.njit(cache=True, error_model="numpy")
def row_lanes(Z):
    """The batch's row reduce on every lane (`batch.reduce_lanes`)."""
    for lane in range(LANES):
        m = _motion(Z, lane, LANES)
        for k in range(13):
            Z[batch.Z_O + k * LANES + lane] = m[k]
    batch.reduce_lanes(Z)


def motion(Y, p):
    """Rotations, fixed-frame ω and work per output row (NaN rows stay NaN)."""
    Rs = quats_to_matrices(np.ascontiguousarray(Y[:, 0:4]))
    return Rs, np.einsum("nij,nj->ni", Rs, Y[:, 4:7]), Y[:, 7]


def initial_state(params, p):
    R0, omega0 = rotor.initial_motion(params, p)
    return np.concatenate([matrix_to_quat(R0), R0.T @ omega0, [0.0]])


def simulate(params, t_out, settings):
    p = rotor.pack(params)
    Y, stats, t_fail, reason, used = rotor.integrate(rhs_into, guard,
                                                     initial_state(params, p), p, t_out,
                                                     settings)
    qn = np.linalg.norm(Y[:, 0:4], axis=1)
    unit = Y[:, 0:4] / qn[:, None]
    unit *= np.where(unit[:, :1] < 0, -1.0, 1.0)             # w ≥ 0, as matrix_to_quat gives
    return rotor.result(params, t_out, Y, stats, t_fail, reason, used, motion, p,
                        {"quaternion_norm": float(np.nanmax(np.abs(qn - 1.0)))}, unit)


def regimes(params_list, t_out, settings, channel, levels, window):
    """Many points in one compiled call, each reduced to its regime (`batch.regimes`)."""
    return batch.regimes(rhs_into, guard, kinematics, initial_state, params_list, t_out,
                         settings, channel, levels, window, (rhs_lanes, row_lanes))
