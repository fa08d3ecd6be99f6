"""`xval extremes`: numerical stability at the extremes of a scene."""
from __future__ import annotations

from collections.abc import Callable

from ..output.folders import claim_out
from ..results import ExtremesResult
from ..workflows.inputs import positive
from ..workflows.plan import names
from . import Command, arg
from .common import (
    JSON,
    RESULT_OUT,
    SCENE,
    TIMEOUT,
    answered,
    log,
    quiet,
    stdout_to_stderr,
)


def extremes(scene: str, solvers=None, *, include_slow: bool = False, timeout=None, out=None,
             log: Callable | None = None, force: bool = False) -> ExtremesResult:
    """Every extreme case of the scene's spec with every solver (`xval extremes`; the long
    cases with `include_slow=True`, the command's `--all`). `out`: the folder its report and
    result.json are written into (default: held in memory); an existing one must be empty or
    hold an earlier extremes result, unless `force`."""
    from ..workflows.extremes import run_extremes
    timeout = positive("--timeout", timeout)
    if out is not None:
        claim_out(str(out), "extremes", force)
    res = run_extremes(scene, names(solvers), include_slow=include_slow, timeout_s=timeout,
                       log=log or quiet)
    if out is not None:
        res.save(out)
    return res


def main(args) -> int:
    from ..workflows.extremes import extremes_dir
    # without --out a new folder under logs/extremes/ (the default place since the first release)
    out = args.out or extremes_dir("logs", args.scene)
    with stdout_to_stderr():
        r = extremes(args.scene, args.solver, include_slow=args.all, timeout=args.timeout,
                     out=out, log=log, force=args.force)
    return answered(args, r)


COMMAND = Command(
    "extremes", order=10, main=main, api=extremes, result=ExtremesResult, docs="extremes.md",
    help="numerical stability at the extremes of a scene",
    description="Run every extreme case of the scene's spec with every solver: each ends "
                "within tolerance of an independent check (energy balance, a second solver, a "
                "closed form) or with an honest status (diverged / unstable / singular / "
                "timeout) and the time and reason.",
    args=(SCENE,
          arg("--solver", action="append", default=[], metavar="NAME",
              help="run this solver; repeat for several (default: every solver)"),
          arg("--all", action="store_true",
              help="include the long cases (e.g. a 1000 s horizon) and the long runs of some "
                   "solvers (an engine at the step that resolves the case)"),
          arg("--strict", action="store_true",
              help="exit 1 on any FAILED, error or stale declaration (a case declaring a "
                   "solver's known failure whose run now passes); a declared FAILED (known), "
                   "explained in the scene file, does not count"),
          TIMEOUT, *RESULT_OUT, JSON))
