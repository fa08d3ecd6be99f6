"""pytest plugin (entry point `pytest11: xval`, active wherever xval is installed).

- fixture `xval_run`: `xval_run(SCENE, **parameters)` runs a scene through the
  Python API once per test session for each distinct set of arguments (later calls get the
  cached result); the run's trajectories and result.json go to a session temporary folder.
- `assert_agree(result, channels=...)` (also `xval.assert_agree`): fails with the verdict
  table of the pairs that disagree — deviation, error estimates, allowance, what decided.
- `assert_matches_baseline(result, baseline)`: fails with the `xval diff` table when the
  result moved beyond its error bars against a baseline from `xval baseline save`.

Imported by pytest at start-up in every project of the environment: it imports nothing heavy
until a test uses it.
"""
import pytest


def assert_agree(result, channels=None):
    from .api import assert_agree as check
    __tracebackhide__ = True
    check(result, channels)


def assert_matches_baseline(result, baseline):
    """Fails with the diff table when `result` (an `xval.run` result, or a run or campaign
    folder) moved beyond its own error bars against `baseline` (a file written by `xval
    baseline save`, or a folder), as `xval diff BASELINE RESULT` would. A missing baseline
    file is written from the result and the test skipped: review it and commit it."""
    from .workflows.diff import check_baseline
    __tracebackhide__ = True
    folder = getattr(getattr(result, "result", None), "out_dir", None) or result
    table, written = check_baseline(folder, baseline)
    if written:
        pytest.skip(written)
    if table:
        pytest.fail(f"moved against the baseline {baseline}:\n{table}", pytrace=False)


@pytest.fixture(scope="session")
def xval_run(tmp_path_factory):
    """A function `(scene, solvers=None, settings=None, **keywords) -> TimeResult` that runs
    each distinct call once per session (keywords as `xval.run`'s; `out` defaults to a session
    temporary folder, `record` to False: pass `record=True` for the recording and report)."""
    from .api import run
    cache = {}

    def runner(scene, solvers=None, settings=None, **kw):
        key = repr((scene, solvers, settings, sorted(kw.items())))
        if key not in cache:
            kw.setdefault("out", tmp_path_factory.mktemp("xval"))
            kw.setdefault("record", False)
            cache[key] = run(scene, solvers, settings, **kw)
        return cache[key]
    return runner
