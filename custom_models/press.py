"""Crank–rocker press with slider (seed 003, scenes `press` and `press-cycle`): the physics shared
by the two Lagrange solvers `press_partial` (the paper's finite-difference "partial systems") and
`press_exact` (the same equations with analytic derivatives).

Generalized coordinates q = (φ, ψ): crank angle and rocker angle (direction C→B).
    A = l1 (cos φ, sin φ),   y_B = l3 sin ψ,   |B − A| = l2,   x_C = x_B − l3 cos ψ,  y_C = 0.
The loop closure is solved in closed form (the paper's eq. 3 is a quadratic in x_B):
    x_B = x_A + σ √(l2² − (y_B − y_A)²),   σ = +1 for assembly 1 (x_B > x_A), −1 for assembly 2.
Written with the rod angle θ2: sin θ2 = s = (l3 sin ψ − l1 sin φ)/l2 and cos θ2 = σ√(1 − s²).
The chart (φ, ψ) breaks down where the root is double, cos θ2 = 0 (rod vertical): there
∂x_B/∂ψ → ∞. Both solvers stop there with a reason instead of dividing by zero.

Kinetic energy T = ½ q'ᵀ A(q) q' is a sum over "inertia items": a scalar coordinate c(q) (a
point's x or y, or a link angle) with a weight (mass or moment of inertia), T = ½ Σ w (∇c·q')².
Both mass models (paper: masses lumped at the joints, eq. 21; midpoint) are just item tables over
the eight base coordinates (x_A, y_A, x_B, y_B, x_C, φ, θ2, ψ). The solvers differ only in how
they get ∇c (and ∂A/∂q): central differences (partial) or analytic gradients/Hessians (exact).

Lagrange's equations of the second kind (paper eq. 35, checked by expanding (30)–(34)):
    Σ_j A_ij q''_j + Σ_jk (A_ij,k − ½ A_jk,i) q'_j q'_k = Q_i,     A_ij,k = ∂A_ij/∂q_k.
The paper's printed (33)–(37) carry index typos ("A1222", "A2222"); the form above is the
expansion of (30) and is what both solvers use.

Generalized forces from virtual work (paper eqs. 27–29): gravity on the lumped masses, the slider
spring–damper −k(x_C − x_C0) − c x_C' along x, the crank torque u·M(s) (Kloss), and in the
locked phase of press-cycle the working load −P tanh(x_C'/v_reg) (a Coulomb-type resistance,
regularised so every solver integrates the same smooth law).

Energy bookkeeping: three work integrals ride along as states z = (W_motor, W_damper, W_press)
so that E = T + V_spring + V_gravity − W_motor + W_damper + W_press (+ the loss at the lock) must
stay constant; the guard stops a run whose balance jumps by more than energy_jump (default 1e3)
times the energy in play (T0 + the work terms): a blow-up, not an accuracy test. Why so large:
a *stable* linear-acceleration run near its limit (h = 0.54·T) already shows a bounded true-energy
error of ~25·E0 — the invariant of Newmark β = 1/6 weighs the potential by 1 − (ωh)²/12, which
vanishes at the limit — while past the limit the error grows by ~1.5× per step.
"""
import math
import time

import numba as nb
from numba import types as nt
import numpy as np

from .integrators.explicit import GUARD, RHS, _MAT, _VEC, _stages
from .integrators.linear_acceleration import ACC
from .integrators import (ADAPTIVE_TABLEAUS, FAIL_REASONS, FIXED_TABLEAUS, LA_REASONS,
                          MODE_FIXED_POINT, MODE_NEWTON, MODE_PC, integrate_adaptive,
                          integrate_fixed, integrate_wilson, wilson_step)

# ---- scene constants (motor 4A80B4U3, Kloss characteristic; scene-press.md) -----------------
P_N, N_SYNC_RPM, S_N, LAMBDA_K, ROTOR_J = 1500.0, 1500.0, 0.058, 2.2, 0.0033
OMEGA_SYNC = 2.0 * math.pi * N_SYNC_RPM / 60.0
M_N = P_N / (OMEGA_SYNC * (1.0 - S_N))
M_K = LAMBDA_K * M_N
S_K = S_N * (LAMBDA_K + math.sqrt(LAMBDA_K ** 2 - 1.0))

CHANNELS = ("crank_angle", "crank_rate", "crank_accel", "rocker_angle", "slider_x",
            "loop_violation", "energy_balance")

