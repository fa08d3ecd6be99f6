"""pytest plugin (entry point `pytest11: xval`, active wherever xval is installed).

- fixture `xval_run`: `xval_run(SCENE, **parameters)` runs a scene through the
  Python API once per test session for each distinct set of arguments (later calls get the
  cached result); the run's trajectories and result.json go to a session temporary folder.
- `assert_agree(result, channels=...)` (also `xval.assert_agree`): fails with the verdict
  table of the pairs that do not agree (disagree, inconclusive, skipped) — deviation, error
  estimates, allowance, what decided.
- `assert_matches_baseline(result, baseline, create=False)`: fails with the `xval diff` table
  when the result moved beyond its error bars against a baseline from `xval baseline save`;
  fails (never skips) when the baseline is missing, unless `create=True` or the run has
  `--xval-create-baselines`.

Imported by pytest at start-up in every project of the environment: it imports nothing heavy
until a test uses it.
"""
import pytest


def assert_agree(result, channels=None):
    from .api import assert_agree as check
    __tracebackhide__ = True
    check(result, channels)


_CREATE = {"baselines": False}     # set by --xval-create-baselines


def assert_matches_baseline(result, baseline, create: bool = False):
    """Fails with the diff table when `result` (an `xval.run` result, in memory or saved, or a
    run or campaign folder) moved beyond its own error bars against `baseline` (a file written
    by `xval baseline save`, or a folder), as `xval diff BASELINE RESULT` would. A missing
    baseline fails the test — a check with nothing to check against must not pass or skip —
    unless told to create it (`create=True` or `pytest --xval-create-baselines`): then it is written
    from the result and the test fails once more, asking for it to be reviewed."""
    from pathlib import Path

    from .workflows.diff import check_baseline
    __tracebackhide__ = True
    if not Path(baseline).exists() and not (create or _CREATE["baselines"]):
        pytest.fail(f"baseline {baseline} is missing: create it with "
                    "assert_matches_baseline(..., create=True) or pytest "
                    "--xval-create-baselines, review it and commit it", pytrace=False)
    table, written = check_baseline(result, baseline)
    if written:
        pytest.fail(written, pytrace=False)
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


def pytest_addoption(parser):
    parser.addoption("--xval-create-baselines", action="store_true",
                     help="xval: write a missing baseline of assert_matches_baseline (the test "
                          "still fails once: review the file and commit it)")


def pytest_configure(config):
    _CREATE["baselines"] = bool(config.getoption("--xval-create-baselines", False))
