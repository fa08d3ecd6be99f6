"""Bricard's mechanism in one minimal coordinate, θ = q0 (the ground joint at P0): the press
paper's Lagrange method as generalised for Andrews' squeezer (custom_models/andrews/model.py).
The five dependent joint angles come from the loop closure g_6(q) = I (compare.physics.bricard)
by Gauss–Newton — six equations of rank five on the mechanism, the redundant one consistent —
warm-started from the last solution (kept in `p`); the velocity analogue J = dq/dθ and its
derivative J2 = d²q/dθ² come from the "partial systems" — the closed mechanism at θ ± Δθ — by
central differences with the virtual step Δθ (setting `dtheta`). Then

    A θ'' = −(½ A' θ'² + V'),   A = Σ m|v_c|² + ωᵀIω,   ½ A' = Σ m v_c·a_c + ω·Iα,

for q' = J, q'' = J2 (compare.physics.bricard.accel; I each rod's inertia about its centre,
a uniform square prism of side a: compare.physics.bricard.principal_inertia). One compiled
`acc(t, q, q', p)` serves the shared linear-acceleration driver
(custom_models/integrators/linear_acceleration.py).
"""
import numba as nb
import numpy as np

from compare.physics import bricard as phys

from .. import loops

NP = len(phys.NAMES)
DTHETA, CLOSURE_TOL, FLAG, WARM = NP, NP + 1, NP + 2, NP + 3     # WARM: 5 slots
P_LEN = WARM + 5
FAIL_CLOSURE = 10
MAX_NEWTON = 30


def pack(params: dict, dtheta: float, closure_tol: float) -> np.ndarray:
    p = np.zeros(P_LEN)
    p[:NP] = phys.pack(params)
    p[DTHETA], p[CLOSURE_TOL] = dtheta, closure_tol
    return p


@nb.njit(cache=True)
def analogues(theta, p):
    """q(θ), J, J2 from the partial systems at θ, θ ± Δθ; ok flag."""
    h, tol = p[DTHETA], p[CLOSURE_TOL]
    q0, ok0 = phys.close(theta, p[WARM:WARM + 5], p, tol, MAX_NEWTON)
    qp, okp = phys.close(theta + h, q0[1:], p, tol, MAX_NEWTON)
    qm, okm = phys.close(theta - h, q0[1:], p, tol, MAX_NEWTON)
    J, J2 = loops.partial_systems(q0, qp, qm, h)
    return q0, J, J2, ok0 and okp and okm


@nb.njit(cache=True)
def acc(t, q, qd, p):
    """[θ''] of the minimal form (NaN and FLAG set where the loop does not close)."""
    out = np.empty(1)
    qf, J, J2, ok = analogues(q[0], p)
    if not ok:
        p[FLAG] = FAIL_CLOSURE
        out[0] = np.nan
        return out
    p[WARM:WARM + 5] = qf[1:]
    out[0] = phys.accel(qf, J, J2, qd[0], p)
    return out


@nb.njit(cache=True)
def guard(t, y, p):
    return int(p[FLAG])


def full_state(Y: np.ndarray, p: np.ndarray):
    """The six joint angles and rates (q(θ), J θ') of each row of [θ, θ'] (NaN rows kept)."""
    return loops.full_state(Y, p, analogues, 6, WARM)
