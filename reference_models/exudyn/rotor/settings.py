"""The leaf's integrators and settings, checked before anything runs."""
import math

import exudyn as exu

from compare.contract import check_once, merge_settings

SOLVERS = {
    "rk4": exu.DynamicSolverType.RK44,
    "rk67": exu.DynamicSolverType.RK67,
    "dopri5": exu.DynamicSolverType.DOPRI5,
    "rk23": exu.DynamicSolverType.ODE23,
    "explicit_euler": exu.DynamicSolverType.ExplicitEuler,
    "generalized_alpha": exu.DynamicSolverType.GeneralizedAlpha,
}
INTEGRATORS = tuple(SOLVERS)
ADAPTIVE = ("dopri5", "rk23")             # integrators that take rtol

# Accurate default (measured, see tests and the module report): RK67 fixed step 2 ms gives an
# energy-balance drift of ~2e-6 J over the 10 s default run and |ω| converged to ~1e-8 rad/s.
DEFAULT_SETTINGS = {"integrator": "rk67", "dt": 2e-3, "rtol": 1e-10, "spectral_radius": 1.0}
# a map point's first look (compare/leafinfo.py `cheaper`): 5× the accurate step, the output
# step; |λ dt| ≤ 0.6 on the rotor map (tilt ~41 rad/s, spin ≤ 56 rad/s), well inside RK67's
# stability region. Measured (`xval bench rotor-spinup --points 200 --solver exudyn`): 0 of
# 200 labels differ from the all-accurate grid, 19.5 % rerun accurate, 4.4 → 9.9 points/s
CHEAP_DT = {"rk67": 1e-2}


@check_once
def check_settings(settings, t_out=None):
    """Settings merged and checked before anything runs."""
    s = merge_settings(settings, DEFAULT_SETTINGS, INTEGRATORS)
    name = s["integrator"]
    if name in ADAPTIVE:
        try:
            rtol = float(s["rtol"])
        except (TypeError, ValueError):
            raise ValueError(f"rtol must be in (0, 1), got {s['rtol']!r}") from None
        if not (math.isfinite(rtol) and 0 < rtol < 1):
            raise ValueError(f"rtol must be in (0, 1), got {s['rtol']!r}")
    else:
        try:
            dt = float(s["dt"])
        except (TypeError, ValueError):
            raise ValueError(f"dt must be a positive number, got {s['dt']!r}") from None
        if not (math.isfinite(dt) and dt > 0):
            raise ValueError(f"dt must be a positive number, got {s['dt']!r}")
        if t_out is not None and len(t_out) > 1 and dt > (t_out[-1] - t_out[0]) * (1 + 1e-9):
            raise ValueError(f"dt ({dt:g}) must not exceed the horizon "
                             f"({t_out[-1] - t_out[0]:g} s)")
    return s
