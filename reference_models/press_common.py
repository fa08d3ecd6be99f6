"""The start every engine leaf of `press` / `press-cycle` shares: settings merged the one way
(compare.contract.merge_settings) with a checked fixed step, the checked output grid and the
consistent initial assembly. The scene physics itself (motor, load, link layout, loop
closure, breakpoints, channels) lives in compare/physics/press.py. Imports numpy only.
"""
from __future__ import annotations

import numpy as np

from compare.contract import merge_settings
from compare.physics import press as phys


def fixed_step_settings(settings: dict | None, defaults: dict, integrators: tuple) -> dict:
    """The one settings merge plus a positive fixed step (ValueError with one line)."""
    s = merge_settings(settings, defaults, integrators)
    s["dt"] = float(s["dt"])
    if not s["dt"] > 0:
        raise ValueError(f"dt must be > 0, got {s['dt']!r}")
    return s


def prepare(params: dict, t_out, s: dict) -> tuple:
    """Returns (cycle, t_out, initial state) for an engine run with checked settings s."""
    t_out = np.asarray(t_out, dtype=float)
    if t_out.ndim != 1 or len(t_out) < 1 or t_out[0] != 0.0 or np.any(np.diff(t_out) <= 0):
        raise ValueError("t_out must be increasing and start at 0")
    return phys.is_cycle(params), t_out, phys.initial_state(params)


BISECT_TOL = 1e-9   # s, width of the final lock-time bracket


def bisect_event(advance, g0: float, h: float, tol: float = BISECT_TOL) -> tuple:
    """Locate a sign change of the event function over one step [0, h] of an engine by
    bisection on the step length: advance(dt) restores the step's start state, steps by dt and
    returns (g, payload). Returns (hi, number of re-steps, payload of the last step to hi or
    None): the event lies in (hi − tol, hi], on the far side of the crossing."""
    lo, hi = 0.0, h
    n = 0
    last = None
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        g, payload = advance(mid)
        n += 1
        if g != 0.0 and np.sign(g) == np.sign(g0):
            lo = mid
        else:
            hi, last = mid, payload
    return hi, n, last
