"""`lagrange-partial` for scenes `press` / `press-cycle`: the paper's method. Joint positions
from the loop closure; velocity analogues ∂r/∂φ, ∂r/∂ψ of the "partial systems" (one coordinate
frozen) by central differences with virtual steps Δφ, Δψ (settings dphi_deg, dpsi_deg); A_ij and
A_ij,k rebuilt from them before every evaluation; generalized forces from virtual work;
linear-acceleration (Wilson) integration (eqs. 41–45) or RK4. Physics in `press.py`.

Settings: as `press_exact`, plus dphi_deg, dpsi_deg (paper: 0.1°).
"""
import numpy as np

from compare.contract import LeafResult, check_once

from . import lagrange as press

DEFAULT_SETTINGS = {**press.COMMON_SETTINGS, "integrator": "linacc", "dt": 1e-5, "dphi_deg": 0.1,
                    "dpsi_deg": 0.1}
INTEGRATORS = press.INTEGRATORS
ADAPTIVE = press.ADAPTIVE          # error-controlled (press only, not press-cycle)
# the virtual steps' central differences: an O(Δ²) error the time step's halving cannot see,
# varied together — one homogeneous a·Δφ² + b·Δψ² whose terms often cancel: alone, each moved
# press-cycle's slider_x by 1.4e-10 m at `xval calibrate --seed 2026` set 18, together by
# 8.5e-12, and 4/3 of the joint change met the distance to lagrange-exact to 3 % at the
# defaults of press and press-cycle (crank_accel, slider_x, rocker_angle)
KNOBS = {"dphi_deg+dpsi_deg": 2}
CHANNELS = press.CHANNELS


@check_once
def check_settings(settings: dict | None, t_out: np.ndarray | None = None) -> dict:
    """The settings merged and checked before anything runs (ValueError with one line)."""
    return press.settings_of(DEFAULT_SETTINGS, settings)


def simulate(params: dict, t_out: np.ndarray, settings: dict | None = None) -> LeafResult:
    return press.simulate("partial", DEFAULT_SETTINGS, params, t_out, settings)
