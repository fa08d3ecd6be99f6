"""A critical speed at the edge of an instability band, located as such.

Inside a divergence band (an anisotropic shaft between its two bending frequencies) a mode's
own-frame frequency is 0: its roots are real, no solver lists it, and its label passes to the
next mode. A line that meets its excitation at the band's edge therefore jumps there: root
finding on the gap converges to the jump, and the gap's frequency errors say nothing of where
a solver puts it — a chain of N segments puts it at its own edge (the engines' N = 40 chain
6e-4 past λ₁²√(EI_yy/EI_xx) at Ω* = 4.199, while their extrapolated frequencies beside it are
good to 4e-4 Hz).

What is smooth through the edge is the gap squared, linear in the distance (two roots meet
at 0 and turn real). So the edge is found from gap² at points on the side
where the mode exists, away from the edge by 1–3 % of the sweep step, where each solver's
frequency error holds: the root of a cubic through four points; its error: those errors
carried onto the root through the cubic's weights, plus the change from the parabola through
the first three (at the shaft's edge 1.2e-8 for the cubic's 2e-9).
"""
from __future__ import annotations

import numpy as np

PROBE = 1e-7        # a side's gap is read this far (× the step) from the jump
SMALL = 1e-2        # at the edge, the gap on the mode's side is below this × the step's gaps,
#                     the other side's (another mode's, or none) above it; a root beside the
#                     jump leaves both sides at ~PROBE × the step's gaps
NODES = (0.01, 0.02, 0.03, 0.04)    # the fit's points, × the step, on the mode's side:
#   past the engines' N/4 chain's own edge (2e-3 past the true one at Ω* = 4.2)


def _lagrange_weights(nodes: np.ndarray, x: float) -> np.ndarray:
    """w with p(x) = Σ w_k y_k for the polynomial p through (nodes, y)."""
    return np.array([np.prod([(x - b) / (a - b) for b in nodes if b != a]) for a in nodes])


def _root_near_zero(t: np.ndarray, y: np.ndarray) -> float:
    roots = np.roots(np.polyfit(t, y, len(t) - 1))
    real = roots[np.abs(roots.imag) <= 1e-9 * np.max(np.abs(t))].real
    if not len(real):
        raise ValueError("no real root")
    return float(real[np.argmin(np.abs(real))])


def locate(sample, v: float, lo: float, hi: float, gaps_at_ends: tuple[float, float]):
    """The band edge at the jump `v` of a gap in the step [lo, hi], or None where `v` is no
    edge (the gap crosses 0 there, or jumps between two modes neither of which meets the
    line). `sample(x)` gives (gap, its error or None, its linearisation error or None) at x
    and raises ValueError where the solver lists no such mode. Returns (edge, error,
    linearisation error, side) — side ±1, where the mode exists; the errors None where the
    solver gives none."""
    h = hi - lo
    big = max(abs(g) for g in gaps_at_ends)
    side_gap = {}
    for side in (-1, 1):
        try:
            side_gap[side] = abs(sample(v + side * PROBE * h)[0])
        except (ValueError, IndexError):
            side_gap[side] = np.inf
    side = min(side_gap, key=side_gap.get)
    if not side_gap[side] <= SMALL * big < side_gap[-side]:
        return None
    room = (hi - v) if side > 0 else (v - lo)
    t = np.array(NODES) * min(h, room / NODES[-1])
    got = [sample(v + side * tk) for tk in t]
    g = np.array([x[0] for x in got])
    y = g ** 2
    r3, r2 = _root_near_zero(t, y), _root_near_zero(t[:3], y[:3])
    slope = abs(np.polyval(np.polyder(np.polyfit(t, y, 3)), r3))
    w = np.abs(_lagrange_weights(t, r3))

    def carried(k):             # a frequency error δf is 2|g|δf on gap²
        e = [x[k] for x in got]
        if any(x is None for x in e) or slope == 0:
            return None
        return float(np.sum(w * 2 * np.abs(g) * np.array(e)) / slope)
    err, lin = carried(1), carried(2)
    return v + side * r3, None if err is None else err + abs(r3 - r2), lin, side
