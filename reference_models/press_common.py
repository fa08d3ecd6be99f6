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
