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

from ..rotation import (
    cross_t,
    mat_tvec_t,
    mat_vec_t,
    matrix_to_quat,
    quat_matrix_t,
    quats_to_matrices,
    transverse_t,
)
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


@nb.njit(cache=True)
def rhs_into(t, y, p, dy):
    w, x, qy, z = y[0], y[1], y[2], y[3]
    W0, W1, W2 = y[4], y[5], y[6]
    R = quat_matrix_t(w, x, qy, z)
    # fixed-frame moment: spring −kγ (γ of the body axis R·e_z), gravity r_c × m g, drive M e_z
    gx, gy = transverse_t(R[2], R[5], R[8])
    rc = mat_vec_t(R, p[_RC0], p[_RC0 + 1], p[_RC0 + 2])
    cg = cross_t(rc[0], rc[1], rc[2], p[_G], p[_G + 1], p[_G + 2])
    k, m, torque = p[K_], p[M_], p[TORQUE]
    mb = mat_tvec_t(R, -k * gx + m * cg[0], -k * gy + m * cg[1], m * cg[2] + torque)
    # Euler's equations in body axes: Ω' = I₀⁻¹ (Rᵀ M − Ω × I₀Ω)
    I = p[_I0:_I0 + 9]
    IW = (I[0] * W0 + I[1] * W1 + I[2] * W2, I[3] * W0 + I[4] * W1 + I[5] * W2,
          I[6] * W0 + I[7] * W1 + I[8] * W2)
    gyro = cross_t(W0, W1, W2, IW[0], IW[1], IW[2])
    b0, b1, b2 = mb[0] - gyro[0], mb[1] - gyro[1], mb[2] - gyro[2]
    J = p[_I0INV:_I0INV + 9]
    dy[4] = J[0] * b0 + J[1] * b1 + J[2] * b2
    dy[5] = J[3] * b0 + J[4] * b1 + J[5] * b2
    dy[6] = J[6] * b0 + J[7] * b1 + J[8] * b2
    # q' = ½ q ⊗ (0, Ω) with the unnormalised q
    dy[0] = 0.5 * (-x * W0 - qy * W1 - z * W2)
    dy[1] = 0.5 * (w * W0 + qy * W2 - z * W1)
    dy[2] = 0.5 * (w * W1 + z * W0 - x * W2)
    dy[3] = 0.5 * (w * W2 + x * W1 - qy * W0)
    dy[7] = torque * (R[6] * W0 + R[7] * W1 + R[8] * W2)


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


@nb.njit(cache=True)
def kinematics(Y, p, out):
    """The rows of `motion` (rotation row-major, fixed-frame ω, work) for the batch path."""
    for i in range(Y.shape[0]):
        R = quat_matrix_t(Y[i, 0], Y[i, 1], Y[i, 2], Y[i, 3])
        for k in range(9):
            out[i, k] = R[k]
        out[i, 9], out[i, 10], out[i, 11] = mat_vec_t(R, Y[i, 4], Y[i, 5], Y[i, 6])
        out[i, 12] = Y[i, 7]


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
                         settings, channel, levels, window)
