"""Scene registry: every scene the toolkit knows, by name. Scenes are data and import no solver."""
from ..errors import BadInput
from . import bearing, mstmm, press, rotor, sail
from .base import Campbell, Extreme, Finding, Scene

SCENES = {s.name: s for s in (rotor.SPINUP, rotor.WHIRL, bearing.BEARING_ROTOR, press.PRESS,
                               press.PRESS_CYCLE, sail.SAIL, mstmm.ROTATING_BEAM,
                               mstmm.SPINNING_SHAFT, mstmm.HELICOPTER_CLAMPED,
                               mstmm.HELICOPTER_HOVER)}


def get_scene(name: str) -> Scene:
    try:
        return SCENES[name]
    except KeyError:
        raise BadInput(f"unknown scene {name!r} (known: {', '.join(SCENES)})") from None


__all__ = ["SCENES", "Scene", "Campbell", "Extreme", "Finding", "get_scene"]
