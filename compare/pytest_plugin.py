"""pytest plugin (entry point `pytest11: xval`, active wherever xval is installed).

- fixture `xval_run`: `xval_run(SCENE, **parameters)` runs a scene through the
  Python API once per test session for each distinct set of arguments (later calls get the
  cached result); the run's trajectories and result.json go to a session temporary folder.
- `--xval-create-baselines`: `xval.assert_matches_baseline` (compare/api.py) writes a missing
  baseline (the test still fails once: review it and commit it).

The assertions (`xval.assert_agree`, `xval.assert_matches_baseline`) live in compare/api.py, so
`import xval` needs no pytest. Imported by pytest at start-up in every project of the
environment: it imports nothing heavy until a test uses it.
"""
import pytest


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
    from .api import CREATE_BASELINES
    CREATE_BASELINES["on"] = bool(config.getoption("--xval-create-baselines", False))