DEFAULT_PARAMS = {
    "l1": 0.015, "l2": 0.040, "l3": 0.030, "m1": 4.6, "m2": 20.0, "m3": 18.0, "m4": 100.0,
    "J1": 0.034, "J2": 0.036, "J3": 0.0441, "phi0": -64.1, "psi0": -46.34, "omega0": 43.5,
    "rocker_rate0": 0.0, "gravity": 9.81, "slider_stiffness": 1e6, "slider_damping": 0.0,
    "gear_ratio": 1.0, "mass_model": "paper", "assembly": 1, "t_end": 0.05,
    "output_dt": 0.00125,
}
# press-cycle defaults. Why these: at idle (defaults above) the rocker starts at −46.34° with
# ψ' = 0 and swings down monotonically, through −50° at t ≈ 0.0395 s with ψ' ≈ −6 rad/s (a real,
# transversal crossing, so every solver locates it the same way, and a visible plastic loss).
# −50° also keeps the locked crank–slider free of toggles: with ψ fixed the loop closes for every
# φ only while l3|sin ψ| + l1 < l2, i.e. |ψ| < 56.4° (the paper's "rocker vertical", ψ = −90°,
# would make the locked linkage jam at φ ≈ 42°). lock_after = 0.02 s lets the idle transient
# run first; the lock holds 30 ms (the crank is stopped and thrown back by the slider spring);
# release at 0.07 s and 30 ms of idle again. press_force: 2 kN (~ 1/5 of the spring force at
# the locked stroke); press_force_vreg: the tanh regularisation speed of the load's direction.
CYCLE_DEFAULTS = {"lock_after": 0.02, "lock_angle": -50.0, "press_force": 2000.0,
                  "press_force_vreg": 0.01, "release_after": 0.07, "t_end": 0.1}

# base coordinates (columns of the gradient table G)
XA, YA, XB, YB, XC, PHI, TH2, PSI = range(8)
NB = 8

# ---- packed parameter array p -------------------------------------------------------------
(L1, L2, L3, SIGMA, GRAV, K_S, C_S, XC0, U, MK, SK, WSYNC, DPHI, DPSI, MODE, PRESS, VREG,
 SING_TOL, E0, E_JUMP, E_LOST, E_SCALE, N_ITEMS, SOLVER) = range(24)
HV = 24                       # 8 gravity "height" coefficients: V_g = g Σ HV_b · base_b
ITEMS = HV + NB               # n_items rows of (8 coefficients, weight)
MAX_ITEMS = 10
P_LEN = ITEMS + MAX_ITEMS * (NB + 1)

FAIL_SINGULAR, FAIL_STENCIL, FAIL_ENERGY = 10, 11, 12
NZ = 3                        # work integrals: motor, damper, press load


def _items(par):
    """Inertia items (coefficients over the base coordinates, weight) and gravity heights."""
    m1, m2, m3, m4 = (float(par[k]) for k in ("m1", "m2", "m3", "m4"))
    J1, J2, J3 = float(par["J1"]), float(par["J2"]), float(par["J3"])
    u = float(par["gear_ratio"])
    # scene: the rotor inertia u²·J_rotor joins the crank only with a reduction (u ≠ 1); the
    # paper (u = 1) applies the motor characteristic to the crank without it
    J1 = J1 + (u * u * ROTOR_J if u != 1.0 else 0.0)

    def c(**kw):
        v = np.zeros(NB)
        for name, val in kw.items():
            v[{"xA": XA, "yA": YA, "xB": XB, "yB": YB, "xC": XC, "phi": PHI, "th2": TH2,
               "psi": PSI}[name]] = val
        return v
    if par["mass_model"] == "paper":          # eq. 21: masses at A, B, C; J about them
        items = [(c(xA=1), m1), (c(yA=1), m1), (c(phi=1), J1), (c(xB=1), m2), (c(yB=1), m2),
                 (c(th2=1), J2), (c(xC=1), m3 + m4), (c(psi=1), J3)]
        heights = c(yA=m1, yB=m2)             # C stays on y = 0
    elif par["mass_model"] == "midpoint":     # link masses at mid-links, J about the mid-point
        items = [(c(xA=.5), m1), (c(yA=.5), m1), (c(phi=1), J1),
                 (c(xA=.5, xB=.5), m2), (c(yA=.5, yB=.5), m2), (c(th2=1), J2),
                 (c(xB=.5, xC=.5), m3), (c(yB=.5), m3), (c(psi=1), J3), (c(xC=1), m4)]
        heights = c(yA=0.5 * m1 + 0.5 * m2, yB=0.5 * m2 + 0.5 * m3)
    else:
        raise ValueError(f"mass_model must be 'paper' or 'midpoint', got {par['mass_model']!r}")
    return items, heights


