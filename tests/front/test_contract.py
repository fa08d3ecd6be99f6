"""The leaf contract as code and the adapter's promises: settings checked for every solver
before any runs, a leaf's unexpected exception recorded as `error` (never bad input), results
validated, frequency leaves that can only approximate answer with a note."""
import json
import sys
import types

import numpy as np
import pytest

from compare import cli, solvers
from compare.contract import LeafResult, canonical_integrator, merge_settings
from compare.scenes.rotor import SPINUP


def test_bad_step_for_one_solver_stops_everything_before_anything_runs(tmp_path, capsys):
    # rtol 2 is no tolerance for euler-vector (mujoco, fixed-step, ignores it); mujoco (listed
    # first) must not run. (A fixed step that does not divide the output step is good input:
    # the custom drivers interpolate the grid.)
    rc = cli.main(["run", "rotor-spinup", "--solver", "mujoco", "--solver", "euler-vector",
                   "--rtol", "2", "--out", str(tmp_path)])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2
    assert len(err) == 1 and "euler-vector" in err[0] and "rtol" in err[0]
    assert not any(tmp_path.rglob("*"))                 # nothing written


def _leaf(exc):
    leaf = types.ModuleType("faulty_leaf")
    leaf.DEFAULT_SETTINGS, leaf.INTEGRATORS = {"integrator": "x"}, ("x",)

    def simulate(params, t_out, settings):
        raise exc
    leaf.simulate = simulate
    return leaf


@pytest.mark.parametrize("exc", [ValueError("a bug, not bad input"), KeyError("torque")])
def test_a_leaf_exception_is_an_error_and_the_others_stand(exc, tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "faulty_leaf", _leaf(exc))
    monkeypatch.setitem(solvers.REGISTRY, "faulty", solvers.Solver("faulty", "test", "numpy"))
    monkeypatch.setitem(SPINUP.leaves, "faulty", "faulty_leaf")
    rc = cli.main(["run", "rotor-spinup", "--solver", "quaternion", "--solver", "faulty",
                   "--set", "t_end=0.2", "--set", "eccentricity=0", "--json", "--no-record",
                   "--out", str(tmp_path)])
    runs = {r["solver"]: r for r in json.loads(capsys.readouterr().out)["runs"]}
    assert rc == 3
    assert runs["faulty"]["status"] == "error"
    assert type(exc).__name__ in runs["faulty"]["message"]
    # a centred rotor spun from rest about its upright axis: |ω| = M t / I_p exactly
    assert runs["quaternion"]["status"] == "ok"
    assert runs["quaternion"]["final"]["omega_norm"] == pytest.approx(1.5 * 0.2 / 0.15625,
                                                                      rel=1e-9)


def test_a_result_breaking_the_contract_is_an_error(monkeypatch):
    leaf = types.ModuleType("short_leaf")
    leaf.DEFAULT_SETTINGS, leaf.INTEGRATORS = {"integrator": "x"}, ("x",)
    leaf.simulate = lambda p, t, s: LeafResult(channels={c: np.zeros(3) for c in SPINUP.channels})
    monkeypatch.setitem(sys.modules, "short_leaf", leaf)
    monkeypatch.setitem(solvers.REGISTRY, "short", solvers.Solver("short", "test", "numpy"))
    monkeypatch.setitem(SPINUP.leaves, "short", "short_leaf")
    tr = solvers.simulate(SPINUP, solvers.get_solver("short"), SPINUP.resolve({"t_end": 0.1}),
                          {"integrator": "x"})
    assert tr.status == "error" and "shape" in tr.reason


def test_eccentric_whirl_at_spin_answers_with_notes(tmp_path, capsys):
    rc = cli.main(["modes", "rotor-whirl", "--set", "eccentricity=0.005", "--set", "spin=10",
                   "--json", "--out", str(tmp_path)])
    obj = json.loads(capsys.readouterr().out)
    assert rc == 0
    runs = {r["solver"]: r for r in obj["runs"]}
    assert set(runs) == {"closed-form", "euler-vector", "exudyn", "mujoco"}
    for r in runs.values():
        assert r["status"] == "ok" and any("approximate" in n for n in r["notes"])


def test_integrator_spellings_and_settings_merge():
    assert canonical_integrator("rk44") == "rk4"
    assert canonical_integrator("generalized-alpha") == "generalized_alpha"
    assert canonical_integrator("trapezoidal-index2") == "trapezoidal"
    assert canonical_integrator("ode23") == "rk23"
    s = merge_settings({"integrator": "RK44", "rho_inf": 0.7}, {"integrator": "rk4", "dt": 1e-3,
                       "spectral_radius": 0.8}, ("rk4",))
    assert s == {"integrator": "rk4", "dt": 1e-3, "spectral_radius": 0.7}
    with pytest.raises(ValueError, match="unknown settings"):
        merge_settings({"dtt": 1}, {"integrator": "rk4", "dt": 1e-3}, ("rk4",))


def test_an_engine_that_swallows_the_wall_clock_alarm_still_ends_timeout(monkeypatch):
    """Exudyn turns an exception raised in a user function into its own error; the adapter
    remembers that its alarm fired (a leaf double that catches everything, like an engine)."""
    import time as _time
    leaf = types.ModuleType("swallowing_leaf")
    leaf.DEFAULT_SETTINGS, leaf.INTEGRATORS = {"integrator": "x"}, ("x",)

    def simulate(params, t_out, settings):
        try:
            _time.sleep(2.0)
        except BaseException:            # noqa: BLE001 - what an engine's user-function wrapper does
            pass
        return LeafResult(channels={c: np.zeros(len(t_out)) for c in SPINUP.channels},
                          status="diverged", t_fail=0.0, reason="engine error")
    leaf.simulate = simulate
    monkeypatch.setitem(sys.modules, "swallowing_leaf", leaf)
    monkeypatch.setitem(solvers.REGISTRY, "swallow", solvers.Solver("swallow", "test", "numpy"))
    monkeypatch.setitem(SPINUP.leaves, "swallow", "swallowing_leaf")
    tr = solvers.simulate(SPINUP, solvers.get_solver("swallow"), SPINUP.resolve({"t_end": 0.1}),
                          {"integrator": "x"}, timeout_s=0.2)
    assert tr.status == "timeout"


def test_a_plugin_leaf_returning_the_old_modes_name_still_validates():
    """`compare.contract.ModesResult` (the name earlier leaves and plug-ins import) is the
    leaf-level `LeafModes`, not the API's `ModesResult`: such a leaf's return is coerced and
    validated as before."""
    from compare.contract import LeafModes, ModesResult
    res = LeafModes.coerce(ModesResult(frequencies_hz=np.array([1.0, 2.0]), labels=["a", "b"]))
    assert res.validate() is None and list(res.labels) == ["a", "b"]
    assert ModesResult(frequencies_hz=np.array([1.0]), labels=[]).validate() == \
        "1 frequencies but 0 labels"
