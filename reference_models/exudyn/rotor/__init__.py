"""Exudyn reference model of the spin-up rotor (scenes `rotor-spinup` and `rotor-whirl`).

The rotor (massless shaft of length l on a spherical joint at O, eccentric disk at its end) is an
`ObjectKinematicTree` gimbal in a Cardan chart, loaded by the scene's cone spring −kγ and a drive
torque fixed in space through compiled user functions. One module per capability:

- `settings`: integrators, DEFAULT_SETTINGS, check_settings;
- `chart`: the Cardan charts (R and ω from the coordinates and back, the change of chart);
- `kernels`: the compiled loads and work rates (and why they are compiled);
- `model`: the engine model, built from the resolved parameters (`build`), and the solver calls;
- `time`: `simulate`; `batch`: `regimes` (the map's batch path, rotors as branches of one tree);
- `linear`: `modes`, `whirl_sweep` (the linearised whirl); `response`: `unbalance_response`.
"""
from compare.contract import lazy_exports

from .settings import ADAPTIVE, CHEAP_DT, DEFAULT_SETTINGS, INTEGRATORS, check_settings
from .time import simulate

# the other capabilities load on first use (a time run needs none of them)
LAZY = {"regimes": "batch", "modes": "linear", "whirl_sweep": "linear",
        "unbalance_response": "response"}
__getattr__ = lazy_exports(__name__, LAZY)

__all__ = ["ADAPTIVE", "CHEAP_DT", "DEFAULT_SETTINGS", "INTEGRATORS",
           "check_settings", "modes", "regimes", "simulate", "unbalance_response", "whirl_sweep"]
