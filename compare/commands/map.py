"""`xval map`: regimes or an observable over one or two parameters."""
from __future__ import annotations

import shlex
import sys
from collections.abc import Callable
from pathlib import Path

from ..errors import BadInput
from ..output.folders import claim_out, make_out
from ..results import MapResult
from ..workflows.inputs import positive, positive_int
from ..workflows.plan import names
from . import Command, arg
from .common import (
    NO_RECORD,
    RESULT_OUT,
    STRICT,
    STUDY,
    answered,
    executor_args,
    log,
    overrides,
    parse_sets,
    quiet,
    stdout_to_stderr,
    warn_workers,
)
from .common import positive as positive_arg
from .common import positive_int as positive_int_arg


def map(scene: str, x: str, y: str | None = None, solvers=None, *,  # noqa: A001 (the command)
        resolution: float = 1e-3, coarse=None, observable: str | None = None, level=None,
        engines: str = "boundary", executor: str = "local", scheduler: str | None = None,
        workers: int | None = None, max_jobs=None, record: bool = True, out=None,
        params: dict | None = None, log: Callable | None = None, y_resolution=None,
        adaptive: bool = True, force: bool = False, store=None, **kw) -> MapResult:
    """A map (`xval map`): the scene's regimes, or `observable`, over `x` (and `y`), each
    "NAME=LO:HI"; every solver's crossings with brackets ≤ resolution × the x range, their
    error estimates and the pairwise verdicts (`s["boundaries"]`, `s["verdicts"]`); a 2-D
    map traces its boundary in y down to `y_resolution` × the y range (default 1/64, or the
    resolution where coarser).
    `adaptive=False`: every coarse point at the accurate setting (not only those next to a
    regime change). `out`: the map's folder (default: none, the map held in memory and
    `save(path)` writing it); an existing one must be empty or hold an earlier map, unless
    `force`. `store`:
    where the points are kept by the digest of their inputs, for a rerun to reuse (default:
    the folder's points/)."""
    from ..workflows.maps import compute_map, map_to_folder, plan_map
    if executor not in ("local", "dask"):
        raise BadInput(f"--executor: {executor!r} is not local or dask")
    if out is not None:
        claim_out(str(out), "map", force)
    if scheduler and executor != "dask":
        raise BadInput("--scheduler needs --executor dask")
    positive_int("--workers", workers)
    plan = plan_map(scene, x, y, overrides(params, kw), names(solvers),
                    positive("--resolution", resolution), coarse, observable, level, engines,
                    positive_int("--max-jobs", max_jobs),
                    None if y_resolution is None else positive("--y-resolution", y_resolution),
                    adaptive=adaptive)
    (log or quiet)(f"map {scene}: ~{plan['estimate']['runs']} runs planned "
                   f"(~{plan['estimate']['seconds']:.3g} s of solver time)")
    if out is None:                     # held in memory: `save` writes its files
        from ..output.map_plot import write_map_outputs
        obj = compute_map(plan, executor=executor, scheduler=scheduler, workers=workers,
                          log=log or quiet, store=Path(store) if store else None)

        def write(folder):
            obj["folder"] = str(folder)
            done = write_map_outputs(folder, obj, record)
            done["report"] = done["files"]["report"]
            return done
        return MapResult(obj, writer=write)
    make_out(str(out))
    # points stored by the digest of their inputs: a stopped map resumes
    obj = map_to_folder(plan, out, executor=executor, scheduler=scheduler, workers=workers,
                        record=record, log=log or quiet,
                        store=Path(store) if store else Path(out) / "points")
    obj["report"] = obj["files"]["report"]
    return MapResult(obj, Path(obj["folder"]))


def _coarse(text):
    try:
        vals = tuple(int(v) for v in text.split(","))
    except ValueError:
        raise BadInput(f"--coarse {text!r}: expected NX or NX,NY (whole numbers)") from None
    if len(vals) not in (1, 2):
        raise BadInput(f"--coarse {text!r}: expected NX or NX,NY")
    return vals if len(vals) == 2 else (vals[0], 9)


def main(args) -> int:
    from ..scenes import get_scene
    from ..workflows.executors import Interrupted
    from ..workflows.maps import map_dir
    out, store = args.out, None
    if out is None:      # a new folder under logs/maps/, the points shared in logs/maps/points/
        out, store = map_dir("logs", get_scene(args.scene).name), Path("logs", "maps", "points")
    coarse = _coarse(args.coarse) if args.coarse else None
    if coarse and not args.y:
        coarse = (coarse[0], 1)
    warn_workers(args)
    try:
        with stdout_to_stderr():
            r = map(args.scene, args.x, args.y, args.solver, resolution=args.resolution,
                    coarse=coarse, observable=args.observable, level=args.level,
                    engines=args.engines, executor=args.executor, scheduler=args.scheduler,
                    workers=args.workers, max_jobs=args.max_jobs, record=not args.no_record,
                    out=out, params=parse_sets(args.set), log=log,
                    y_resolution=args.y_resolution, adaptive=not args.accurate_everywhere,
                    force=args.force, store=store)
    except Interrupted as e:             # Ctrl-C / SIGTERM: workers stopped, points kept
        print(f"xval: interrupted: {e}; resume with: {shlex.join(['xval', *args.argv])}",
              file=sys.stderr)
        return 130
    return answered(args, r, r.data)


COMMAND = Command(
    "map", order=8, main=main, api=map, result=MapResult, docs="map.md",
    help="regimes or an observable over one or two parameters",
    description="Map a scene's regimes (or a scalar observable) over a parameter line or "
                "plane: a coarse grid, then bisection where neighbours differ, every solver's "
                "boundary located on its own and compared with error bars.",
    args=(*STUDY,
          arg("--x", required=True, metavar="NAME=LO:HI", help="the x axis"),
          arg("--y", metavar="NAME=LO:HI", help="the y axis (a 2-D map)"),
          arg("--resolution", type=positive_arg("--resolution"), default=1e-3,
              help="bracket of every crossing as a fraction of the x range (default 1e-3)"),
          arg("--y-resolution", type=positive_arg("--y-resolution"), default=None,
              help="a 2-D map adds rows where neighbouring rows' crossings differ, down to "
                   "this fraction of the y range (default: 1/64, or --resolution where "
                   "coarser)"),
          arg("--coarse", metavar="NX[,NY]",
              help="the coarse grid: points along x and rows along y (default 17,9)"),
          arg("--accurate-everywhere", action="store_true",
              help="run every coarse point at the accurate setting (default: a cheap "
                   "tolerance first, the accurate one next to a regime change)"),
          arg("--observable", metavar="NAME",
              help="map a scalar observable of the scene instead of its regime"),
          arg("--level", type=float, metavar="V",
              help="with --observable: locate where it crosses V"),
          arg("--engines", choices=("boundary", "everywhere"), default="boundary",
              help="engines refine the custom solvers' boundary (default) or map the whole "
                   "plane"),
          *executor_args("workers"),
          arg("--max-jobs", type=positive_int_arg("--max-jobs"), default=None, metavar="N",
              help="refuse to start a map estimated above N runs (default 100000)"),
          NO_RECORD, *RESULT_OUT, STRICT))
