"""Time integrators shared by every custom model: one place, one file per family.

- `explicit`: fixed-step and adaptive embedded Runge–Kutta methods as coefficient tables
  (numba-compiled drivers; the right-hand side is a jitted `f(t, y, p)`).
- `linear_acceleration`: the linear-acceleration (Wilson-θ) method for M(q) q'' = Q(q, q', t).
- `implicit`: methods for stiff systems.
"""
from .explicit import (FIXED_TABLEAUS, ADAPTIVE_TABLEAUS, FAIL_REASONS, integrate_fixed,
                       integrate_adaptive, no_guard)
from .linear_acceleration import (integrate_wilson, wilson_step, accel_from_mass_force,
                                  as_first_order, LA_REASONS, MODE_NEWTON, MODE_FIXED_POINT,
                                  MODE_PC)

__all__ = ["FIXED_TABLEAUS", "ADAPTIVE_TABLEAUS", "FAIL_REASONS", "integrate_fixed",
           "integrate_adaptive", "no_guard",
           "integrate_wilson", "wilson_step", "accel_from_mass_force", "as_first_order",
           "LA_REASONS", "MODE_NEWTON", "MODE_FIXED_POINT", "MODE_PC"]
