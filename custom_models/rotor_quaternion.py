"""`quaternion` solver: an independent formulation of the rotor (cf. seed 001).

Unit quaternion q (Rodrigues–Hamilton parameters, body → fixed) with the body-frame angular
velocity Ω and Euler's equations about the fixed point O in body axes:
    q' = ½ q ⊗ Ω,   I₀ Ω' + Ω × I₀ Ω = Rᵀ(−kγ + r_c × m g + M e_z),   A' = M (RΩ)·e_z.
Nothing of the Euler-vector split is used; γ comes only into the spring law. |q| is left free
(no renormalisation) so its drift is an honest accuracy measure, reported as an invariant.
"""
import numba as nb
import numpy as np

from . import rotor
from .rotation import matrix_to_quat, quat_times_vector, quat_to_matrix
from .rotor import (  # noqa: F401
    ADAPTIVE,
    DEFAULT_SETTINGS,
    I0,
    I0INV,
    INTEGRATORS,
    M_,
    RC0,
    TORQUE,
    G,
    check_settings,
)


@nb.njit(cache=True)
def rhs(t, y, p):
    q, W = y[0:4], y[4:7]
    R = quat_to_matrix(q)
    I0m = p[I0].reshape(3, 3)
    moment = rotor.spring_moment(R, p) + p[M_] * np.cross(R @ p[RC0], p[G])
    moment[2] += p[TORQUE]
    dy = np.empty(8)
    dy[0:4] = 0.5 * quat_times_vector(q, W)
    dy[4:7] = p[I0INV].reshape(3, 3) @ (R.T @ moment - np.cross(W, I0m @ W))
    dy[7] = p[TORQUE] * (R @ W)[2]
    return dy


@nb.njit(cache=True)
def guard(t, y, p):
    return rotor.tilt_guard(quat_to_matrix(y[0:4]))


def motion(Y, p):
    Rs = np.array([quat_to_matrix(y[0:4]) if np.isfinite(y).all() else np.full((3, 3), np.nan)
                   for y in Y])
    return Rs, np.einsum("nij,nj->ni", Rs, Y[:, 4:7]), Y[:, 7]


def initial_state(params, p):
    R0, omega0 = rotor.initial_motion(params, p)
    return np.concatenate([matrix_to_quat(R0), R0.T @ omega0, [0.0]])


def simulate(params, t_out, settings):
    p = rotor.pack(params)
    Y, stats, t_fail, reason, used = rotor.integrate(rhs, guard, initial_state(params, p), p,
                                                     t_out, settings)
    qn = np.linalg.norm(Y[:, 0:4], axis=1)
    return rotor.result(params, t_out, Y, stats, t_fail, reason, used, motion, p,
                        {"quaternion_norm": float(np.nanmax(np.abs(qn - 1.0)))})
