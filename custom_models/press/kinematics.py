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

from .model import DPHI, DPSI, L1, L2, L3, NB, SIGMA


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
def exact_kinematics(phi, psi, p):
    """Base coordinates, their gradients and Hessians, analytically, as tuples over the base
    coordinates XA … PSI (values, not arrays: nothing is allocated per call):
    (base, ∂/∂φ, ∂/∂ψ, ∂²/∂φ², ∂²/∂φ∂ψ, ∂²/∂ψ²).

    sin θ2 = s(φ, ψ), cos θ2 = c2 = σ√(1 − s²):  ∇θ2 = ∇s/c2,  ∇²θ2 = ∇²s/c2 + s ∇s∇sᵀ/c2³;
    x_B = x_A + l2 c2 with ∇c2 = −s ∇θ2 and ∇²c2 = −∇θ2∇sᵀ − s ∇²θ2."""
    l1, l2, l3 = p[L1], p[L2], p[L3]
    cf, sf, cp, sp = math.cos(phi), math.sin(phi), math.cos(psi), math.sin(psi)
    s = (l3 * sp - l1 * sf) / l2
    c2 = p[SIGMA] * math.sqrt(max(0.0, 1.0 - s * s))
    gs0, gs1 = -l1 * cf / l2, l3 * cp / l2
    hs00, hs11 = l1 * sf / l2, -l3 * sp / l2
    gt0, gt1 = gs0 / c2, gs1 / c2
    c3 = c2 * c2 * c2
    ht00 = hs00 / c2 + s * gs0 * gs0 / c3
    ht01 = s * gs0 * gs1 / c3
    ht11 = hs11 / c2 + s * gs1 * gs1 / c3
    xA, yA = l1 * cf, l1 * sf
    xB = xA + l2 * c2                                  # x_B = x_A + l2 c2
    gB0, gB1 = -l1 * sf - l2 * s * gt0, -l2 * s * gt1
    hB00 = -l1 * cf + l2 * (-gt0 * gs0 - s * ht00)
    hB01 = l2 * (-gt0 * gs1 - s * ht01)
    hB11 = l2 * (-gt1 * gs1 - s * ht11)
    base = (xA, yA, xB, l3 * sp, xB - l3 * cp, phi, math.atan2(s, c2), psi)
    g0 = (-l1 * sf, l1 * cf, gB0, 0.0, gB0, 1.0, gt0, 0.0)
    g1 = (0.0, 0.0, gB1, l3 * cp, gB1 + l3 * sp, 0.0, gt1, 1.0)
    h00 = (-l1 * cf, -l1 * sf, hB00, 0.0, hB00, 0.0, ht00, 0.0)
    h01 = (0.0, 0.0, hB01, 0.0, hB01, 0.0, ht01, 0.0)
    h11 = (0.0, 0.0, hB11, -l3 * sp, hB11 + l3 * cp, 0.0, ht11, 0.0)
    return base, g0, g1, h00, h01, h11


@nb.njit(cache=True)
def exact_derivatives(phi, psi, p):
    """`exact_kinematics` as arrays: base (8,), gradients G (8, 2), Hessians H (8, 2, 2)."""
    base, g0, g1, h00, h01, h11 = exact_kinematics(phi, psi, p)
    b = np.empty(NB)
    G = np.empty((NB, 2))
    H = np.empty((NB, 2, 2))
    for k in range(NB):
        b[k], G[k, 0], G[k, 1] = base[k], g0[k], g1[k]
        H[k, 0, 0], H[k, 0, 1], H[k, 1, 0], H[k, 1, 1] = h00[k], h01[k], h01[k], h11[k]
    return b, G, H


# ---- the paper's "partial systems": velocity analogues by central differences --------------
# Stencil of the nested differences (offsets in units of Δφ, Δψ): A_ij needs r at (±1, 0),
# (0, ±1) around its point; A_ij,k needs A at (±1, 0), (0, ±1): 13 distinct points in all.
STENCIL = np.array([[0, 0], [1, 0], [-1, 0], [0, 1], [0, -1], [2, 0], [-2, 0], [0, 2], [0, -2],
                    [1, 1], [1, -1], [-1, 1], [-1, -1]], dtype=np.int64)
