"""Andrews' squeezer in one minimal coordinate, the crank angle β: the press paper's Lagrange
method (seed 003) on a 1-DOF closed-loop mechanism. The six dependent angles s = (Θ, γ, Φ, δ,
Ω, ε) come from the loop closure g(β, s) = 0 (compare.physics.andrews) by Newton, warm-started
from the last solution (kept in `p`); the velocity analogue J = ∂q/∂β and its derivative
J' = ∂²q/∂β² come from the "partial systems" — the closed mechanism at β ± Δβ — by central
differences with the virtual step Δβ (setting `dbeta`), as the paper builds A_ij and A_ij,k.
With q' = J β', q'' = J β'' + J' β'², and Jᵀ Gᵀ = 0 (the loop forces do no virtual work):

    A β'' = Jᵀ (f(q, J β') − M J' β'²),      A = Jᵀ M(q) J,

f and M the test set's. One compiled `acc(t, q, q', p)` serves the shared linear-acceleration
driver (custom_models/integrators/linear_acceleration.py).
"""
import math

import numba as nb
import numpy as np

from compare.physics import andrews as phys

from .. import loops
from ..integrators.linear_acceleration import solve_small

NP = len(phys.NAMES)
DBETA, NEWTON_TOL, FLAG, WARM = NP, NP + 1, NP + 2, NP + 3     # WARM: 6 slots
P_LEN = WARM + 6
FAIL_CLOSURE = 10
MAX_NEWTON = 30


def pack(params: dict, dbeta: float, newton_tol: float, s0) -> np.ndarray:
    p = np.zeros(P_LEN)
    p[:NP] = phys.pack(params)
    p[DBETA], p[NEWTON_TOL] = dbeta, newton_tol
    p[WARM:WARM + 6] = s0
    return p


@nb.njit(cache=True)
def close(beta, guess, p):
    """q = (β, s) with g = 0 by Newton from s = guess; (q, ok)."""
    q = np.empty(7)
    q[0] = beta
    q[1:] = guess
    tol = p[NEWTON_TOL]
    for _ in range(MAX_NEWTON):
        g = phys.closure(q, p)
        G = phys.closure_jacobian(q, p)
        dx = solve_small(np.ascontiguousarray(G[:, 1:]), g)
        big = 0.0
        for k in range(6):
            if not math.isfinite(dx[k]):
                return q, False
            q[k + 1] -= dx[k]
            big = max(big, abs(dx[k]))
        if big <= tol:
            return q, True
    return q, False


@nb.njit(cache=True)
def analogues(beta, p):
    """q(β), J = ∂q/∂β, J' = ∂²q/∂β² from the partial systems at β, β ± Δβ; ok flag."""
    h = p[DBETA]
    q0, ok0 = close(beta, p[WARM:WARM + 6], p)
    qp, okp = close(beta + h, q0[1:], p)
    qm, okm = close(beta - h, q0[1:], p)
    J, J2 = loops.partial_systems(q0, qp, qm, h)
    return q0, J, J2, ok0 and okp and okm


@nb.njit(cache=True)
def acc(t, q, qd, p):
    """[β''] of the minimal form (NaN and FLAG set where the loops do not close)."""
    out = np.empty(1)
    qf, J, J2, ok = analogues(q[0], p)
    if not ok:
        p[FLAG] = FAIL_CLOSURE
        out[0] = np.nan
        return out
    p[WARM:WARM + 6] = qf[1:]
    b = qd[0]
    M = phys.mass_matrix(qf, p)
    f = phys.forces(qf, J * b, p)
    MJ = M @ J
    A = J @ MJ
    rhs = J @ (f - (M @ J2) * (b * b))
    out[0] = rhs / A
    return out


@nb.njit(cache=True)
def guard(t, y, p):
    return int(p[FLAG])


def full_state(Y: np.ndarray, p: np.ndarray):
    """The seven angles and rates (q = q(β), q' = J β') of each row of [β, β'] (NaN rows kept)."""
    return loops.full_state(Y, p, analogues, 7, WARM)
