"""`xval bench`: speed against accuracy — the work-precision sweep, or a map's throughput."""
from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from ..errors import BadInput
from ..output.folders import claim_out, make_out
from ..results import BenchResult
from ..workflows.inputs import positive, positive_int
from ..workflows.plan import names
from . import Command, arg
from .common import (
    BUDGET,
    RESULT_OUT,
    STUDY,
    answer,
    log,
    overrides,
    parse_sets,
    quiet,
    stdout_to_stderr,
)
from .common import positive_int as positive_int_arg


def bench(scene: str, solvers=None, *, repeats: int = 3, vary=None, out=None,
          max_output_gib=None, max_steps=None, params: dict | None = None,
          log: Callable | None = None, points: int | None = None, force: bool = False,
          identify: bool = False, **kw) -> BenchResult:
    """Work-precision sweep (`xval bench`): each solver along its accuracy knob, error of the
    key channel against a tight reference, median wall time of `repeats` runs. `vary`: trade a
    model parameter instead, as `"stiffness=1e5,1e6"` or `{"stiffness": [1e5, 1e6]}`.
    `points=N`: throughput instead — each solver's points per second over N points of the
    scene's first default map. `identify=True`: the identification's speed instead — xval's
    fit of a synthetic record against a plain least_squares loop over the same solver (a scene
    with a Fit). `out`: the bench's folder (default: none, the bench held in memory — its
    rows, not its trajectories — and `save(path)` writing it); an existing one must be empty or
    hold an earlier bench, unless `force`."""
    from ..output import bench_identify as bi
    from ..output import bench_report as br
    from ..workflows.bench import run_bench, run_throughput
    positive_int("--repeats", repeats)
    if identify and (points is not None or vary is not None):
        raise BadInput(f"--identify: not with {'--points' if points is not None else '--vary'}"
                       " (one bench mode at a time)")
    if out is not None:
        claim_out(str(out), "bench", force)
    if identify:                        # the identification's speed (issue 50, item 5)
        from ..workflows.bench_identify import run_identify_bench
        obj = run_identify_bench(scene, names(solvers), overrides(params, kw), repeats,
                                 log=log or quiet)
        return _result(obj, out, bi.write_identify_bench)
    if points is not None:              # throughput: points per second over the default map
        positive_int("--points", points)
        obj = run_throughput(scene, names(solvers), overrides(params, kw), points,
                             log=log or quiet)
        return _result(obj, out, lambda d, o: br.write_throughput(d, o, scene))
    max_output_gib, max_steps = (positive("--max-output-gib", max_output_gib),
                                 positive("--max-steps", max_steps))
    if isinstance(vary, dict):
        if len(vary) != 1:
            raise BadInput(f"--vary: one parameter, got {len(vary)}")
        (name, values), = vary.items()
        vary = f"{name}={','.join(repr(v) for v in values)}"
    from ..scenes import get_scene
    obj = run_bench(scene, names(solvers), overrides(params, kw), out, repeats=repeats,
                    log=log or quiet, vary=vary, max_output_gib=max_output_gib,
                    max_steps=max_steps, make_out=make_out)
    write = get_scene(scene).either(time=br.write_time_bench, modes=br.write_modes_bench)
    return _result(obj, out, write)


def _result(obj, out, write) -> BenchResult:
    """The bench written into `out` (`write(folder, obj)`), or held in memory, `save` writing
    it then."""
    from ..output.bench_report import bench_dir
    if out is None:
        return BenchResult(obj, writer=lambda d: write(bench_dir(d), obj))
    make_out(str(out))
    obj = write(bench_dir(out), obj)
    return BenchResult(obj, Path(obj["report"]).parent)


def main(args) -> int:
    from ..scenes import get_scene
    from ..workflows.work_precision import new_bench_dir
    # without --out a new folder under logs/bench/ (the default place since the first release)
    out = args.out or new_bench_dir("logs", get_scene(args.scene).name
                                    + ("-points" if args.points else "")
                                    + ("-identify" if args.identify else ""))
    with stdout_to_stderr():
        r = bench(args.scene, args.solver, repeats=args.repeats, vary=args.vary, out=out,
                  max_output_gib=args.max_output_gib, max_steps=args.max_steps,
                  params=parse_sets(args.set), log=log, points=args.points, force=args.force,
                  identify=args.identify)
    answer(args, r)
    return 0


COMMAND = Command(
    "bench", order=7, main=main, api=bench, result=BenchResult, docs="bench.md",
    help="speed/accuracy (work-precision) sweep",
    description="Work-precision: each solver along its accuracy knob (step or tolerance; "
                "frequency scenes: mesh, segments or root tolerance), error of the key "
                "channel's final value (frequency scenes: the largest relative frequency "
                "error, and the paper's computing times against each solver's defaults) "
                "against a tight reference, median wall time.",
    args=(*STUDY,
          arg("--repeats", type=positive_int_arg("--repeats"), default=3, metavar="N",
              help="timed runs per rung; the median counts (default 3)"),
          arg("--points", type=positive_int_arg("--points"), metavar="N",
              help="throughput instead: each solver's points per second over N points of the "
                   "scene's default map (the map's batch path)"),
          arg("--identify", action="store_true",
              help="the identification's speed instead (a scene with a Fit): a record "
                   "synthesised from the first solver at the --set parameters, xval's fit on "
                   "each solver against a plain scipy least_squares loop over the first"),
          arg("--vary", metavar="NAME=V1,V2,...",
              help="trade a model parameter instead of the step: each solver's default "
                   "settings at each value, errors against the reference at the --set value "
                   "(e.g. --vary stiffness=1e5,1e6)"),
          *RESULT_OUT, *BUDGET))