def pack(par, dphi_deg=0.1, dpsi_deg=0.1, singular_tol=0.02, energy_jump=1e3):
    """Physical parameters (+ the finite-difference steps and guard limits) as one float array."""
    for k in ("l1", "l2", "l3"):
        if not float(par[k]) > 0.0:
            raise ValueError(f"{k} must be > 0, got {par[k]!r}")
    if int(par["assembly"]) not in (1, 2):
        raise ValueError(f"assembly must be 1 or 2, got {par['assembly']!r}")
    p = np.zeros(P_LEN)
    p[L1], p[L2], p[L3] = par["l1"], par["l2"], par["l3"]
    p[SIGMA] = 1.0 if int(par["assembly"]) == 1 else -1.0
    p[GRAV], p[K_S], p[C_S] = par["gravity"], par["slider_stiffness"], par["slider_damping"]
    p[U], p[MK], p[SK], p[WSYNC] = par["gear_ratio"], M_K, S_K, OMEGA_SYNC
    p[DPHI], p[DPSI] = math.radians(dphi_deg), math.radians(dpsi_deg)
    p[PRESS] = par.get("press_force", 0.0)
    p[VREG] = par.get("press_force_vreg", CYCLE_DEFAULTS["press_force_vreg"])
    p[SING_TOL], p[E_JUMP] = singular_tol, energy_jump
    items, heights = _items(par)
    p[N_ITEMS] = len(items)
    p[HV:HV + NB] = heights
    for i, (coef, w) in enumerate(items):
        p[ITEMS + i * (NB + 1): ITEMS + i * (NB + 1) + NB] = coef
        p[ITEMS + i * (NB + 1) + NB] = w
    phi0, psi0 = math.radians(par["phi0"]), math.radians(par["psi0"])
    xA, yA, xB, yB, xC, ok = positions(phi0, psi0, p)
    if not ok:
        raise ValueError(f"the loop cannot close at phi0={par['phi0']}, psi0={par['psi0']} deg "
                         "(|y_B - y_A| > l2)")
    p[XC0] = xC                               # the spring acts about the initial slider position
    return p


# ---- geometry --------------------------------------------------------------------------------
@nb.njit(cache=True)
def positions(phi, psi, p):
    """Joint positions from the loop closure; ok = False where no real root exists."""
    l1, l2, l3 = p[L1], p[L2], p[L3]
    xA, yA = l1 * math.cos(phi), l1 * math.sin(phi)
    yB = l3 * math.sin(psi)
    dy = yB - yA
    disc = l2 * l2 - dy * dy
    if disc < 0.0:
        return xA, yA, np.nan, yB, np.nan, False
    xB = xA + p[SIGMA] * math.sqrt(disc)
    return xA, yA, xB, yB, xB - l3 * math.cos(psi), True


@nb.njit(cache=True)
def rod_sine(phi, psi, p):
    """s = sin θ2; |s| → 1 is the double root (rod vertical)."""
    return (p[L3] * math.sin(psi) - p[L1] * math.sin(phi)) / p[L2]


@nb.njit(cache=True)
def exact_derivatives(phi, psi, p):
    """Base coordinates, their gradients G (8, 2) and Hessians H (8, 2, 2), analytically.

    sin θ2 = s(φ, ψ), cos θ2 = c2 = σ√(1 − s²):  ∇θ2 = ∇s/c2,  ∇²θ2 = ∇²s/c2 + s ∇s∇sᵀ/c2³;
    x_B = x_A + l2 c2 with ∇c2 = −s ∇θ2 and ∇²c2 = −∇θ2∇sᵀ − s ∇²θ2."""
    l1, l2, l3 = p[L1], p[L2], p[L3]
    cf, sf, cp, sp = math.cos(phi), math.sin(phi), math.cos(psi), math.sin(psi)
    s = (l3 * sp - l1 * sf) / l2
    c2 = p[SIGMA] * math.sqrt(max(0.0, 1.0 - s * s))
    base = np.empty(NB)
    G = np.zeros((NB, 2))
    H = np.zeros((NB, 2, 2))
    gs0, gs1 = -l1 * cf / l2, l3 * cp / l2
    hs00, hs11 = l1 * sf / l2, -l3 * sp / l2
    gt0, gt1 = gs0 / c2, gs1 / c2
    c3 = c2 * c2 * c2
    ht00 = hs00 / c2 + s * gs0 * gs0 / c3
    ht01 = s * gs0 * gs1 / c3
    ht11 = hs11 / c2 + s * gs1 * gs1 / c3
    base[XA], base[YA] = l1 * cf, l1 * sf
    G[XA, 0], H[XA, 0, 0] = -l1 * sf, -l1 * cf
    G[YA, 0], H[YA, 0, 0] = l1 * cf, -l1 * sf
    # x_B = x_A + l2 c2
    base[XB] = base[XA] + l2 * c2
    G[XB, 0] = G[XA, 0] - l2 * s * gt0
    G[XB, 1] = -l2 * s * gt1
    H[XB, 0, 0] = H[XA, 0, 0] + l2 * (-gt0 * gs0 - s * ht00)
    H[XB, 0, 1] = l2 * (-gt0 * gs1 - s * ht01)
    H[XB, 1, 0] = H[XB, 0, 1]
    H[XB, 1, 1] = l2 * (-gt1 * gs1 - s * ht11)
    base[YB] = l3 * sp
    G[YB, 1], H[YB, 1, 1] = l3 * cp, -l3 * sp
    base[XC] = base[XB] - l3 * cp
    G[XC, 0], G[XC, 1] = G[XB, 0], G[XB, 1] + l3 * sp
    H[XC, 0, 0], H[XC, 0, 1], H[XC, 1, 0] = H[XB, 0, 0], H[XB, 0, 1], H[XB, 1, 0]
    H[XC, 1, 1] = H[XB, 1, 1] + l3 * cp
    base[PHI], G[PHI, 0] = phi, 1.0
    base[TH2], G[TH2, 0], G[TH2, 1] = math.atan2(s, c2), gt0, gt1
    H[TH2, 0, 0], H[TH2, 0, 1], H[TH2, 1, 0], H[TH2, 1, 1] = ht00, ht01, ht01, ht11
    base[PSI], G[PSI, 1] = psi, 1.0
    return base, G, H


