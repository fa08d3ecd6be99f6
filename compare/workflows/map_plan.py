"""A map's plan (`xval map`), checked before anything runs: the axes (`Axis`, `parse_axis`),
the run estimate and its measured costs (`estimate`), and `plan_map` — scene, axes, parameters,
solvers and the work against the budget, each refused with one line (BadInput)."""
from __future__ import annotations

import math
from dataclasses import dataclass

from ..errors import BadInput
from ..scenes import get_scene
from . import plan as planner

MAX_JOBS = 100_000                # runs a map may plan before it is refused (--max-jobs)
MAX_ROWS = 257                    # rows a 2-D map's boundary tracing may reach per solver
# the rows' default spacing where the boundary bends, of the y range: the x bracket (1e-3 by
# default) taken for y too hit MAX_ROWS on the rotor map (197 rows, 144 gaps left, 180 s)
Y_RESOLUTION = 1 / 64
# the estimate before anything runs: seconds per output sample and per run, by solver engine,
# measured on rotor-spinup over 10 s at 1001 samples (quaternion 3.3 ms, euler-vector 5 ms,
# MuJoCo 86 ms, Exudyn 316 ms per run) plus a fixed cost per run; rough for other scenes
COST_PER_SAMPLE = {"numba": 5e-6, "numpy": 1e-6, "scipy": 5e-5, "mujoco": 9e-5,
                   "exudyn": 3.2e-4}
COST_PER_RUN = {"mujoco": 0.02, "exudyn": 0.05}


@dataclass(frozen=True)
class Axis:
    name: str
    lo: float
    hi: float
    unit: str

    @property
    def span(self):
        return self.hi - self.lo

    def as_dict(self):
        return {"name": self.name, "lo": self.lo, "hi": self.hi, "unit": self.unit}


def parse_axis(text, sc, flag):
    """NAME=LO:HI → Axis, the name a numeric scalar parameter of the scene, LO < HI inside its
    admissible range."""
    name, sep, rng = (text or "").partition("=")
    lo_t, sep2, hi_t = rng.partition(":")
    if not sep or not sep2:
        raise BadInput(f"{flag} {text!r}: expected NAME=LO:HI")
    p = sc.param(name.strip())
    if not p.is_numeric:
        raise BadInput(f"{flag} {name}: not a numeric parameter of scene {sc.name}")
    lo, hi = p.parse(lo_t), p.parse(hi_t)
    if not lo < hi:
        raise BadInput(f"{flag} {text!r}: LO must be below HI")
    return Axis(p.name, float(lo), float(hi), p.unit)


def estimate(sc, x_axis, y_axis, chosen, resolution, coarse, engines, params,
             y_resolution=None):
    """(runs, seconds) before anything runs: the coarse grid, ~log2 bisection rounds per row
    for a few crossings, the rows a boundary's tracing adds (~log2 halvings per gap), the
    engines' share, each run at its engine's measured cost."""
    nx, ny = coarse
    rows = ny if y_axis else 1
    rounds = max(1, math.ceil(math.log2(max(2.0, 1.0 / (resolution * (nx - 1))))))
    traced = ((ny - 1) * max(1, math.ceil(math.log2(max(2.0, 1.0 / (
        (y_resolution or resolution) * (ny - 1)))))) if y_axis else 0)
    per_custom = (nx + 2 * rounds + 4) * (rows + traced)
    per_engine = (nx * rows + 2 * rows * rounds) if engines == "everywhere" else 8 * rows
    samples = sc.samples_per_run(params)
    runs, secs = 0, 0.0
    for s in chosen:
        n = per_engine if is_engine(s) else per_custom
        runs += n
        secs += n * (COST_PER_SAMPLE.get(s.engine, 1e-4) * samples
                     + COST_PER_RUN.get(s.engine, 1e-3))
    return runs, secs


