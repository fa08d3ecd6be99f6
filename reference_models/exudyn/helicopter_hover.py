"""Exudyn model of the hovering helicopter (`helicopter-hover`, Table 4): the leaf entry point;
the model is `reference_models.exudyn.helicopter` (see there)."""
from reference_models.exudyn.helicopter import MODES_SETTINGS
from reference_models.exudyn.helicopter import hover_modes as modes

__all__ = ["MODES_SETTINGS", "modes"]
