"""Scene registry: every scene the toolkit knows, by name. Scenes are data and import no solver."""
from ..errors import BadInput
from .base import Finding, Scene
from . import press, rotor, sail

SCENES = {s.name: s for s in (rotor.SPINUP, rotor.WHIRL, press.PRESS, press.PRESS_CYCLE,
                                       sail.SAIL)}


def get_scene(name):
    try:
        return SCENES[name]
    except KeyError:
        raise BadInput(f"unknown scene {name!r} (known: {', '.join(SCENES)})") from None


__all__ = ["SCENES", "Scene", "Finding", "get_scene"]
