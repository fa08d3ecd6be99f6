"""Lagrange's equations of the custom press model and its energy bookkeeping.

Lagrange's equations of the second kind (paper eq. 35, checked by expanding (30)–(34)):
    Σ_j A_ij q''_j + Σ_jk (A_ij,k − ½ A_jk,i) q'_j q'_k = Q_i,     A_ij,k = ∂A_ij/∂q_k.
The paper's printed (33)–(37) carry index typos ("A1222", "A2222"); the form above is the
expansion of (30) and is what both solvers use.

Generalized forces from virtual work (paper eqs. 27–29): gravity on the lumped masses, the slider
spring–damper −k(x_C − x_C0) − c x_C' along x, the crank torque u·M(s) (the shared Kloss law) and
in the locked phase of press-cycle the shared working load −P tanh(x_C'/v_reg).

Energy bookkeeping: three work integrals ride along as states z = (W_motor, W_damper, W_press)
so that E = T + V_spring + V_gravity − W_motor + W_damper + W_press (+ the loss at the lock) must
stay constant. The guard stops a run whose balance jumps by more than energy_jump (default 1e3)
times the energy in play (T0 + the work terms): a blow-up stop that saves time, not an accuracy
test (the scene's energy bound, applied by the adapter, is that). Why so large: a *stable*
linear-acceleration run near its limit (h = 0.54·T) already shows a bounded true-energy error of
~25·E0 — the invariant of Newmark β = 1/6 weighs the potential by 1 − (ωh)²/12, which vanishes at
the limit — while past the limit the error grows by ~1.5× per step.
"""
import math

import numba as nb
import numpy as np

from compare.physics.press import motor_torque

from .press_kinematics import NEIGH, _stencil_positions, exact_derivatives, fd_gradients, rod_sine
from .press_model import (
    C_S,
    DPHI,
    DPSI,
    E0,
    E_JUMP,
    E_LOST,
    E_SCALE,
    GRAV,
    HV,
    ITEMS,
    K_S,
    L1,
    L2,
    L3,
    LOCK_PSI,
    MODE,
    N_ITEMS,
    NB,
    NZ,
    PHI,
    PRESS,
    PSI,
    SING_TOL,
    SOLVER,
    TH2,
    VREG,
    XA,
    XB,
    XC,
    XC0,
    YA,
    YB,
    U,
)

FAIL_SINGULAR, FAIL_STENCIL, FAIL_ENERGY = 10, 11, 12


# ---- Lagrange's equations -------------------------------------------------------------------
@nb.njit(cache=True)
def mass_matrix(G, p):
    """A_ij = Σ_items w (c·∇)_i (c·∇)_j."""
    A = np.zeros((2, 2))
    for it in range(int(p[N_ITEMS])):
        o = ITEMS + it * (NB + 1)
        g0 = 0.0
        g1 = 0.0
        for b in range(NB):
            g0 += p[o + b] * G[b, 0]
            g1 += p[o + b] * G[b, 1]
        w = p[o + NB]
        A[0, 0] += w * g0 * g0
        A[0, 1] += w * g0 * g1
        A[1, 1] += w * g1 * g1
    A[1, 0] = A[0, 1]
    return A


@nb.njit(cache=True)
def mass_matrix_derivative(G, H, p):
    """A_ij,k = Σ_items w (H_ik g_j + g_i H_jk) with g = c·∇, H = c·∇² (analytic)."""
    dA = np.zeros((2, 2, 2))
    for it in range(int(p[N_ITEMS])):
        o = ITEMS + it * (NB + 1)
        g = np.zeros(2)
        h = np.zeros((2, 2))
        for b in range(NB):
            cb = p[o + b]
            if cb != 0.0:
                g[0] += cb * G[b, 0]
                g[1] += cb * G[b, 1]
                for i in range(2):
                    for j in range(2):
                        h[i, j] += cb * H[b, i, j]
        w = p[o + NB]
        for i in range(2):
            for j in range(2):
                for k in range(2):
                    dA[i, j, k] += w * (h[i, k] * g[j] + g[i] * h[j, k])
    return dA


@nb.njit(cache=True)
def lagrange_exact(q, p):
    base, G, H = exact_derivatives(q[0], q[1], p)
    return base, G, mass_matrix(G, p), mass_matrix_derivative(G, H, p)


@nb.njit(cache=True)
def lagrange_partial(q, p):
    """The paper's method: A_ij from the velocity analogues, A_ij,k by central differences of
    A_ij over the same virtual steps (the garbled formula after eq. 31:
    A_12,1 = [A_12(φ+Δφ, ψ) − A_12(φ−Δφ, ψ)]/(2Δφ)). ok False: a stencil point has no root."""
    P, ok = _stencil_positions(q[0], q[1], p, 13)
    G = fd_gradients(P, NEIGH[0], p)
    A = mass_matrix(G, p)
    Af = mass_matrix(fd_gradients(P, NEIGH[1], p), p)
    Ab = mass_matrix(fd_gradients(P, NEIGH[2], p), p)
    Bf = mass_matrix(fd_gradients(P, NEIGH[3], p), p)
    Bb = mass_matrix(fd_gradients(P, NEIGH[4], p), p)
    dA = np.empty((2, 2, 2))
    for i in range(2):
        for j in range(2):
            dA[i, j, 0] = (Af[i, j] - Ab[i, j]) * 0.5 / p[DPHI]
            dA[i, j, 1] = (Bf[i, j] - Bb[i, j]) * 0.5 / p[DPSI]
    base = np.empty(NB)
    base[XA], base[YA], base[XB], base[YB], base[XC] = P[0, 0], P[0, 1], P[0, 2], P[0, 3], P[0, 4]
    base[PHI], base[PSI] = q[0], q[1]
    base[TH2] = math.atan2(P[0, 3] - P[0, 1], P[0, 2] - P[0, 0])
    return base, G, A, dA, ok


