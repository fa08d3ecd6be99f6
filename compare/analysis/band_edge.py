"""A critical speed at the edge of an instability band, located as such.

Inside a divergence band (an anisotropic shaft between its two bending frequencies) a mode's
own-frame frequency is 0: its roots are real, no solver lists it, and its label passes to the
next mode. A line that meets its excitation at the band's edge therefore jumps there: root
finding on the gap converges to the jump, and the gap's frequency errors say nothing of where
a solver puts it. The engines' chains put it where their N-segment chain's mode reappears
(6e-4 past λ₁²√(EI_yy/EI_xx) at Ω* = 4.199, `xval calibrate spinning-shaft --seed 7373` set
1, with bars of 1.8e-6: 3 of 6 pairs disagreed); fem's bar there was that of a mode its
coarser mesh lacked. And a jump between two modes, neither of which meets the line (the
forward whirl 1 against the 2× line at a band's edge, seed 11 set 1), is no crossing at all.

What is smooth through the edge is the gap squared, linear in the distance (two roots meet
at 0 and turn real). So the edge is found from gap² at points on the side where the mode
exists, 1–4 % of the sweep step away, where each solver's frequency error holds: the root of
a cubic through four points; its error: those errors carried onto the root through the
cubic's weights, plus the change from the parabola through the first three (at that edge
1.2e-8 for the cubic's 2e-9).
"""
from __future__ import annotations

import numpy as np

PROBE = 1e-7        # a side's gap is read this far (× the step) from the jump
JUMP = 1e-2         # a gap above this × the step's gaps beside the root: it jumped there (a
#                     root where the gap crosses 0 leaves both sides at ~PROBE × them)
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
    """What the root `v` of a gap in the step [lo, hi] is: None where the gap crosses 0 there
    (a crossing, also where the solver lists the mode on neither side: mstmm within 1e-7 of
    a forward whirl's rotating-frame zero); the band edge (edge, error, linearisation
    error) where it jumps and gap² on the side where it is smaller reaches 0 within the fit's
    points, as a simple root (a crossing's is double) — the errors None where the solver gives
    none; else why it is no crossing (str: the line jumps between two modes, neither of which
    meets the excitation). `sample(x)` gives (gap, its error or None, its linearisation error
    or None) at x and raises ValueError where the solver lists no such mode; the last point
    it is given lies beside the edge, on the mode's side."""
    h = hi - lo
    big = max(abs(g) for g in gaps_at_ends)
    side_gap = {}
    for side in (-1, 1):
        try:
            side_gap[side] = abs(sample(v + side * PROBE * h)[0])
        except (ValueError, IndexError):
            side_gap[side] = np.inf
    side = min(side_gap, key=side_gap.get)
    if side_gap[-side] <= JUMP * big or side_gap[side] == np.inf:
        return None
    room = (hi - v) if side > 0 else (v - lo)
    t = np.array(NODES) * min(h, room / NODES[-1])
    try:
        got = [sample(v + side * tk) for tk in t]
        g = np.array([x[0] for x in got])
        y = g ** 2
        r3, r2 = _root_near_zero(t, y), _root_near_zero(t[:3], y[:3])
        slope = abs(np.polyval(np.polyder(np.polyfit(t, y, 3)), r3))
        edge = abs(r3) <= t[-1] and slope * t[-1] >= 0.5 * y[-1]
    except (ValueError, IndexError):
        edge = False
    if not edge:
        if side_gap[side] <= JUMP * big:     # a crossing, the other side's mode missing
            return None
        return (f"the gap jumps at {v:.8g} from {side_gap[side]:.3g} to {side_gap[-side]:.3g} "
                f"(another mode, or none): no crossing, and no band edge within "
                f"{t[-1]:.3g} of it")
    w = np.abs(_lagrange_weights(t, r3))

    def carried(k):             # a frequency error δf is 2|g|δf on gap²
        e = [x[k] for x in got]
        if any(x is None for x in e) or slope == 0:
            return None
        return float(np.sum(w * 2 * np.abs(g) * np.array(e)) / slope)
    err, lin = carried(1), carried(2)
    return v + side * r3, None if err is None else err + abs(r3 - r2), lin