# ---- the paper's "partial systems": velocity analogues by central differences --------------
# Stencil of the nested differences (offsets in units of Δφ, Δψ): A_ij needs r at (±1, 0),
# (0, ±1) around its point; A_ij,k needs A at (±1, 0), (0, ±1): 13 distinct points in all.
STENCIL = np.array([[0, 0], [1, 0], [-1, 0], [0, 1], [0, -1], [2, 0], [-2, 0], [0, 2], [0, -2],
                    [1, 1], [1, -1], [-1, 1], [-1, -1]], dtype=np.int64)
# for A at centre, (+1,0), (−1,0), (0,+1), (0,−1): indices into STENCIL of (centre, +φ, −φ, +ψ, −ψ)
NEIGH = np.array([[0, 1, 2, 3, 4], [1, 5, 0, 9, 10], [2, 0, 6, 11, 12], [3, 9, 11, 7, 0],
                  [4, 10, 12, 0, 8]], dtype=np.int64)


@nb.njit(cache=True)
def _stencil_positions(phi, psi, p, n_pts):
    """x_A, y_A, x_B, y_B, x_C at the first n_pts stencil points; ok False if any is unreal."""
    P = np.empty((n_pts, 5))
    dphi, dpsi = p[DPHI], p[DPSI]
    ok = True
    for k in range(n_pts):
        xA, yA, xB, yB, xC, good = positions(phi + STENCIL[k, 0] * dphi,
                                             psi + STENCIL[k, 1] * dpsi, p)
        P[k, 0], P[k, 1], P[k, 2], P[k, 3], P[k, 4] = xA, yA, xB, yB, xC
        ok = ok and good
    return P, ok


@nb.njit(cache=True)
def fd_gradients(P, nb_idx, p):
    """Velocity analogues (∂r/∂φ, ∂r/∂ψ) of the partial systems PS1 (ψ frozen) and PS2 (φ
    frozen) by central differences (eqs. 6–8, 12–13); link angular-velocity analogues from the
    cross-product formula ω* = (AB × v*_BA)/|AB|² (eqs. 9, 14–15), the crank's exactly e_z."""
    c, fp, fm, sp, sm = nb_idx[0], nb_idx[1], nb_idx[2], nb_idx[3], nb_idx[4]
    G = np.zeros((NB, 2))
    inv = (0.5 / p[DPHI], 0.5 / p[DPSI])
    for b in range(5):
        G[b, 0] = (P[fp, b] - P[fm, b]) * inv[0]
        G[b, 1] = (P[sp, b] - P[sm, b]) * inv[1]
    G[PHI, 0] = 1.0
    dx, dy = P[c, 2] - P[c, 0], P[c, 3] - P[c, 1]          # AB
    ex, ey = P[c, 4] - P[c, 2], -P[c, 3]                   # BC (y_C = 0)
    for k in range(2):
        vx, vy = G[XB, k] - G[XA, k], G[YB, k] - G[YA, k]  # v*_BA
        G[TH2, k] = (dx * vy - dy * vx) / (dx * dx + dy * dy)
        wx, wy = G[XC, k] - G[XB, k], -G[YB, k]            # v*_CB
        G[PSI, k] = (ex * wy - ey * wx) / (ex * ex + ey * ey)
    return G


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
def motor_torque(rate, p):
    """Crank torque u·M(s), Kloss M = 2M_k/(s/s_k + s_k/s) written 2M_k s s_k/(s² + s_k²) so it
    is regular at synchronous speed (s = 0)."""
    s = 1.0 - p[U] * rate / p[WSYNC]
    return p[U] * 2.0 * p[MK] * s * p[SK] / (s * s + p[SK] * p[SK])


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
    torque = motor_torque(qd[0], p)
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
SOLVER_IDS = {"exact": 0.0, "partial": 1.0}


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


