"""Scene registry: every scene the toolkit knows, by name — the built-in ones and those other
installed packages register through the entry-point group `xval.scenes`. Scenes are data and
import no solver.

A plug-in's entry point names a `Scene`, a list of scenes, or a module (or object) with
`SCENES` (scenes) and optionally `SOLVERS`: the solvers the plug-in adds, each a dict of
`compare.solvers.Solver`'s fields (name, doc, engine, compiled, preset) — the built-in `exudyn`
and `mujoco` serve a plug-in scene through its `leaves`. One way to write a scene: the same
`Scene` and `LeafResult` as the built-in ones. A plug-in that fails to load is reported in one
line on stderr and left out; the built-in scenes stay."""
import importlib
import importlib.metadata
import sys
from collections.abc import MutableMapping

from ..errors import BadInput
from .base import (  # noqa: F401  (the scene types, for plug-ins)
    Calibration,
    Campbell,
    Extreme,
    Finding,
    FormulaCheck,
    Linearisation,
    MapSpec,
    ModesScene,
    Response,
    Scene,
    Threshold,
    TimeScene,
)

GROUP = "xval.scenes"

# the built-in scenes, in `xval list`'s order: name -> (module of compare.scenes, attribute).
# A scene's module (and its physics) is imported when the scene is first asked for, so
# `xval run SCENE` loads one scene family, not all of them.
BUILT_IN = {
    "rotor-spinup": ("rotor", "SPINUP"),
    "rotor-whirl": ("rotor", "WHIRL"),
    "bearing-rotor": ("bearing", "BEARING_ROTOR"),
    "press": ("press", "PRESS"),
    "press-cycle": ("press", "PRESS_CYCLE"),
    "sail-deploy": ("sail", "SAIL"),
    "rotating-beam": ("mstmm", "ROTATING_BEAM"),
    "spinning-shaft": ("mstmm", "SPINNING_SHAFT"),
    "helicopter-clamped": ("mstmm", "HELICOPTER_CLAMPED"),
    "helicopter-hover": ("mstmm", "HELICOPTER_HOVER"),
    "bicycle": ("benchmarks_bicycle", "BICYCLE"),
    "andrews-squeezer": ("benchmarks_andrews", "ANDREWS"),
    "bricard": ("benchmarks_bricard", "BRICARD"),
    "n-four-bar": ("benchmarks_nfourbar", "NFOURBAR"),
}


class Registry(MutableMapping):
    """Scenes by name: the built-in ones imported on first use, plug-ins' as registered."""

    def __init__(self, built_in):
        self._built_in, self._scenes = dict(built_in), {}

    def __getitem__(self, name):
        if name not in self._scenes and name in self._built_in:
            module, attr = self._built_in[name]
            sc = getattr(importlib.import_module(f"{__name__}.{module}"), attr)
            if sc.name != name:
                raise RuntimeError(f"BUILT_IN names {name!r} for the scene {sc.name!r}")
            self._scenes[name] = sc
        return self._scenes[name]

    def __setitem__(self, name, scene):
        self._scenes[name] = scene

    def __delitem__(self, name):
        if name not in self:
            raise KeyError(name)
        self._built_in.pop(name, None)
        self._scenes.pop(name, None)

    def __contains__(self, name):
        return name in self._built_in or name in self._scenes

    def __iter__(self):
        yield from self._built_in
        yield from (n for n in list(self._scenes) if n not in self._built_in)

    def __len__(self):
        return len(self._built_in) + sum(n not in self._built_in for n in self._scenes)


SCENES = Registry(BUILT_IN)
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
