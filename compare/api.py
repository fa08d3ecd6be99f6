"""The Python API (`import xval`): the same engine as the `xval` command — every command's
function, from its module in compare/commands/ (the registry), under its own name. Every call
returns a `Result` (compare/results/); bad arguments raise `BadInput` with the command's
one-line message, before anything runs or is written.

Files: with `out=FOLDER` a call writes what the command writes into FOLDER itself (a run: the
.npz per solver, run.rrd, report.md with plots, result.json; FOLDER empty or an earlier result
of the same command, unless `force=True`).
Without `out` a run, modes, extremes, power, diff, bench or map result is held in memory and
nothing is written; a campaign (whose jobs hand their results back through its folder, to
resume from) uses the command's folder, logs/campaign/<name>. `result.save(path)` writes the
files then; `xval.load(path)` reads any of them back.
"""
from __future__ import annotations

from pathlib import Path

from .commands import COMMANDS, api_functions
from .errors import BadInput
from .results import Result
from .results.tables import disagreement_message
from .workflows.plan import per_solver_settings  # noqa: F401  (the API's documented helper)

globals().update(api_functions())


def load(path) -> Result:
    """A result saved by `.save(path)` or written by the command (a run, modes, bench,
    extremes, map, campaign, power or diff folder, its JSON file, or a baseline), read back
    as the type it was."""
    return Result.load(path)


# set by the pytest plugin's --xval-create-baselines: write a missing baseline
CREATE_BASELINES = {"on": False}


def assert_matches_baseline(result, baseline, create: bool = False):
    """Fails (AssertionError) with the diff table when `result` (an `xval.run` result, in
    memory or saved, or a run or campaign folder) moved beyond its own error bars against
    `baseline` (a file written by `xval baseline save`, or a folder), as `xval diff BASELINE
    RESULT` would. A missing baseline fails — a check with nothing to check against must not
    pass — unless told to create it (`create=True` or `pytest --xval-create-baselines`): then
    it is written from the result and the check fails once more, asking for it to be
    reviewed."""
    from .workflows.diff import check_baseline
    __tracebackhide__ = True
    if not Path(baseline).exists() and not (create or CREATE_BASELINES["on"]):
        raise AssertionError(f"baseline {baseline} is missing: create it with "
                             "assert_matches_baseline(..., create=True) or pytest "
                             "--xval-create-baselines, review it and commit it")
    table, written = check_baseline(result, baseline)
    if written:
        raise AssertionError(written)
    if table:
        raise AssertionError(f"moved against the baseline {baseline}:\n{table}")


def assert_agree(result, channels=None):
    """Assert that every comparison of `result` (a run or modes result) on `channels`
    (default: all) agrees; the failure message is the verdict table of the pairs that do
    not — deviation, both solvers' error estimates, the allowance, what decided."""
    if isinstance(channels, str):
        channels = [channels]
    msg = disagreement_message(result, channels)
    if msg:
        raise AssertionError(msg)


XvalError = BadInput            # one exception type for bad arguments; either name catches it
# the Result types every command returns, and the base and the scene's description
RESULTS = {t.__name__: t for t in (Result, *(c.result for c in COMMANDS.values() if c.result))}
globals().update(RESULTS)

__all__ = [*api_functions(), "load", "assert_agree", "assert_matches_baseline",
           "per_solver_settings", "BadInput", "XvalError", *RESULTS]
