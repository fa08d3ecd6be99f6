"""MuJoCo reference model of the spinning cantilever shaft (`spinning-shaft`): the leaf entry
point; the model is `reference_models.mujoco.beam_modes.shaft_modes` (see there)."""
from reference_models.mujoco.beam_modes import SHAFT_MODES_SETTINGS as MODES_SETTINGS
from reference_models.mujoco.beam_modes import shaft_modes as modes

__all__ = ["MODES_SETTINGS", "modes"]
