"""`lagrange-partial` for scene `bricard`: the press paper's method (Lagrange's equations in
minimal coordinates with velocity analogues from "partial systems" by central differences,
linear-acceleration integration) on Bricard's mechanism, one coordinate θ1 = q0 (model.py).

Settings: integrator (linacc, wilson [theta], linacc-pc, linacc-fp), dt, dtheta (the virtual
step of the partial systems, rad), newton_tol (the implicit step, relative to the
accelerations), closure_tol (the loop closure's Gauss–Newton, rad), max_iter.
"""
import time

import numpy as np

from compare.contract import LeafResult, merge_settings, require_positive
from compare.physics import bricard as phys

from ..integrators import FAIL_REASONS, LA_REASONS, integrate_wilson
from ..integrators.dense import first_class
from ..integrators.explicit import GUARD
from ..integrators.linear_acceleration import ACC, LA_INTEGRATORS, la_args, steps_per_output
from . import model

CHANNELS = phys.CHANNELS
INTEGRATORS = tuple(LA_INTEGRATORS)
DEFAULT_SETTINGS = {"integrator": "linacc", "dt": 1e-3, "theta": 1.4, "dtheta": 1e-4,
                    "newton_tol": 1e-10, "closure_tol": 1e-14, "max_iter": 30}
# the virtual step's central differences: an O(Δθ²) error the time step's halving cannot see
KNOBS = {"dtheta": 2}
REASONS = {**FAIL_REASONS, **LA_REASONS,
           model.FAIL_CLOSURE: "singular: the loop closure's Gauss–Newton iteration found no "
                               "assembly near the last one (dependent-angle Jacobian singular)"}


def check_settings(settings: dict | None, t_out: np.ndarray | None = None) -> dict:
    """The settings merged and checked before anything runs (ValueError with one line)."""
    s = merge_settings(settings, DEFAULT_SETTINGS, INTEGRATORS)
    require_positive(s, ("dt", "dtheta", "newton_tol", "closure_tol", "max_iter"))
    if s["integrator"] == "wilson" and not float(s["theta"]) >= 1.0:
        raise ValueError(f"theta must be >= 1, got {s['theta']!r}")
    return s


def simulate(params: dict, t_out: np.ndarray, settings: dict | None = None) -> LeafResult:
    s = check_settings(settings)
    t_out = np.asarray(t_out, float)
    p = model.pack(params, float(s["dtheta"]), float(s["closure_tol"]))
    y0 = np.zeros(2)                     # the library's start: all joint angles 0, at rest
    n_sub = steps_per_output(t_out, float(s["dt"]))
    theta, mode = la_args(s)
    t0 = time.perf_counter()
    Y, steps, evals, t_fail, code = integrate_wilson(
        first_class(model.acc, ACC), first_class(model.guard, GUARD), y0, 1, p, t_out, n_sub,
        theta, mode, float(s["newton_tol"]), int(s["max_iter"]))
    wall = time.perf_counter() - t0
    p[model.WARM:model.WARM + 5] = 0.0
    Q, QD = model.full_state(Y, p)
    ch = phys.channels(Q, QD, p[:model.NP])
    ok = code == 0
    used = {"integrator": s["integrator"], "dt": float((t_out[1] - t_out[0]) / n_sub),
            "theta": theta, "dtheta": float(s["dtheta"]), "newton_tol": float(s["newton_tol"]),
            "closure_tol": float(s["closure_tol"]), "max_iter": int(s["max_iter"])}
    return LeafResult(channels=ch, status="ok" if ok else "diverged",
                      t_fail=None if ok else float(t_fail),
                      reason=None if ok else REASONS.get(int(code), f"failure code {code}"),
                      stats={"steps": int(steps), "rhs_evals": int(evals), "integrate_s": wall},
                      settings=used, extra={"theta1_rate": Y[:, 1].copy()})
