"""`xval calibrate`: the verdicts' false-alarm rate and the error bars' coverage over parameter
sets drawn from the scene's sampling region."""
from __future__ import annotations

from collections.abc import Callable

from ..output.folders import claim_out
from ..results import CalibrationResult
from ..workflows.inputs import positive_int
from ..workflows.plan import names
from . import Command, arg
from .common import (
    JSON,
    RESULT_OUT,
    SCENE,
    SETS,
    SOLVERS,
    STRICT,
    answered,
    log,
    overrides,
    parse_sets,
    quiet,
    stdout_to_stderr,
)
from .common import positive_int as positive_int_arg


def calibrate(scene: str, samples: int = 20, seed: int = 0, solvers=None, *, out=None,
              force: bool = False, params: dict | None = None, spread: float = 2.0,
              campbell: bool = False, log: Callable | None = None, **kw) -> CalibrationResult:
    """Calibration (`xval calibrate`): `samples` parameter sets drawn with `seed` from the
    scene's sampling region (`Calibration`) — the parameters given in `params` or as keywords
    (`--set`) held at their value in every set, the default axes reaching default/`spread` …
    default·`spread` — every solver (or those named) run at each with its error estimate, and
    with `campbell` each set's Campbell sweep judged as `xval modes` judges it.
    Returns a `CalibrationResult` (`s["disagree"]`, `s["coverage"]`, `s["sharpness"]`,
    `s["widest_window"]`, `s["skipped"]`), saved in the folder `out` when given (`claim_out`'s
    rule)."""
    from ..workflows.calibrate import calibrate as run_calibration
    if out is not None:
        claim_out(str(out), "calibration", force)
    res = run_calibration(scene, positive_int("samples", samples), seed=int(seed),
                          solvers=names(solvers), log=log or quiet,
                          held=overrides(params, kw), spread=spread, campbell=campbell)
    if out is not None:
        res.save(out)
    return res


def main(args) -> int:
    with stdout_to_stderr():
        r = calibrate(args.scene, args.samples, args.seed, args.solver, out=args.out,
                      force=args.force, params=parse_sets(args.set), spread=args.spread,
                      campbell=args.campbell, log=log)
    return answered(args, r)


COMMAND = Command(
    "calibrate", order=10, main=main, api=calibrate, result=CalibrationResult,
    docs="calibrate.md",
    help="false alarms and error-bar coverage over parameter sets drawn from the scene's "
         "sampling region",
    description="Draw parameter sets from the scene's sampling region, run every solver with "
                "its error estimate at each, and report the comparisons that disagree (none "
                "expected), the error bars' coverage and sharpness against each solver's far "
                "tighter run, the widest window (bound / deviation) and the solvers that "
                "stopped.",
    args=(SCENE, SOLVERS, SETS,
          arg("--samples", type=positive_int_arg("--samples"), default=20, metavar="N",
              help="parameter sets to draw (default 20)"),
          arg("--seed", type=int, default=0, metavar="S", help="random seed (default 0)"),
          arg("--spread", type=float, default=2.0, metavar="F",
              help="how far a parameter the scene declares no range for is drawn: "
                   "default/F … default·F within its admissible range (default 2; > 1)"),
          arg("--campbell", action="store_true",
              help="also judge each set's Campbell sweep as `xval modes` does (every sampled "
                   "speed pairwise, the critical speeds): its disagreements are false alarms "
                   "too"),
          *RESULT_OUT, JSON, STRICT))
