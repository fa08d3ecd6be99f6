"""Kinematics of the custom press model over the chart q = (φ, ψ): crank and rocker angle.

    A = l1 (cos φ, sin φ),   y_B = l3 sin ψ,   |B − A| = l2,   x_C = x_B − l3 cos ψ,  y_C = 0,
solved in closed form by the shared loop closure (compare.physics.press.loop_closure):
    x_B = x_A + σ √(l2² − (y_B − y_A)²),   σ = +1 for assembly 1 (x_B > x_A), −1 for assembly 2.
Written with the rod angle θ2: sin θ2 = s = (l3 sin ψ − l1 sin φ)/l2 and cos θ2 = σ√(1 − s²).
The chart breaks down where the root is double, cos θ2 = 0 (rod vertical): there ∂x_B/∂ψ → ∞.

Two ways to the gradients ∇c of the base coordinates (and their Hessians): analytic
(`exact_derivatives`, solver lagrange-exact) or the paper's "partial systems" by central
differences over a stencil of virtual steps (`fd_gradients`, solver lagrange-partial).
"""
import math

import numba as nb
import numpy as np

from compare.physics.press import loop_closure

from .press_model import DPHI, DPSI, L1, L2, L3, NB, PHI, PSI, SIGMA, TH2, XA, XB, XC, YA, YB


# ---- exact kinematics ---------------------------------------------------------------------
@nb.njit(cache=True)
def positions(phi, psi, p):
    """Joint positions from the shared loop closure; ok = False where no real root exists."""
    return loop_closure(phi, psi, p[L1], p[L2], p[L3], p[SIGMA])


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
