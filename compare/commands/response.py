"""`xval response`: the steady unbalance response vs spin, frequency domain against time
domain — the worked example of a study as one unit (ARCHITECTURE.md, "Add a study"): this
module (arguments, API, command line), its workflow (compare/workflows/response.py), its Result
(compare/results/response.py) and its page (docs/commands/response.md)."""
from __future__ import annotations

from collections.abc import Callable

from ..output.folders import claim_out
from ..results.response import ResponseResult
from ..workflows.inputs import positive_int
from ..workflows.plan import names
from . import Command, arg
from .common import (
    RESULT_OUT,
    STRICT,
    STUDY,
    answered,
    log,
    overrides,
    parse_sets,
    quiet,
    result_folder,
    stdout_to_stderr,
)
from .common import positive_int as positive_int_arg


def response(scene: str, solvers=None, *, speeds: int = 24, out=None,
             params: dict | None = None, log: Callable | None = None, force: bool = False,
             **kw) -> ResponseResult:
    """The steady unbalance response vs spin through the first critical speed (`xval
    response`): every solver that takes the unbalance into its linear model (frequency
    domain) and the scene's time solvers at constant spin (time domain), judged speed by speed
    on amplitude and phase; peaks, Q, half-power ζ. `out`: the folder its files are written
    into (empty or an earlier response, unless `force`). Returns a `ResponseResult`."""
    from ..workflows.response import run_response
    n = positive_int("--speeds", speeds)
    if out is not None:
        claim_out(str(out), "response", force)
    res = run_response(scene, names(solvers), overrides(params, kw), n, log=log or quiet)
    if out is not None:
        res.save(out)
    return res


def main(args) -> int:
    out = result_folder(args)
    with stdout_to_stderr():
        r = response(args.scene, args.solver, speeds=args.speeds, out=out,
                     params=parse_sets(args.set), log=log, force=args.force)
    return answered(args, r)


COMMAND = Command(
    "response", order=5, main=main, api=response, result=ResponseResult, docs="response.md",
    help="unbalance response vs speed: frequency domain vs time domain",
    description="Steady unbalance response (amplitude and phase lag vs spin, through the "
                "first critical speed) from every solver that takes the unbalance into its "
                "linear model and from the time-domain solvers run at constant spin to steady "
                "state (1× fit), judged speed by speed against the error bars; peak, "
                "amplification factor Q, half-power ζ against the modal ζ; Bode and polar "
                "plots.",
    args=(*STUDY,
          arg("--speeds", type=positive_int_arg("--speeds"), default=24, metavar="N",
              help="number of speeds, half of them within ±3ζ of the critical (default 24)"),
          *RESULT_OUT, STRICT))
