"""MuJoCo model of the hovering helicopter (`helicopter-hover`, Table 4): the leaf entry point;
the model is `reference_models.mujoco.helicopter` (see there)."""
from reference_models.mujoco.helicopter import MODES_SETTINGS
from reference_models.mujoco.helicopter import hover_modes as modes

__all__ = ["MODES_SETTINGS", "modes"]
