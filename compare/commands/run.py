"""`xval run`: a time-domain scene through every solver, compared pairwise."""
from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from ..errors import BadInput
from ..output.folders import claim_out, make_out
from ..results import TimeResult
from ..workflows.inputs import positive
from ..workflows.plan import names
from . import Command, arg
from .common import (
    BUDGET,
    NO_RECORD,
    RESULT_OUT,
    STRICT,
    STUDY,
    TIMEOUT,
    compared_answer,
    log,
    overrides,
    parse_sets,
    quiet,
    result_folder,
    stdout_to_stderr,
)
from .common import (
    positive as positive_arg,
)


def run(scene: str, solvers=None, settings: dict | None = None, *, dt=None, rtol=None,
        integrator: str | None = None, out=None, record: bool | None = None,
        timeout=None, max_output_gib=None, max_steps=None, estimate_errors: bool = True,
        params: dict | None = None, log: Callable | None = None, force: bool = False,
        **kw) -> TimeResult:
    """Simulate a time-domain scene with each solver (default: every solver of the scene),
    compare them pairwise, and return a `TimeResult`.

    Scene parameters as keywords (`torque=3.2, t_end=5`) or `params={...}`. `settings`: one
    dict for every solver or one per solver name (see `per_solver_settings`), passed to the
    leaves as they are; `dt` / `rtol` / `integrator` as `--dt` / `--rtol` / `--integrator`
    (which also switch an adaptive default to a fixed-step method and back). `out`: the folder
    the run's files are written into (default: nothing kept; an existing one must be empty or
    hold an earlier run, unless `force`); `record`: the rerun recording (default: when
    `out` is given; the report is written whenever `out` is). `timeout`: wall-clock limit per
    solver (s). `estimate_errors=False` skips the tighter rerun that estimates each solver's
    own error (half the time; the verdicts then weigh the deviation against the scene's
    allowance alone). `log`: a callable for progress lines (default: silent)."""
    from ..scenes import get_scene
    from ..workflows import runner
    from ..workflows.plan import Knobs, Limits, plan
    sc = get_scene(scene)
    if sc.command != "run":
        raise BadInput(f"scene {sc.name!r} is {sc.described}: use `xval {sc.command} {sc.name}`")
    if out is not None:
        claim_out(str(out), "time", force)
    if record and out is None:
        raise BadInput("record=True needs out=FOLDER (or call .save(path) on the result)")
    knobs = Knobs(positive("--dt", dt), positive("--rtol", rtol), integrator)
    limits = Limits(positive("--max-output-gib", max_output_gib),
                    positive("--max-steps", max_steps))
    # everything checked (solvers, budgets, parameters, settings) before anything runs
    pl = plan(sc, overrides(params, kw), names(solvers), settings, knobs, limits,
              timeout_s=positive("--timeout", timeout), estimate_errors=estimate_errors)
    log = log or quiet
    out_dir = None
    if out is not None:
        make_out(str(out))
        out_dir = Path(out)
    if knobs.rtol is not None:
        for s in pl.solvers:
            if not s.info(sc).adaptive:
                log(f"{s.name}: no error-controlled integrator, --rtol ignored (fixed step kept)")
    try:                 # with `out` the report is written, as by `xval run`; else nothing
        return runner.execute(pl, out_dir, record=out is not None if record is None else record,
                              report=out is not None, log=log)
    except OSError as e:                 # disk full / read-only: one line, folder stays marked
        from ..output.guard import write_failure
        if write_failure(e) is None:
            raise
        raise BadInput(f"{write_failure(e)}; {out_dir} is left marked incomplete") from None


def main(args) -> int:
    out = result_folder(args)
    with stdout_to_stderr():
        r = run(args.scene, args.solver, dt=args.dt, rtol=args.rtol,
                integrator=args.integrator, out=out, record=not args.no_record,
                timeout=args.timeout, max_output_gib=args.max_output_gib,
                max_steps=args.max_steps, params=parse_sets(args.set), log=log,
                force=args.force)
    return compared_answer(args, r)


COMMAND = Command(
    "run", order=3, main=main, api=run, result=TimeResult, docs="run.md",
    help="simulate a scene with several solvers and compare them",
    description="Simulate a time-domain scene with each solver, compare the trajectories "
                "pairwise, record (rerun .rrd) and report (Markdown with plots).",
    args=(*STUDY,
          arg("--dt", type=positive_arg("--dt"), metavar="S", exclusive="knob",
              help="fixed step in seconds (an adaptive default switches to its fixed-step "
                   "method, e.g. rk4)"),
          arg("--rtol", type=positive_arg("--rtol"), exclusive="knob",
              help="relative tolerance for the error-controlled integrators (fixed-step "
                   "solvers keep their step and say so)"),
          arg("--integrator", metavar="NAME",
              help="integrator of every chosen solver (each must offer it)"),
          *RESULT_OUT, STRICT, NO_RECORD, TIMEOUT, *BUDGET))