# ---- drivers ----------------------------------------------------------------------------------
# method ids of the event-capable segment driver (press-cycle)
M_RK, M_WILSON = 0, 1
EVENT = 50


@nb.njit(cache=True)
def _rk_step(f, t, y, p, h, A, B, C):
    n_st, ny = B.shape[0], y.shape[0]
    K = np.empty((n_st, ny))
    K[0] = f(t, y, p)
    _stages(f, t, y, p, h, A, C, K)
    y1 = y.copy()
    for j in range(ny):
        acc = 0.0
        for s in range(n_st):
            acc += B[s] * K[s, j]
        y1[j] += h * acc
    return y1


@nb.njit(nt.Tuple((nt.int64, nt.float64, _VEC, nt.int64, nt.int64, nt.int64))(
    RHS, ACC, GUARD, nt.int64, _VEC, _VEC, nt.float64, nt.float64, _VEC, nt.int64, _MAT,
    nt.float64, _MAT, _VEC, _VEC, nt.float64, nt.int64, nt.float64, nt.int64, nt.boolean,
    nt.float64, nt.float64), cache=True)
def segment(f, acc, guard, method, y0, p, t0, t_stop, t_out, i_next, Y, h_nom, tA, tB, tC,
            theta, la_mode, tol, max_iter, ev_on, psi_target, t_tol):
    """Fixed-step integration from (t0, y0) to t_stop, filling Y at the output times in
    (t0, t_stop]; intervals between stops are split into equal steps ≤ h_nom, so a segment may
    start off the output grid (after an event). With ev_on, stops at the first crossing of
    ψ = psi_target, located by bisection on the step length (re-stepping from the step start)
    to t_tol. Returns (code, t, y, i_next, steps, evals); code EVENT at an event, 0 at t_stop."""
    n_out = t_out.shape[0]
    t = t0
    y = y0.copy()
    steps = 0
    evals = 0
    qdd = np.zeros(2)
    zd = np.zeros(y.shape[0] - 4)
    if method == M_WILSON:
        r = acc(t, y[:2], y[2:4], p)
        qdd = r[:2].copy()
        zd = r[2:].copy()
        evals += 1
    n_st = tB.shape[0]
    i = i_next
    while True:
        on_grid = i < n_out and t_out[i] <= t_stop + 1e-12 * max(1.0, abs(t_stop))
        tb = t_out[i] if on_grid else t_stop
        span = tb - t
        if span > 0.0:
            nsub = max(1, int(math.ceil(span / h_nom - 1e-9)))
            h = span / nsub
            ta = t
            for k in range(nsub):
                tk = ta + k * h
                if method == M_RK:
                    y1 = _rk_step(f, tk, y, p, h, tA, tB, tC)
                    evals += n_st
                    code = 0
                else:
                    q1, qd1, qdd1, z1, zd1, ev, code = wilson_step(
                        acc, tk, y[:2], y[2:4], qdd, y[4:], zd, p, h, theta, la_mode, tol,
                        max_iter)
                    evals += ev
                    y1 = np.concatenate((q1, qd1, z1))
                steps += 1
                if code == 0:
                    for v in y1:
                        if not np.isfinite(v):
                            code = 1
                            break
                if code == 0:
                    code = guard(tk + h, y1, p)
                if code != 0:
                    return code, tk + h, y, i, steps, evals
                g0 = y[1] - psi_target
                g1 = y1[1] - psi_target
                if ev_on and g0 != 0.0 and g0 * g1 <= 0.0:
                    lo, hi = 0.0, h
                    y_hi = y1
                    while hi - lo > t_tol:
                        mid = 0.5 * (lo + hi)
                        if method == M_RK:
                            ym = _rk_step(f, tk, y, p, mid, tA, tB, tC)
                            evals += n_st
                        else:
                            q1, qd1, qdd1, z1, zd1, ev, c2 = wilson_step(
                                acc, tk, y[:2], y[2:4], qdd, y[4:], zd, p, mid, theta,
                                la_mode, tol, max_iter)
                            evals += ev
                            ym = np.concatenate((q1, qd1, z1))
                        if (ym[1] - psi_target) * g0 > 0.0:
                            lo = mid
                        else:
                            hi = mid
                            y_hi = ym
                    return EVENT, tk + hi, y_hi, i, steps, evals
                y = y1
                if method == M_WILSON:
                    qdd = qdd1
                    zd = zd1
            t = tb
        if on_grid:
            Y[i] = y
            i += 1
            if abs(tb - t_stop) <= 1e-12 * max(1.0, abs(t_stop)):
                return 0, t_stop, y, i, steps, evals
        else:
            return 0, t_stop, y, i, steps, evals


# ---- the leaf contract ------------------------------------------------------------------------
WILSON_INTEGRATORS = {"linacc": (1.0, MODE_NEWTON), "wilson": (None, MODE_NEWTON),
                      "linacc-pc": (1.0, MODE_PC), "linacc-fp": (1.0, MODE_FIXED_POINT)}
