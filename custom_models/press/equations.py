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

import numba as nb
import numpy as np

from compare.physics.press import loop_closure, motor_torque, press_load

from .kinematics import exact_kinematics, fd_gradients, rod_sine, stencil_positions
from .model import (
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
    PRESS,
    SIGMA,
    SING_TOL,
    SOLVER,
    VREG,
    XC,
    XC0,
    U,
)

FAIL_SINGULAR, FAIL_STENCIL, FAIL_ENERGY = 10, 11, 12


# ---- Lagrange's equations -------------------------------------------------------------------
# Everything on the path of one evaluation works on tuples over the base coordinates (gradients
# g0 = ∂/∂φ, g1 = ∂/∂ψ) and returns tuples: one right-hand side allocates nothing. A = (A11,
# A12, A22); dA = (A11,1, A11,2, A12,1, A12,2, A22,1, A22,2), A_ij,k at index (i + j)·2 + k.
NAN5 = (np.nan, np.nan, np.nan, np.nan, np.nan)


@nb.njit(cache=True)
def mass_terms(g0, g1, p):
    """A_ij = Σ_items w (c·∇)_i (c·∇)_j."""
    A11 = A12 = A22 = 0.0
    for it in range(int(p[N_ITEMS])):
        o = ITEMS + it * (NB + 1)
        a = 0.0
        b = 0.0
        for k in range(NB):
            a += p[o + k] * g0[k]
            b += p[o + k] * g1[k]
        w = p[o + NB]
        A11 += w * a * a
        A12 += w * a * b
        A22 += w * b * b
    return A11, A12, A22


@nb.njit(cache=True)
def mass_derivative_terms(g0, g1, h00, h01, h11, p):
    """A_ij,k = Σ_items w (H_ik g_j + g_i H_jk) with g = c·∇, H = c·∇² (analytic)."""
    a110 = a111 = a120 = a121 = a220 = a221 = 0.0
    for it in range(int(p[N_ITEMS])):
        o = ITEMS + it * (NB + 1)
        a = b = x00 = x01 = x11 = 0.0
        for k in range(NB):
            c = p[o + k]
            if c != 0.0:
                a += c * g0[k]
                b += c * g1[k]
                x00 += c * h00[k]
                x01 += c * h01[k]
                x11 += c * h11[k]
        w = p[o + NB]
        a110 += 2.0 * w * x00 * a
        a111 += 2.0 * w * x01 * a
        a120 += w * (x00 * b + a * x01)
        a121 += w * (x01 * b + a * x11)
        a220 += 2.0 * w * x01 * b
        a221 += 2.0 * w * x11 * b
    return a110, a111, a120, a121, a220, a221


@nb.njit(cache=True)
def lagrange_exact(q0, q1, p):
    """(x_C, g0, g1, A, dA) with the analytic kinematics."""
    base, g0, g1, h00, h01, h11 = exact_kinematics(q0, q1, p)
    return (base[XC], g0, g1, mass_terms(g0, g1, p),
            mass_derivative_terms(g0, g1, h00, h01, h11, p))


@nb.njit(cache=True)
def lagrange_partial(q0, q1, p):
    """The paper's method: A_ij from the velocity analogues, A_ij,k by central differences of
    A_ij over the same virtual steps (the garbled formula after eq. 31:
    A_12,1 = [A_12(φ+Δφ, ψ) − A_12(φ−Δφ, ψ)]/(2Δφ)). Returns (x_C, g0, g1, A, dA, ok); ok
    False: a stencil point has no root."""
    P, ok = stencil_positions(q0, q1, p)
    g0, g1 = fd_gradients(P, 0, p)
    A = mass_terms(g0, g1, p)
    f0, f1 = fd_gradients(P, 1, p)
    Af = mass_terms(f0, f1, p)
    f0, f1 = fd_gradients(P, 2, p)
    Ab = mass_terms(f0, f1, p)
    f0, f1 = fd_gradients(P, 3, p)
    Bf = mass_terms(f0, f1, p)
    f0, f1 = fd_gradients(P, 4, p)
    Bb = mass_terms(f0, f1, p)
    i0, i1 = 0.5 / p[DPHI], 0.5 / p[DPSI]
    dA = ((Af[0] - Ab[0]) * i0, (Bf[0] - Bb[0]) * i1, (Af[1] - Ab[1]) * i0,
          (Bf[1] - Bb[1]) * i1, (Af[2] - Ab[2]) * i0, (Bf[2] - Bb[2]) * i1)
    return P[0][0][XC], g0, g1, A, dA, ok


