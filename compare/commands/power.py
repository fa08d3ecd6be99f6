"""`xval power`: the detection power of a scene's verdicts."""
from __future__ import annotations

from collections.abc import Callable

from ..results import PowerResult
from ..workflows.inputs import positive
from ..workflows.plan import names
from . import Command, arg
from .common import (
    STUDY,
    TIMEOUT,
    answered,
    log,
    overrides,
    parse_sets,
    quiet,
    stdout_to_stderr,
)


def power(scene: str, solvers=None, *, parameters=None, timeout=None,
          params: dict | None = None, log: Callable | None = None, **kw) -> PowerResult:
    """Detection power (`xval power`): for each continuous physical parameter and each solver,
    the smallest relative change ε* reaching that solver only that turns an agreeing verdict
    into disagree. Returns a `PowerResult` (`s["power"]`, `s["summary"]`)."""
    from ..workflows.power import run_power
    return run_power(scene, overrides(params, kw), names(solvers), list(parameters or []),
                     positive("timeout", timeout), log=log or quiet)


def main(args) -> int:
    with stdout_to_stderr():
        r = power(args.scene, args.solver, parameters=args.parameter, timeout=args.timeout,
                  params=parse_sets(args.set), log=log)
    return answered(args, r, r.data)


COMMAND = Command(
    "power", order=9, main=main, api=power, result=PowerResult, docs="power.md",
    help="detection power: the smallest error of one solver's parameter that a verdict sees",
    description="For each physical parameter and each solver in turn, the smallest relative "
                "change of that parameter reaching that solver only that turns an agreeing "
                "verdict into disagree (finite-difference estimate, one confirming run, "
                "bisection where the response is not linear).",
    args=(*STUDY,
          arg("--parameter", action="append", default=[], metavar="NAME",
              help="only this parameter; repeatable (default: every continuous physical "
                   "parameter of the scene)"),
          TIMEOUT))