INTEGRATORS = tuple(WILSON_INTEGRATORS) + tuple(FIXED_TABLEAUS) + tuple(ADAPTIVE_TABLEAUS)
ADAPTIVE = tuple(ADAPTIVE_TABLEAUS)
COMMON_SETTINGS = {"theta": 1.4, "newton_tol": 1e-10, "max_iter": 30, "rtol": None,
                   "atol": None, "h_max": None, "max_steps": 10**8, "singular_tol": 0.02,
                   "energy_jump": 1e3, "event_tol": 1e-10}
REASONS = {**FAIL_REASONS, **LA_REASONS,
           FAIL_SINGULAR: "singular: the rod reached the vertical, where the loop-closure root "
                          "for x_B is double and the (phi, psi) chart's Jacobian is singular",
           FAIL_STENCIL: "singular: the finite-difference stencil of the partial systems "
                         "reaches past the double loop-closure root (rod near vertical)",
           FAIL_ENERGY: "unstable: the energy balance jumped"}


def merged_params(params, cycle):
    par = dict(DEFAULT_PARAMS)
    if cycle:
        par.update(CYCLE_DEFAULTS)
    par.update(params or {})
    return par


def _settings(defaults, settings):
    s = dict(COMMON_SETTINGS, **defaults)
    s.update({k: v for k, v in (settings or {}).items() if v is not None})
    if s["integrator"] not in INTEGRATORS:
        raise ValueError(f"unknown integrator {s['integrator']!r}; choose one of "
                         f"{', '.join(INTEGRATORS)}")
    if s["integrator"] == "wilson" and not float(s["theta"]) >= 1.0:
        raise ValueError(f"theta must be >= 1, got {s['theta']!r}")
    for k in ("dphi_deg", "dpsi_deg"):
        if k in s and not float(s[k]) > 0.0:
            raise ValueError(f"{k} must be > 0, got {s[k]!r}")
    return s


def initial_state(par, p):
    y0 = np.array([math.radians(par["phi0"]), math.radians(par["psi0"]), par["omega0"],
                   par["rocker_rate0"], 0.0, 0.0, 0.0])
    T, Vs, Vg, E = energy_terms(y0, p)
    p[E0], p[E_SCALE] = E, abs(T) + 1e-9
    return y0


def _steps_per_output(t_out, dt):
    dt_out = t_out[1] - t_out[0]
    if not dt or not dt > 0.0:
        raise ValueError(f"dt must be > 0, got {dt!r}")
    n = dt_out / dt
    return max(1, int(round(n)) if abs(n - round(n)) < 1e-6 * n else int(math.ceil(n)))


def _integrate_plain(solver, y0, p, t_out, s):
    """One idle run (scene `press`) with the shared drivers."""
    acc, f, guard = acc_any, f_any, guard_any
    name = s["integrator"]
    if name in ADAPTIVE_TABLEAUS:
        tb = ADAPTIVE_TABLEAUS[name]
        rtol = float(s["rtol"] or 1e-10)
        atol = float(s["atol"] or rtol * 1e-2)
        h_max = float(s["h_max"] or (t_out[1] - t_out[0]))
        Y, steps, evals, rej, t_fail, code = integrate_adaptive(
            f, guard, y0, p, t_out, rtol, atol, h_max, int(s["max_steps"]), tb["A"], tb["B"],
            tb["C"], tb["E"], tb["E3"], tb["err_order"])
        return Y, {"steps": int(steps), "rhs_evals": int(evals), "rejected": int(rej)}, \
            t_fail, code, {"rtol": rtol, "atol": atol, "h_max": h_max}
    n_sub = _steps_per_output(t_out, s["dt"])
    used = {"dt": float((t_out[1] - t_out[0]) / n_sub)}
    if name in FIXED_TABLEAUS:
        tb = FIXED_TABLEAUS[name]
        Y, steps, evals, t_fail, code = integrate_fixed(f, guard, y0, p, t_out, n_sub, tb["A"],
                                                        tb["B"], tb["C"])
    else:
        theta, mode = _wilson_args(s)
        Y, steps, evals, t_fail, code = integrate_wilson(
            acc, guard, y0, 2, p, t_out, n_sub, theta, mode, float(s["newton_tol"]),
            int(s["max_iter"]))
        used["theta"] = theta
    return Y, {"steps": int(steps), "rhs_evals": int(evals)}, t_fail, code, used


def _wilson_args(s):
    theta, mode = WILSON_INTEGRATORS[s["integrator"]]
    return (float(s["theta"]) if theta is None else theta), mode


