"""`euler-vector` solver: the paper's axial + transverse Euler-vector formulation (seed 000).

State y = [K (3), γ (3), φ, A]: angular momentum about O in the fixed frame, the transverse
Euler vector γ ⊥ e (e = e_z), the axial turn φ and the drive work A. The rotation is split as
L = L(γ)·L(φ e); then
    ω = I⁻¹K,  I = L I₀ Lᵀ
    φ' = (e·Z⁻¹·ω)/(e·Z⁻¹·L(γ)·e),   γ' = Z⁻¹·(ω − φ' L(γ)·e)      (γ'·e = 0 by construction)
    K' = −kγ + r_c × m g + M e,   A' = M ω·e.
The denominator e·Z⁻¹·L(γ)·e equals (θ/2)·cot(θ/2), θ = |γ|: the split is singular at tilt π,
which `rotor.tilt_guard` reports.
"""
import numba as nb
import numpy as np

from . import rotor
from .rotation import rotation_tensor, rotation_z, transverse_vector, zhilin_inverse
from .rotor import (  # noqa: F401
    ADAPTIVE,
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


@nb.njit(cache=True)
def rotation(y):
    return rotation_tensor(y[3:6]) @ rotation_z(y[6])


@nb.njit(cache=True)
def rhs(t, y, p):
    K, gamma = y[0:3], y[3:6]
    Lg = rotation_tensor(gamma)
    L = Lg @ rotation_z(y[6])
    omega = L @ (p[I0INV].reshape(3, 3) @ (L.T @ K))
    Zi = zhilin_inverse(gamma)
    axis = Lg[:, 2]                                  # L(γ)·e, the body's spin axis
    phi_dot = (Zi @ omega)[2] / (Zi @ axis)[2]
    dy = np.empty(8)
    dy[3:6] = Zi @ (omega - phi_dot * axis)
    dy[6] = phi_dot
    rc = L @ p[RC0]
    dy[0:3] = -p[K_] * gamma + p[M_] * np.cross(rc, p[G])
    dy[2] += p[TORQUE]
    dy[7] = p[TORQUE] * omega[2]
    return dy


@nb.njit(cache=True)
def guard(t, y, p):
    return rotor.tilt_guard(rotation(y))


def motion(Y, p):
    Rs = np.array([rotation(y) if np.isfinite(y).all() else np.full((3, 3), np.nan) for y in Y])
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
    Y, stats, t_fail, reason, used = rotor.integrate(rhs, guard, initial_state(params, p), p,
                                                     t_out, settings)
    gamma_axial = np.nanmax(np.abs(Y[:, 5]))
    return rotor.result(params, t_out, Y, stats, t_fail, reason, used, motion, p,
                        {"gamma_axial": float(gamma_axial)})
