"""`lagrange-partial` for scene `andrews-squeezer`: the press paper's method (Lagrange's
equations in minimal coordinates with velocity analogues from "partial systems" by central
differences, linear-acceleration integration) on Andrews' squeezer, one coordinate β (model.py).

Settings: integrator (linacc, wilson [theta], linacc-pc, linacc-fp), dt, dbeta (the virtual
step of the partial systems, rad), newton_tol (the implicit step, relative to the
accelerations), closure_tol (the loop closure's Newton, rad), max_iter.
"""
import numpy as np

from compare.contract import LeafResult, check_once
from compare.physics import andrews as phys

from .. import loops
from ..integrators import FAIL_REASONS, LA_REASONS
from ..integrators.linear_acceleration import LA_INTEGRATORS
from . import model

CHANNELS = phys.CHANNELS
INTEGRATORS = tuple(LA_INTEGRATORS)
DEFAULT_SETTINGS = {"integrator": "linacc", "dt": 1e-6, "theta": 1.4, "dbeta": 1e-4,
                    "newton_tol": 1e-8, "closure_tol": 1e-13, "max_iter": 30}
# the virtual step's central differences: an O(Δβ²) error the time step's halving cannot see
KNOBS = {"dbeta": 2}
# its round-off optimum: the closure, solved to ~1e-15 rad, rounds the differences as δ/Δβ²,
# so a reference run halves Δβ once (at a drawn set the distance to Exudyn at dt/16 is 3.3e-11,
# 1.4e-11, 3.9e-11, 4.5e-11, 5.7e-10 rad in β at Δβ/1, /2, /4, /8, /16)
KNOB_LIMITS = {"dbeta": 1}
REASONS = {**FAIL_REASONS, **LA_REASONS,
           model.FAIL_CLOSURE: "singular: the loop closure's Newton iteration found no "
                               "assembly near the last one (dependent-angle Jacobian "
                               "singular, as at a dead point: β turns back while the loop "
                               "moves on, and one coordinate cannot carry it)"}


@check_once
def check_settings(settings: dict | None, t_out: np.ndarray | None = None) -> dict:
    """The settings merged and checked before anything runs (ValueError with one line)."""
    return loops.partial_settings(settings, DEFAULT_SETTINGS, INTEGRATORS, "dbeta")


def simulate(params: dict, t_out: np.ndarray, settings: dict | None = None) -> LeafResult:
    s = check_settings(settings)
    t_out = np.asarray(t_out, float)
    q0 = phys.initial_angles(params)
    p = model.pack(params, float(s["dbeta"]), float(s["closure_tol"]), q0[1:])
    y0 = np.array([q0[0], 0.0])
    return loops.run_partial(model, phys, p, y0, q0[1:], t_out, s, "dbeta", "beta_rate", REASONS)