def _integrate_cycle(solver, y0, p, par, t_out, s):
    """press-cycle: idle → lock at ψ = lock_angle (first crossing after lock_after, located by
    bisection) → locked crank–slider under the working load → release at release_after → idle.
    Returns Y, per-row mode, stats, t_fail, code, used settings, lock record."""
    acc, f, guard = acc_any, f_any, guard_any
    name = s["integrator"]
    if name in ADAPTIVE_TABLEAUS:
        raise ValueError(f"press-cycle runs fixed-step integrators only, got {name!r}")
    h = (t_out[1] - t_out[0]) / _steps_per_output(t_out, s["dt"])
    used = {"dt": float(h)}
    if name in FIXED_TABLEAUS:
        tb = FIXED_TABLEAUS[name]
        method, theta, mode = M_RK, 1.0, 0
        tA, tB, tC = tb["A"], tb["B"], tb["C"]
    else:
        theta, mode = _wilson_args(s)
        method, tA, tB, tC = M_WILSON, np.zeros((1, 1)), np.zeros(1), np.zeros(1)
        used["theta"] = theta
    t_end = float(t_out[-1])
    t_lock_after, t_release = float(par["lock_after"]), float(par["release_after"])
    psi_lock = math.radians(par["lock_angle"])
    Y = np.full((len(t_out), len(y0)), np.nan)
    Y[0] = y0
    modes = np.zeros(len(t_out))
    stats = {"steps": 0, "rhs_evals": 0}
    lock = {"t_lock": np.nan, "loss": 0.0, "rate_before": np.nan, "rate_after": np.nan}
    # phases: (mode, t_stop, event on)
    t, y, i = 0.0, y0.copy(), 1
    p[MODE] = 0.0
    plan = [(0.0, min(t_lock_after, t_end), False), (0.0, min(t_release, t_end), True)]
    while plan:
        md, t_stop, ev = plan.pop(0)
        p[MODE] = md
        if t_stop > t:
            code, t_new, y_new, i_new, st, evs = segment(
                f, acc, guard, method, y, p, t, t_stop, t_out, i, Y, h, tA, tB, tC, theta,
                mode, float(s["newton_tol"]), int(s["max_iter"]), ev, psi_lock,
                float(s["event_tol"]))
            modes[i:i_new] = md
            stats["steps"] += st
            stats["rhs_evals"] += evs
            t, y, i = t_new, y_new, i_new
            if code not in (0, EVENT):
                return Y, modes, stats, t, code, used, lock
            if code == EVENT:
                # plastic lock: ψ' → 0 keeping the crank's generalized momentum
                # p_φ = A11 φ' + A12 ψ'  (A of the solver's own description)
                A = (lagrange_partial(y[:2], p)[2] if p[SOLVER] != 0.0
                     else lagrange_exact(y[:2], p)[2])
                T_before = energy_terms(y, p)[0]
                lock["t_lock"], lock["rate_before"] = t, y[2]
                y = y.copy()
                y[2] = y[2] + A[0, 1] / A[0, 0] * y[3]
                y[3] = 0.0
                lock["rate_after"] = y[2]
                lock["loss"] = T_before - energy_terms(y, p)[0]
                p[E_LOST] = lock["loss"]
                plan = [(1.0, min(t_release, t_end), False), (0.0, t_end, False)]
                continue
        if ev and not plan:              # no lock before release: idle to the end
            plan = [(0.0, t_end, False)]
    return Y, modes, stats, None, 0, used, lock


def _channels(solver, Y, modes, p, t_out, e_lost_rows):
    acc = acc_any
    n = len(t_out)
    ch = {k: np.full(n, np.nan) for k in CHANNELS}
    mode0 = p[MODE]
    e_lost0 = p[E_LOST]
    for r in range(n):
        y = Y[r]
        if not np.all(np.isfinite(y)):
            continue
        p[MODE], p[E_LOST] = modes[r], e_lost_rows[r]
        xA, yA, xB, yB, xC, ok = positions(y[0], y[1], p)
        ch["crank_angle"][r], ch["crank_rate"][r], ch["rocker_angle"][r] = y[0], y[2], y[1]
        ch["crank_accel"][r] = acc(t_out[r], y[:2], y[2:4], p)[0]
        ch["slider_x"][r] = xC
        ch["loop_violation"][r] = abs(math.hypot(xB - xA, yB - yA) - p[L2])
        ch["energy_balance"][r] = energy_terms(y, p)[3]
    p[MODE], p[E_LOST] = mode0, e_lost0
    return ch


def _reason(code, t_fail, Y, p):
    reason = REASONS.get(int(code), f"failure code {code}")
    good = Y[np.all(np.isfinite(Y), axis=1)]
    if len(good):
        y = good[-1]
        s = rod_sine(y[0], y[1], p)
        tilt = math.degrees(math.acos(min(1.0, abs(s))))
        reason += f" (last output state: rod {tilt:.3g} deg from vertical"
        if code == FAIL_ENERGY:
            reason += f", energy balance {energy_terms(y, p)[3] - p[E0]:+.3g} J from start"
        reason += ")"
    return reason


