"""The leaf's integrators and settings, checked before anything runs."""
import math

import mujoco

from compare.contract import check_once, merge_settings

DEFAULT_SETTINGS = {
    "integrator": "rk4",
    "dt": 1e-3,
    "spring": "cone",       # "cone" (the scene's −kγ) | "cardan" (named model variant)
    "callback": "native",   # "native" (numba cfunc, no GIL) | "python" (Python callable)
    "omega_max": 1e5,       # |ω| bound [rad/s]: beyond it the run is reported diverged
}
INTEGRATORS = ("rk4", "euler", "implicitfast", "implicit")
# a map point's first look (compare/leafinfo.py `cheaper`): 10× the accurate step, the output
# step. RK4 is stable to |λ dt| ≤ 2.78; on the rotor map the tilt root is ~41 rad/s and the
# spin at most 56 rad/s (torque 5, e 0.02, 10 s): |λ dt| ≤ 0.6. Measured (`xval bench
# rotor-spinup --points 400 --solver mujoco`): 0 of 400 labels differ from the all-accurate
# grid, 16 % rerun accurate; 5e-2 gives wrong cheap labels (tests/studies/test_map_trace.py fails)
CHEAP_DT = {"rk4": 1e-2}
SPRINGS = ("cone", "cardan")
CALLBACKS = ("native", "python")

INTEGRATOR_ENUM = {
    "rk4": mujoco.mjtIntegrator.mjINT_RK4,
    "euler": mujoco.mjtIntegrator.mjINT_EULER,
    "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST,
    "implicit": mujoco.mjtIntegrator.mjINT_IMPLICIT,
}
RHS_PER_STEP = {"rk4": 4, "euler": 1, "implicitfast": 1, "implicit": 1}


@check_once
def check_settings(settings, t_out=None):
    """Settings merged and checked before anything runs."""
    s = merge_settings(settings, DEFAULT_SETTINGS, INTEGRATORS)
    if not (isinstance(s["dt"], (int, float)) and math.isfinite(s["dt"]) and s["dt"] > 0):
        raise ValueError(f"dt must be a positive number, got {s['dt']!r}")
    if s["spring"] not in SPRINGS:
        raise ValueError(f"spring must be one of {SPRINGS}, got {s['spring']!r}")
    if s["callback"] not in CALLBACKS:
        raise ValueError(f"callback must be one of {CALLBACKS}, got {s['callback']!r}")
    if not (float(s["omega_max"]) > 0):
        raise ValueError(f"omega_max must be positive, got {s['omega_max']!r}")
    s["dt"] = float(s["dt"])
    return s