def plan_map(scene_name, x, y=None, overrides=None, solver_names=None, resolution=1e-3,
             coarse=None, observable=None, level=None, engines="boundary", max_jobs=None,
             y_resolution=None, max_rows=MAX_ROWS, adaptive=True):
    """Everything checked before a run (one line, BadInput): scene, axes, parameters,
    solvers, the work against the budget."""
    sc = get_scene(scene_name)
    if not sc.mappable:
        raise BadInput(f"scene {sc.name!r} is a frequency scene with no map observable: maps "
                       f"are of time scenes' regimes and of observables")
    if level is not None and observable is None:      # a level of which observable?
        raise BadInput(f"--level needs --observable NAME (of {sc.name}: "
                       f"{', '.join(sc.map_observables) or 'none'})")
    if observable is None and sc.regime is None and sc.map_observables:
        observable = next(iter(sc.map_observables))
    if observable is None and sc.regime is None:
        raise BadInput(f"scene {sc.name!r} declares no regime or map observable")
    if observable is not None and observable not in sc.map_observables:
        raise BadInput(f"--observable {observable}: not a map observable of {sc.name} "
                       f"(known: {', '.join(sc.map_observables) or 'none'})")
    if not (isinstance(resolution, (int, float)) and 0 < resolution < 0.5):
        raise BadInput(f"--resolution must be in (0, 0.5), got {resolution!r}")
    y_resolution = max(resolution, Y_RESOLUTION) if y_resolution is None else y_resolution
    if not (isinstance(y_resolution, (int, float)) and 0 < y_resolution < 0.5):
        raise BadInput(f"--y-resolution must be in (0, 0.5), got {y_resolution!r}")
    if engines not in ("boundary", "everywhere"):
        raise BadInput(f"--engines must be boundary or everywhere, got {engines!r}")
    x_axis = parse_axis(x, sc, "--x")
    y_axis = parse_axis(y, sc, "--y") if y else None
    if y_axis and y_axis.name == x_axis.name:
        raise BadInput("--y names the same parameter as --x")
    overrides = dict(overrides or {})
    for a in (x_axis, y_axis):
        if a and a.name in overrides:
            raise BadInput(f"--set {a.name}: it is an axis of the map")
    coarse = tuple(coarse) if isinstance(coarse, (list, tuple)) else (
        (coarse,) if coarse else ())
    if not all(isinstance(n, int) and not isinstance(n, bool) for n in coarse) \
            or len(coarse) > 2:
        raise BadInput(f"coarse grid: NX or (NX, NY) whole numbers, got {coarse!r}")
    coarse = (coarse + ((17,) if not coarse else ()) + (9 if y_axis else 1,))[:2]
    if not y_axis:
        coarse = (coarse[0], 1)
    if coarse[0] < 2 or (y_axis and coarse[1] < 2):
        raise BadInput("coarse grid: at least 2 points along each axis")
    # every solver's settings checked at the low corner; a run holds one solver's output
    pl = planner.plan(sc, {**overrides, x_axis.name: x_axis.lo,
                           **({y_axis.name: y_axis.lo} if y_axis else {})}, solver_names,
                      limits=planner.Limits(together=False))
    params, chosen = pl.params, list(pl.solvers)
    for corner in (x_axis.hi,):
        sc.resolve({**overrides, x_axis.name: corner})
    runs, secs = estimate(sc, x_axis, y_axis, chosen, resolution, coarse, engines, params,
                          y_resolution)
    limit = MAX_JOBS if max_jobs is None else max_jobs
    if runs > limit:
        raise BadInput(f"map of {sc.name}: ~{runs} runs (~{secs:.3g} s on one core) exceed the "
                       f"budget of {limit} runs: lower the resolution or the coarse grid, or "
                       f"pass --max-jobs")
    return {"scene": sc, "x": x_axis, "y": y_axis, "overrides": overrides, "chosen": chosen,
            "resolution": resolution, "coarse": coarse, "observable": observable,
            "level": level, "engines": engines, "estimate": {"runs": runs, "seconds": secs},
            "settings": pl.settings, "y_resolution": y_resolution, "max_rows": max_rows,
            "adaptive": bool(adaptive)}


def is_engine(s):
    return s.engine in ("exudyn", "mujoco")