@nb.njit(cache=True)
def equations(q, qd, p, base, G, A, dA):
    """[q''_φ, q''_ψ, P_motor, P_damper, P_press] from Lagrange's equations (35).

    Locked (p[MODE] = 1): ψ is frozen (ψ' = ψ'' = 0) and only the φ equation remains,
    A_11 φ'' + ½ A_11,1 φ'² = Q_φ."""
    out = np.empty(2 + NZ)
    vC = G[XC, 0] * qd[0] + G[XC, 1] * qd[1]
    locked = p[MODE] != 0.0
    f_slider = -p[K_S] * (base[XC] - p[XC0]) - p[C_S] * vC
    f_press = -p[PRESS] * math.tanh(vC / p[VREG]) if locked else 0.0
    torque = motor_torque(qd[0], p[U])
    Q = np.empty(2)
    for i in range(2):
        grav = 0.0
        for b in range(NB):
            grav += p[HV + b] * G[b, i]
        Q[i] = -p[GRAV] * grav + (f_slider + f_press) * G[XC, i]
    Q[0] += torque
    for i in range(2):                        # Q − (A_ij,k − ½ A_jk,i) q'_j q'_k
        for j in range(2):
            for k in range(2):
                Q[i] -= (dA[i, j, k] - 0.5 * dA[j, k, i]) * qd[j] * qd[k]
    if locked:
        out[0] = Q[0] / A[0, 0]
        out[1] = 0.0
    else:
        det = A[0, 0] * A[1, 1] - A[0, 1] * A[0, 1]
        out[0] = (A[1, 1] * Q[0] - A[0, 1] * Q[1]) / det
        out[1] = (A[0, 0] * Q[1] - A[0, 1] * Q[0]) / det
    out[2] = torque * qd[0]
    out[3] = p[C_S] * vC * vC
    out[4] = -f_press * vC
    return out


@nb.njit(cache=True)
def acc_exact(t, q, qd, p):
    if abs(rod_sine(q[0], q[1], p)) >= 1.0:
        return np.full(2 + NZ, np.nan)
    base, G, A, dA = lagrange_exact(q, p)
    return equations(q, qd, p, base, G, A, dA)


@nb.njit(cache=True)
def acc_partial(t, q, qd, p):
    base, G, A, dA, ok = lagrange_partial(q, p)
    if not ok:
        return np.full(2 + NZ, np.nan)
    return equations(q, qd, p, base, G, A, dA)


# One entry point for both solvers (p[SOLVER]: 0 exact, 1 partial): the shared drivers take the
# model as a function argument, which numba neither caches nor shares between specialisations,
# so one specialisation per driver halves the compile time of a process that runs both.
@nb.njit(cache=True)
def acc_any(t, q, qd, p):
    return acc_partial(t, q, qd, p) if p[SOLVER] != 0.0 else acc_exact(t, q, qd, p)


@nb.njit(cache=True)
def f_any(t, y, p):
    r = acc_any(t, y[:2], y[2:4], p)
    dy = np.empty(y.shape[0])
    dy[:2] = y[2:4]
    dy[2:] = r
    return dy


# ---- energy and the guards --------------------------------------------------------------------
@nb.njit(cache=True)
def energy_terms(y, p):
    """(T, V_spring, V_gravity, E) for y = [φ, ψ, φ', ψ', W_motor, W_damper, W_press], with the
    exact kinematics: the physical energy whichever solver produced y."""
    base, G, H = exact_derivatives(y[0], y[1], p)
    A = mass_matrix(G, p)
    qd0, qd1 = y[2], y[3]
    T = 0.5 * (A[0, 0] * qd0 * qd0 + 2.0 * A[0, 1] * qd0 * qd1 + A[1, 1] * qd1 * qd1)
    dx = base[XC] - p[XC0]
    Vs = 0.5 * p[K_S] * dx * dx
    Vg = 0.0
    for b in range(NB):
        Vg += p[GRAV] * p[HV + b] * base[b]
    return T, Vs, Vg, T + Vs + Vg - y[4] + y[5] + y[6] + p[E_LOST]


@nb.njit(cache=True)
def _guard_common(y, p, reach):
    """Singular chart (rod within singular_tol of vertical), stencil reaching the double root,
    energy-balance jump (instability)."""
    s = rod_sine(y[0], y[1], p)
    if 1.0 - s * s < p[SING_TOL] * p[SING_TOL]:
        return FAIL_SINGULAR
    if abs(s) + reach >= 1.0:
        return FAIL_STENCIL
    T, Vs, Vg, E = energy_terms(y, p)
    scale = p[E_SCALE] + abs(y[4]) + abs(y[5]) + abs(y[6]) + p[E_LOST]
    if not abs(E - p[E0]) <= p[E_JUMP] * scale:
        return FAIL_ENERGY
    return 0


@nb.njit(cache=True)
def guard_any(t, y, p):
    # partial: the nested stencil reaches 2Δφ, 2Δψ; bound its change of s = sin θ2
    reach = 2.0 * (p[L1] * p[DPHI] + p[L3] * p[DPSI]) / p[L2] if p[SOLVER] != 0.0 else 0.0
    return _guard_common(y, p, reach)


@nb.njit(cache=True)
def lock_event(t, y, p):
    """press-cycle's lock: the rocker angle crosses lock_angle."""
    return y[1] - p[LOCK_PSI]
