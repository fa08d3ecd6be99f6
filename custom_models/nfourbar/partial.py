"""`lagrange-partial` for scene `n-four-bar`: the press paper's method (Lagrange's equations in
minimal coordinates with velocity analogues from "partial systems" by central differences,
linear-acceleration integration) on the N four-bar mechanism, one coordinate θ = φ_0
(model.py). The method never leaves the parallelogram by construction unless a loop's closure
jumps branch at a singular position: the full state is read back loop by loop, so the
`parallelogram` channel shows it if it does.

Settings: integrator (linacc, wilson [theta], linacc-pc, linacc-fp), dt, dtheta (the virtual
step of the partial systems, rad), newton_tol (the implicit step, relative to the
accelerations), closure_tol (the loops' Newton iteration, rad), max_iter.
"""
import numpy as np

from compare.contract import LeafResult
from compare.physics import nfourbar as phys

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
# its round-off optimum: its halvings at dt/16 change φ̇ by 3.5e-11, 4.1e-11, 2.2e-11, 2.5e-10
# rad/s (n-four-bar calibration set 19) — rounding from the first, so a reference run halves
# Δθ once
KNOB_LIMITS = {"dtheta": 1}
REASONS = {**FAIL_REASONS, **LA_REASONS,
           model.FAIL_CLOSURE: "singular: a loop's closure (Newton) found no assembly near the "
                               "last one (its Jacobian singular: all rods horizontal)"}


def check_settings(settings: dict | None, t_out: np.ndarray | None = None) -> dict:
    """The settings merged and checked before anything runs (ValueError with one line)."""
    return loops.partial_settings(settings, DEFAULT_SETTINGS, INTEGRATORS, "dtheta")


class _Run:
    """What the shared driver (loops.run_partial) asks of a model and its physics: the
    compiled pieces, the state read back from the start along the run's branch, and the
    scene's channels from the coordinates (cranks first, then couplers)."""

    def __init__(self, params):
        self.params, self.n = params, int(params["N"])
        self.acc, self.guard, self.WARM, self.NP = model.acc, model.guard, model.WARM, model.NP

    def full_state(self, Y, p):
        return model.full_state(Y, p, float(self.params["phi0"]),
                                model.initial_warm(self.params))

    def channels(self, Q, QD, _p):
        k = self.n + 1
        return phys.channels(Q[:, :k], QD[:, :k], Q[:, k:], QD[:, k:], self.params)


def simulate(params: dict, t_out: np.ndarray, settings: dict | None = None) -> LeafResult:
    s = check_settings(settings)
    t_out = np.asarray(t_out, float)
    p = model.pack(params, float(s["dtheta"]), float(s["closure_tol"]))
    y0 = np.array([float(params["phi0"]), phys.initial_rate(params)])
    run = _Run(params)
    return loops.run_partial(run, run, p, y0, model.initial_warm(params), t_out, s, "dtheta",
                             "theta_rate", REASONS)
