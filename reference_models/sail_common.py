"""What the engine leaves of `sail-deploy` share beyond the scene physics (which lives in
compare/physics/sail.py: thread, payout, release law, breakpoints, formula 18, channels): the
output-grid check and the explicit engines' stable step.

The engines model ONE blade in the inertial frame with half the hub inertia (two symmetric
blades: J Ω' = 2 M_blade  <=>  (J/2) Ω' = M_blade) and report both blades' totals; the boundary
node's Q-spring has the growing rest length l0(t) = r ω (t − t_b) and a damper on the true
stretch rate d/dt|x_b − Q| − r ω: the "conservative" variant of the custom `thread-spool`.
Imports numpy only.
"""
from __future__ import annotations

import numpy as np

from compare.physics.sail import thread


def check_grid(t_out) -> np.ndarray:
    t_out = np.asarray(t_out, float)
    if np.any(np.diff(t_out) <= 0):
        raise ValueError("t_out must be strictly increasing")
    return t_out


def stable_dt_explicit(params: dict, factor: float = 2.0, safety: float = 0.8) -> float:
    """Stable step of an explicit scheme (stability interval `factor` on the imaginary axis:
    2 for symplectic Euler, 2.785 for RK4) from the highest chain frequency 2 sqrt(c/m_min)."""
    m = thread(params)[2]
    lam = 2.0 * np.sqrt(params["stiffness"] / m.min()) + 4.0 * params["damping"] / m.min()
    return safety * factor / lam
