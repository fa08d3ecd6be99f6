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
stay constant; the guard stops a run whose balance jumps (the linear-acceleration instability).
"""
import math

import numba as nb
import numpy as np

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
# press-cycle defaults (see custom_models/press_cycle notes in the module docstring of
# press_partial): lock on the rocker's first downward pass through −60° after 4 ms, release at
# 30 ms, 2 kN working load, 60 ms run.
CYCLE_DEFAULTS = {"lock_after": 0.004, "lock_angle": -60.0, "press_force": 2000.0,
                  "press_force_vreg": 0.01, "release_after": 0.03, "t_end": 0.06}

# base coordinates (columns of the gradient table G)
XA, YA, XB, YB, XC, PHI, TH2, PSI = range(8)
NB = 8

# ---- packed parameter array p -------------------------------------------------------------
(L1, L2, L3, SIGMA, GRAV, K_S, C_S, XC0, U, MK, SK, WSYNC, DPHI, DPSI, MODE, PRESS, VREG,
 SING_TOL, E0, E_JUMP, E_LOST, E_SCALE, N_ITEMS) = range(23)
HV = 23                       # 8 gravity "height" coefficients: V_g = g Σ HV_b · base_b
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


def pack(par, dphi_deg=0.1, dpsi_deg=0.1, singular_tol=0.02, energy_jump=0.1):
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


@nb.njit(cache=True)
def f_exact(t, y, p):
    r = acc_exact(t, y[:2], y[2:4], p)
    dy = np.empty(y.shape[0])
    dy[:2] = y[2:4]
    dy[2:] = r
    return dy


@nb.njit(cache=True)
def f_partial(t, y, p):
    r = acc_partial(t, y[:2], y[2:4], p)
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
def guard_exact(t, y, p):
    return _guard_common(y, p, 0.0)


@nb.njit(cache=True)
def guard_partial(t, y, p):
    # the nested stencil reaches 2Δφ, 2Δψ: bound its change of s = sin θ2
    reach = 2.0 * (p[L1] * p[DPHI] + p[L3] * p[DPSI]) / p[L2]
    return _guard_common(y, p, reach)
