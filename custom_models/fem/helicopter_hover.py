"""`fem` leaf for `helicopter-hover`: the helicopter with the tail end free (Table 4)."""
from compare.contract import LeafModes

from .helicopter import MODES_SETTINGS, check_settings, modes_for  # noqa: F401


def modes(params: dict, settings: dict) -> LeafModes:
    return modes_for(params, settings, False)