def simulate(solver, defaults, params, t_out, settings):
    """The leaf contract for both solvers; `press-cycle` when params carry `lock_after`."""
    cycle = "lock_after" in (params or {})
    par = merged_params(params, cycle)
    s = _settings(defaults, settings)
    t_out = np.asarray(t_out, dtype=float)
    if t_out.ndim != 1 or len(t_out) < 2 or t_out[0] != 0.0 or np.any(np.diff(t_out) <= 0):
        raise ValueError("t_out must be an increasing grid starting at 0 with >= 2 points")
    p = pack(par, s.get("dphi_deg", 0.1), s.get("dpsi_deg", 0.1), float(s["singular_tol"]),
             float(s["energy_jump"]))
    p[SOLVER] = SOLVER_IDS[solver]
    y0 = initial_state(par, p)
    t0 = time.perf_counter()
    extra = {}
    code0 = guard_any(0.0, y0, p)
    if code0 in (FAIL_SINGULAR, FAIL_STENCIL):
        # the start itself sits at (or, for the finite differences, too near) the double root
        Y = np.full((len(t_out), len(y0)), np.nan)
        Y[0] = y0
        nan = np.full(len(t_out), np.nan)
        return {"channels": {k: nan.copy() for k in CHANNELS}, "status": "diverged",
                "t_fail": 0.0, "reason": _reason(code0, 0.0, Y, p) + " at the initial state",
                "stats": {"steps": 0, "rhs_evals": 0}, "settings": dict(s), "extra": {}}
    if cycle:
        Y, modes, stats, t_fail, code, used, lock = _integrate_cycle(solver, y0, p, par, t_out, s)
        lost = np.where(t_out >= lock["t_lock"], lock["loss"], 0.0)
        extra = {"t_lock": np.array([lock["t_lock"]]),
                 "lock_energy_loss": np.array([lock["loss"]]),
                 "crank_rate_at_lock": np.array([lock["rate_before"], lock["rate_after"]]),
                 "locked": modes.copy(), "press_work": Y[:, 6].copy()}
    else:
        Y, stats, t_fail, code, used = _integrate_plain(solver, y0, p, t_out, s)
        modes, lost = np.zeros(len(t_out)), np.zeros(len(t_out))
        t_fail = None if code == 0 else t_fail
    stats["integrate_s"] = time.perf_counter() - t0
    ch = _channels(solver, Y, modes, p, t_out, lost)
    extra.update({"motor_work": Y[:, 4].copy(), "damper_loss": Y[:, 5].copy()})
    used = dict(used, integrator=s["integrator"], singular_tol=float(s["singular_tol"]),
                energy_jump=float(s["energy_jump"]))
    if s["integrator"] in WILSON_INTEGRATORS:
        used.update(newton_tol=float(s["newton_tol"]), max_iter=int(s["max_iter"]))
    if solver == "partial":
        used.update(dphi_deg=float(s["dphi_deg"]), dpsi_deg=float(s["dpsi_deg"]))
    if cycle:
        used["event_tol"] = float(s["event_tol"])
    ok = code == 0
    return {"channels": ch, "status": "ok" if ok else "diverged",
            "t_fail": None if ok else float(t_fail),
            "reason": None if ok else _reason(code, t_fail, Y, p),
            "stats": stats, "settings": used, "extra": extra}


def linearised_modes(params, q=None, solver="exact", settings=None):
    """Eigen-analysis of the idle system about the initial state (or q): ω² = eig(A⁻¹K), K the
    Hessian of V = V_spring + V_gravity in (φ, ψ) by central differences of the generalized
    forces at rest. Returns (omega (rad/s), T = 2π/ω) sorted by ω descending."""
    par = merged_params(params, False)
    p = pack(par)
    q0 = np.radians([par["phi0"], par["psi0"]]) if q is None else np.asarray(q, float)
    p[U] = 0.0                                  # no motor torque: the conservative part only
    base, G, A, dA = lagrange_exact(q0, p)
    K = np.zeros((2, 2))
    for k, dq in enumerate(np.eye(2) * 1e-6):
        fp = acc_exact(0.0, q0 + dq, np.zeros(2), p)[:2]
        fm = acc_exact(0.0, q0 - dq, np.zeros(2), p)[:2]
        Ap = lagrange_exact(q0 + dq, p)[2]
        Am = lagrange_exact(q0 - dq, p)[2]
        K[:, k] = -(Ap @ fp - Am @ fm) / 2e-6     # K = −∂Q/∂q
    w2 = np.sort(np.linalg.eigvals(np.linalg.solve(A, K)).real)[::-1]
    w = np.sqrt(np.maximum(w2, 0.0))
    return w, np.where(w > 0, 2 * np.pi / np.where(w > 0, w, 1), np.inf)