@nb.njit(cache=True)
def equations(qd0, qd1, xc, g0, g1, A, dA, p):
    """(q''_φ, q''_ψ, P_motor, P_damper, P_press) from Lagrange's equations (35).

    Locked (p[MODE] = 1): ψ is frozen (ψ' = ψ'' = 0) and only the φ equation remains,
    A_11 φ'' + ½ A_11,1 φ'² = Q_φ."""
    vC = g0[XC] * qd0 + g1[XC] * qd1
    locked = p[MODE] != 0.0
    f_slider = -p[K_S] * (xc - p[XC0]) - p[C_S] * vC
    f_press = press_load(vC, p[PRESS], p[VREG]) if locked else 0.0
    torque = motor_torque(qd0, p[U])
    grav0 = 0.0
    grav1 = 0.0
    for b in range(NB):
        grav0 += p[HV + b] * g0[b]
        grav1 += p[HV + b] * g1[b]
    Q0 = -p[GRAV] * grav0 + (f_slider + f_press) * g0[XC] + torque
    Q1 = -p[GRAV] * grav1 + (f_slider + f_press) * g1[XC]
    qd = (qd0, qd1)
    for j in range(2):                        # Q − (A_ij,k − ½ A_jk,i) q'_j q'_k
        for k in range(2):
            v = qd[j] * qd[k]
            Q0 -= (dA[j * 2 + k] - 0.5 * dA[(j + k) * 2]) * v
            Q1 -= (dA[(1 + j) * 2 + k] - 0.5 * dA[(j + k) * 2 + 1]) * v
    if locked:
        qdd0, qdd1 = Q0 / A[0], 0.0
    else:
        det = A[0] * A[2] - A[1] * A[1]
        qdd0, qdd1 = (A[2] * Q0 - A[1] * Q1) / det, (A[0] * Q1 - A[1] * Q0) / det
    return qdd0, qdd1, torque * qd0, p[C_S] * vC * vC, -f_press * vC


@nb.njit(cache=True)
def acc_exact_t(q0, q1, qd0, qd1, p):
    if abs(rod_sine(q0, q1, p)) >= 1.0:
        return NAN5
    xc, g0, g1, A, dA = lagrange_exact(q0, q1, p)
    return equations(qd0, qd1, xc, g0, g1, A, dA, p)


@nb.njit(cache=True)
def acc_partial_t(q0, q1, qd0, qd1, p):
    xc, g0, g1, A, dA, ok = lagrange_partial(q0, q1, p)
    if not ok:
        return NAN5
    return equations(qd0, qd1, xc, g0, g1, A, dA, p)


@nb.njit(cache=True)
def acc_any_t(q0, q1, qd0, qd1, p):
    """[q'', z'] of either solver (p[SOLVER]: 0 exact, 1 partial) as a tuple."""
    if p[SOLVER] != 0.0:
        return acc_partial_t(q0, q1, qd0, qd1, p)
    return acc_exact_t(q0, q1, qd0, qd1, p)


@nb.njit(cache=True)
def f_any_into(t, y, p, dy):
    """y' = [q', q'', z'] for y = [φ, ψ, φ', ψ', W_motor, W_damper, W_press], into dy."""
    r = acc_any_t(y[0], y[1], y[2], y[3], p)
    dy[0] = y[2]
    dy[1] = y[3]
    for i in range(2 + NZ):
        dy[2 + i] = r[i]


# The same as arrays, for the linear-acceleration driver (one entry point for both solvers: the
# shared drivers take the model as a function argument, compiled once per signature) and tests.
@nb.njit(cache=True)
def acc_any(t, q, qd, p):
    return np.array(acc_any_t(q[0], q[1], qd[0], qd[1], p))


@nb.njit(cache=True)
def acc_exact(t, q, qd, p):
    return np.array(acc_exact_t(q[0], q[1], qd[0], qd[1], p))


@nb.njit(cache=True)
def mass_matrix_any(q0, q1, p):
    """A(q) of the solver's own description (p[SOLVER]) as a 2×2 array."""
    if p[SOLVER] != 0.0:
        A = lagrange_partial(q0, q1, p)[3]
    else:
        A = lagrange_exact(q0, q1, p)[3]
    return np.array([[A[0], A[1]], [A[1], A[2]]])


# ---- energy, the output terms and the guards ---------------------------------------------------
@nb.njit(cache=True)
def energy_terms(y, p):
    """(T, V_spring, V_gravity, E) for y = [φ, ψ, φ', ψ', W_motor, W_damper, W_press], with the
    exact kinematics: the physical energy whichever solver produced y."""
    base, g0, g1, _, _, _ = exact_kinematics(y[0], y[1], p)
    A11, A12, A22 = mass_terms(g0, g1, p)
    qd0, qd1 = y[2], y[3]
    T = 0.5 * (A11 * qd0 * qd0 + 2.0 * A12 * qd0 * qd1 + A22 * qd1 * qd1)
    dx = base[XC] - p[XC0]
    Vs = 0.5 * p[K_S] * dx * dx
    Vg = 0.0
    for b in range(NB):
        Vg += p[GRAV] * p[HV + b] * base[b]
    return T, Vs, Vg, T + Vs + Vg - y[4] + y[5] + y[6] + p[E_LOST]


@nb.njit(cache=True)
def output_terms(Y, modes, p):
    """Per output row (mode modes[r]): φ'', x_C, T, V_spring + V_gravity; NaN rows stay NaN."""
    n = Y.shape[0]
    out = np.full((n, 4), np.nan)
    mode0 = p[MODE]
    for r in range(n):
        y = Y[r]
        finite = True
        for v in y:
            finite = finite and np.isfinite(v)
        if not finite:
            continue
        p[MODE] = modes[r]
        T, Vs, Vg, _ = energy_terms(y, p)
        out[r, 0] = acc_any_t(y[0], y[1], y[2], y[3], p)[0]
        out[r, 1] = loop_closure(y[0], y[1], p[L1], p[L2], p[L3], p[SIGMA])[4]
        out[r, 2] = T
        out[r, 3] = Vs + Vg
    p[MODE] = mode0
    return out


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
