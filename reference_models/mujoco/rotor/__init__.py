"""MuJoCo reference model of the spin-up rotor (scenes `rotor-spinup` and `rotor-whirl`).

A disk on a massless shaft on a ball joint; the scene's cone spring −kγ (MuJoCo has none that
leaves the spin free) is a passive-force callback, by default a numba cfunc. One module per
capability:

- `settings`: integrators, DEFAULT_SETTINGS, check_settings;
- `kernel`: the spring and damper moments; `callback`: the passive callback that applies them
  (native or Python) and its installation;
- `model`: the MjModel compiled from the resolved parameters and the data of one point;
- `time`: `simulate`; `batch`: `regimes` (the map's batch path, one rollout for many points);
- `linear`: `modes`, `whirl_sweep` (the linearised whirl); `response`: `unbalance_response`.
"""
from compare.contract import lazy_exports

from .settings import CHEAP_DT, DEFAULT_SETTINGS, INTEGRATORS, check_settings
from .time import simulate

# the other capabilities load on first use (a time run needs none of them)
LAZY = {"regimes": "batch", "modes": "linear", "whirl_sweep": "linear",
        "unbalance_response": "response"}
__getattr__ = lazy_exports(__name__, LAZY)

__all__ = ["CHEAP_DT", "DEFAULT_SETTINGS", "INTEGRATORS", "check_settings", "modes", "regimes",
           "simulate", "unbalance_response", "whirl_sweep"]
