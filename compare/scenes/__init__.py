"""Scene registry: every scene the toolkit knows, by name — the built-in ones and those other
installed packages register through the entry-point group `xval.scenes`. Scenes are data and
import no solver.

A plug-in's entry point names a `Scene`, a list of scenes, or a module (or object) with
`SCENES` (scenes) and optionally `SOLVERS`: the solvers the plug-in adds, each a dict of
`compare.solvers.Solver`'s fields (name, doc, engine, compiled, preset) — the built-in `exudyn`
and `mujoco` serve a plug-in scene through its `leaves`. One way to write a scene: the same
`Scene` and `LeafResult` as the built-in ones. A plug-in that fails to load is reported in one
line on stderr and left out; the built-in scenes stay."""
import importlib.metadata
import sys

from ..errors import BadInput
from . import bearing, mstmm, press, rotor, sail
from .base import (  # noqa: F401  (the scene types, for plug-ins)
    Calibration,
    Campbell,
    Extreme,
    Finding,
    Linearisation,
    MapSpec,
    ModesScene,
    Response,
    Scene,
    Threshold,
    TimeScene,
)
from .benchmarks_andrews import ANDREWS
from .benchmarks_bicycle import BICYCLE
from .benchmarks_bricard import BRICARD

GROUP = "xval.scenes"

SCENES = {s.name: s for s in (rotor.SPINUP, rotor.WHIRL, bearing.BEARING_ROTOR, press.PRESS,
                               press.PRESS_CYCLE, sail.SAIL, mstmm.ROTATING_BEAM,
                               mstmm.SPINNING_SHAFT, mstmm.HELICOPTER_CLAMPED,
                               mstmm.HELICOPTER_HOVER)}
SCENES[BICYCLE.name] = BICYCLE
SCENES[ANDREWS.name] = ANDREWS
SCENES[BRICARD.name] = BRICARD
ORIGIN = {}          # plug-in scene name -> (distribution or entry point, module)
PLUGIN_SOLVERS = []  # solvers plug-ins add, as dicts (compare.solvers puts them in REGISTRY)


def _contents(obj):
    if isinstance(obj, Scene):
        return [obj], []
    if isinstance(obj, (list, tuple)):
        return list(obj), []
    return list(getattr(obj, "SCENES", ())), list(getattr(obj, "SOLVERS", ()))


def load_plugins(entry_points=None):
    """Register the scenes (and solvers) of every `xval.scenes` entry point."""
    eps = (importlib.metadata.entry_points(group=GROUP) if entry_points is None
           else entry_points)
    for ep in eps:
        where = f"{ep.dist.name if getattr(ep, 'dist', None) else ep.value}"
        try:
            scenes, solvers = _contents(ep.load())
            bad = [s for s in scenes if not isinstance(s, Scene)]
            if bad or not scenes:
                raise TypeError("it names no Scene (a Scene, a list of them, or a module "
                                "with SCENES)")
            if not all(isinstance(s, dict) and "name" in s for s in solvers):
                raise TypeError("SOLVERS: each a dict of Solver fields (name, doc, engine, …)")
        except Exception as e:                   # a broken plug-in never breaks xval
            _say(f"plug-in {ep.name} ({where}) left out: {type(e).__name__}: "
                 f"{str(e).splitlines()[0] if str(e) else ''}")
            continue
        for sc in scenes:
            if sc.name in SCENES:
                _say(f"plug-in {ep.name} ({where}): scene {sc.name!r} left out: the name is "
                     f"taken")
                continue
            SCENES[sc.name] = sc
            ORIGIN[sc.name] = (where, ep.value.split(":")[0])
        PLUGIN_SOLVERS.extend(solvers)


def _say(line):
    print(f"xval: warning: {line}", file=sys.stderr)


def get_scene(name: str) -> Scene:
    try:
        return SCENES[name]
    except KeyError:
        raise BadInput(f"unknown scene {name!r} (known: {', '.join(SCENES)})") from None


load_plugins()

__all__ = ["SCENES", "Scene", "Campbell", "Extreme", "Finding", "Linearisation", "MapSpec",
           "Response", "Threshold", "get_scene", "ORIGIN", "PLUGIN_SOLVERS", "load_plugins"]
