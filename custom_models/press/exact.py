"""`lagrange-exact` for scenes `press` / `press-cycle`: the paper's Lagrange equations (35) with
analytic velocity analogues ∂r/∂q and analytic A_ij,k (our addition: it isolates the
finite-difference error of the paper's method, `press_partial`). Physics in `press.py`.

Settings: integrator (see INTEGRATORS: linacc, wilson [theta], linacc-pc (the paper's printed
predictor–corrector), linacc-fp, euler, midpoint, rk4, rk23, dopri5, dop853 (adaptive: press
only)), dt or rtol/atol, newton_tol, max_iter, singular_tol, energy_jump, event_tol.
"""
import numpy as np

from compare.contract import LeafResult, check_once

from . import lagrange as press

DEFAULT_SETTINGS = {**press.COMMON_SETTINGS, "integrator": "rk4", "dt": 1e-5}
INTEGRATORS = press.INTEGRATORS
ADAPTIVE = press.ADAPTIVE          # error-controlled (press only, not press-cycle)
CHANNELS = press.CHANNELS


@check_once
def check_settings(settings: dict | None, t_out: np.ndarray | None = None) -> dict:
    """The settings merged and checked before anything runs (ValueError with one line)."""
    return press.settings_of(DEFAULT_SETTINGS, settings)


def simulate(params: dict, t_out: np.ndarray, settings: dict | None = None) -> LeafResult:
    return press.simulate("exact", DEFAULT_SETTINGS, params, t_out, settings)
