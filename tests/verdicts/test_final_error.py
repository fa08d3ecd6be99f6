"""Each run's own error bar at t_end (`final_error` in `xval run --json`, printed as ± beside
each final value) against its true error: the custom solvers at a coarse fixed step measured
against Exudyn's adaptive run (an independent engine, ~1e-9 off at its defaults)."""
import json

import pytest

from tests.conftest import xval


def _finals(*args):
    rc, so, se = xval("run", "rotor-spinup", "--no-record", "--json", *args)
    assert rc == 0, se
    return {r["solver"]: r for r in json.loads(so)["runs"]}


@pytest.fixture(scope="module")
def runs():
    return _finals("--solver", "euler-vector", "--solver", "quaternion", "--dt", "0.01"), \
        _finals("--solver", "exudyn")["exudyn"]


@pytest.mark.parametrize("solver", ["euler-vector", "quaternion"])
@pytest.mark.parametrize("channel", ["spin_rate", "kinetic"])
def test_the_final_error_bar_bounds_the_true_error_and_is_not_vacuous(runs, solver, channel):
    coarse, truth = runs
    r = coarse[solver]
    true = abs(r["final"][channel] - truth["final"][channel])
    assert truth["final_error"][channel] < 1e-3 * true      # the truth is far tighter
    assert true <= r["final_error"][channel] <= 20 * true, (true, r["final_error"][channel])