# for A at centre, (+1,0), (−1,0), (0,+1), (0,−1): indices into STENCIL of (centre, +φ, −φ, +ψ, −ψ)
NEIGH = np.array([[0, 1, 2, 3, 4], [1, 5, 0, 9, 10], [2, 0, 6, 11, 12], [3, 9, 11, 7, 0],
                  [4, 10, 12, 0, 8]], dtype=np.int64)


# Explicit signatures: called with the constants 0 … 12, numba compiled one Literal[int] copy
# per stencil point (13 of `_point`, 5 of `fd_gradients`, ~9 s on a fresh clone)
_POINT = nb.types.Tuple((nb.types.UniTuple(nb.float64, 5), nb.boolean))
_ANALOGUES = nb.types.UniTuple(nb.float64, 8)


@nb.njit(_POINT(nb.float64, nb.float64, nb.int64, nb.float64[::1]), cache=True)
def _point(phi, psi, k, p):
    """(x_A, y_A, x_B, y_B, x_C) at stencil point k, and whether the loop closes there."""
    xA, yA, xB, yB, xC, ok = positions(phi + STENCIL[k, 0] * p[DPHI],
                                       psi + STENCIL[k, 1] * p[DPSI], p)
    return (xA, yA, xB, yB, xC), ok


@nb.njit(cache=True)
def stencil_positions(phi, psi, p):
    """`_point` at the 13 stencil points (a tuple: nothing allocated); ok False if any is
    unreal."""
    P = (_point(phi, psi, 0, p), _point(phi, psi, 1, p), _point(phi, psi, 2, p),
         _point(phi, psi, 3, p), _point(phi, psi, 4, p), _point(phi, psi, 5, p),
         _point(phi, psi, 6, p), _point(phi, psi, 7, p), _point(phi, psi, 8, p),
         _point(phi, psi, 9, p), _point(phi, psi, 10, p), _point(phi, psi, 11, p),
         _point(phi, psi, 12, p))
    ok = True
    for k in range(13):
        ok = ok and P[k][1]
    return P, ok


@nb.njit(cache=True)
def _link_analogues(v, c):
    """(θ2, ψ) analogues of one partial system from the cross-product formula
    ω* = (AB × v*_BA)/|AB|² (eqs. 9, 14–15); v = the joints' analogues, c = the joints."""
    dx, dy = c[2] - c[0], c[3] - c[1]                  # AB
    ex, ey = c[4] - c[2], -c[3]                        # BC (y_C = 0)
    vx, vy = v[2] - v[0], v[3] - v[1]                  # v*_BA
    wx, wy = v[4] - v[2], -v[3]                        # v*_CB
    return (dx * vy - dy * vx) / (dx * dx + dy * dy), (ex * wy - ey * wx) / (ex * ex + ey * ey)


@nb.njit(nb.types.Tuple((_ANALOGUES, _ANALOGUES))(nb.types.UniTuple(_POINT, 13), nb.int64,
                                                  nb.float64[::1]), cache=True)
def fd_gradients(P, n, p):
    """Velocity analogues (∂r/∂φ, ∂r/∂ψ) at neighbourhood n (NEIGH[n]) of the stencil P: the
    partial systems PS1 (ψ frozen) and PS2 (φ frozen) by central differences (eqs. 6–8,
    12–13), the links' angular analogues by `_link_analogues`, the crank's exactly e_z. Two
    tuples over the base coordinates XA … PSI."""
    c, fp, fm = P[NEIGH[n, 0]][0], P[NEIGH[n, 1]][0], P[NEIGH[n, 2]][0]
    sp, sm = P[NEIGH[n, 3]][0], P[NEIGH[n, 4]][0]
    i0, i1 = 0.5 / p[DPHI], 0.5 / p[DPSI]
    a = ((fp[0] - fm[0]) * i0, (fp[1] - fm[1]) * i0, (fp[2] - fm[2]) * i0,
         (fp[3] - fm[3]) * i0, (fp[4] - fm[4]) * i0)
    b = ((sp[0] - sm[0]) * i1, (sp[1] - sm[1]) * i1, (sp[2] - sm[2]) * i1,
         (sp[3] - sm[3]) * i1, (sp[4] - sm[4]) * i1)
    ta, pa = _link_analogues(a, c)
    tb, pb = _link_analogues(b, c)
    return (a[0], a[1], a[2], a[3], a[4], 1.0, ta, pa), (b[0], b[1], b[2], b[3], b[4], 0.0, tb, pb)
