"""Time integrators shared by every custom model: one place, one file per family.

- `explicit`: the Runge–Kutta coefficient tables, failure codes, guard type, error norm.
- `dense`: the drivers, with dense output (DOP853's 7th-order extension, Dopri5/RK23
  interpolants, cubic Hermite for fixed steps): the step is set by the tolerance or `dt` alone;
  the right-hand side writes into a given array, `f(t, y, p, dy)`.
- `lanes`: DOP853 with dense output over 8 points at once on the SIMD lanes (a map's batch),
  each lane bit for bit `dense`'s driver.
- `linear_acceleration`: the linear-acceleration (Wilson-θ) method for M(q) q'' = Q(q, q', t).
- `implicit`: building blocks for stiff systems (O(n) block-tridiagonal Newton solves for
  spring–mass chains, bordered by one extra unknown).
"""
from .explicit import ADAPTIVE_TABLEAUS, FAIL_REASONS, FIXED_TABLEAUS, no_guard
from .implicit import block3_tridiag_factor, block3_tridiag_solve, bordered_block3_solve, inv3

# imported on first use: its driver has a fixed signature, so importing the module compiles it
# or loads it from numba's cache (0.3 s warm, ~13 s cold) — and only the press uses it, while
# every custom model's process imports this package
_LINEAR_ACCELERATION = ("LA_REASONS", "MODE_FIXED_POINT", "MODE_NEWTON", "MODE_PC",
                        "accel_from_mass_force", "as_first_order", "integrate_wilson",
                        "wilson_step")


def __getattr__(name):
    if name in _LINEAR_ACCELERATION:
        from . import linear_acceleration
        return getattr(linear_acceleration, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["FIXED_TABLEAUS", "ADAPTIVE_TABLEAUS", "FAIL_REASONS", "no_guard",
           *_LINEAR_ACCELERATION,
           "block3_tridiag_factor", "block3_tridiag_solve", "bordered_block3_solve", "inv3"]
