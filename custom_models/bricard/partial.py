"""`lagrange-partial` for scene `bricard`: the press paper's method (Lagrange's equations in
minimal coordinates with velocity analogues from "partial systems" by central differences,
linear-acceleration integration) on Bricard's mechanism, one coordinate θ1 = q0 (model.py).

Settings: integrator (linacc, wilson [theta], linacc-pc, linacc-fp), dt, dtheta (the virtual
step of the partial systems, rad), newton_tol (the implicit step, relative to the
accelerations), closure_tol (the loop closure's Gauss–Newton, rad), max_iter.
"""
import numpy as np

from compare.contract import LeafResult, check_once
from compare.physics import bricard as phys

from .. import loops
from ..integrators import FAIL_REASONS, LA_REASONS
from ..integrators.linear_acceleration import LA_INTEGRATORS
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


@check_once
def check_settings(settings: dict | None, t_out: np.ndarray | None = None) -> dict:
    """The settings merged and checked before anything runs (ValueError with one line)."""
    return loops.partial_settings(settings, DEFAULT_SETTINGS, INTEGRATORS, "dtheta")


def simulate(params: dict, t_out: np.ndarray, settings: dict | None = None) -> LeafResult:
    s = check_settings(settings)
    t_out = np.asarray(t_out, float)
    p = model.pack(params, float(s["dtheta"]), float(s["closure_tol"]))
    y0 = np.zeros(2)                     # the library's start: all joint angles 0, at rest
    return loops.run_partial(model, phys, p, y0, np.zeros(5), t_out, s, "dtheta", "theta1_rate",
                             REASONS)
