"""The command-line contract (contract.md): JSON shape, exit statuses, bad input, recordings."""
import json

import numpy as np
import pytest

from compare.output.recording import load_scalar_series
from compare.scenes import get_scene
from tests.conftest import xval

CHANNELS = get_scene("rotor-spinup").channels


def test_run_json_has_every_contract_field(rotor_default_run):
    obj, _ = rotor_default_run
    assert obj["scene"] == "rotor-spinup"
    assert obj["params"]["torque"] == 1.5
    assert {r["solver"] for r in obj["runs"]} == {"euler-vector", "quaternion", "exudyn",
                                                  "mujoco"}
    for r in obj["runs"]:
        assert r["status"] == "ok"
        assert set(r["final"]) == set(CHANNELS)
        for key in ("wall_s", "settings", "stats", "energy_residual", "invariants", "trajectory"):
            assert key in r
    assert obj["recording"].endswith("run.rrd")


def test_trajectory_files_follow_the_contract(rotor_default_run):
    obj, _ = rotor_default_run
    grids = []
    for r in obj["runs"]:
        with np.load(r["trajectory"]) as z:
            assert set(CHANNELS) <= set(z.files)
            grids.append(z["t"])
            assert z["omega_norm"][-1] == pytest.approx(r["final"]["omega_norm"], rel=1e-15)
    for g in grids[1:]:
        np.testing.assert_array_equal(g, grids[0])          # one output grid for all solvers
    assert grids[0][1] - grids[0][0] == pytest.approx(0.01)


def test_recording_reads_back_with_every_solver_channel(rotor_default_run):
    obj, _ = rotor_default_run
    for r in obj["runs"]:
        with np.load(r["trajectory"]) as z:
            for ch in ("omega_norm", "tilt", "energy_balance"):
                t, v = load_scalar_series(obj["recording"], f"/{ch}/{r['solver']}")
                np.testing.assert_allclose(t, z["t"], atol=1e-9)
                np.testing.assert_array_equal(v, z[ch])     # scalars are stored as float64


@pytest.mark.parametrize("setting, word", [
    ("m=-1", "m"), ("l=0", "l"), ("k=nan", "k"), ("foo=1", "foo"), ("torque=abc", "torque"),
    ("gravity=1,2", "gravity"), ("R", "R"),
    ("output_dt=0.03", "output_dt")])
def test_bad_set_exits_2_with_one_line_and_writes_nothing(tmp_path, setting, word):
    out = tmp_path / "out"
    rc, so, se = xval("run", "rotor-spinup", "--set", setting, "--out", str(out))
    assert rc == 2
    assert so == ""
    lines = se.strip().splitlines()
    assert len(lines) == 1 and word in lines[0]
    assert not out.exists()


@pytest.mark.parametrize("args", [("run", "no-such-scene"), ("run", "rotor-spinup", "--solver",
                                  "nope"), ("run", "rotor-spinup", "--dt", "-1"),
                                  ("campaign", "missing-file.json"), ("modes", "rotor-spinup")])
def test_other_bad_input_exits_2(tmp_path, args):
    rc, so, se = xval(*args, "--out", str(tmp_path / "o"))
    assert rc == 2 and len(se.strip().splitlines()) == 1
    assert not (tmp_path / "o").exists()


def test_a_loop_that_cannot_close_is_bad_input(tmp_path):
    # y_B − y_A = 0.03·sin(−46.34°) − 0.015·sin(−64.1°) = −0.00821 m: a 5 mm rod cannot reach
    rc, so, se = xval("run", "press", "--set", "l2=0.005", "--out", str(tmp_path / "o"))
    assert rc == 2 and "l2" in se and len(se.strip().splitlines()) == 1
    assert not (tmp_path / "o").exists()


def test_list_and_show():
    rc, so, _ = xval("list")
    assert rc == 0 and "rotor-spinup" in so and "euler-vector" in so
    rc, so, _ = xval("show", "rotor-spinup", "--json")
    shown = {p["name"]: p for p in json.loads(so)["params"]}
    assert shown["k"]["default"] == 2000.0 and shown["k"]["unit"] == "N·m/rad"


def test_a_crashing_solver_is_recorded_and_hides_nothing(tmp_path, monkeypatch, capsys):
    """Exit 3, the crash recorded with its message, the other solver's result intact."""
    import sys
    import types

    from compare import cli, solvers
    broken = types.ModuleType("broken_leaf")
    broken.DEFAULT_SETTINGS, broken.INTEGRATORS = {"integrator": "x"}, ("x",)

    def simulate(params, t_out, settings):
        raise RuntimeError("model exploded")
    broken.simulate = simulate
    monkeypatch.setitem(sys.modules, "broken_leaf", broken)
    from compare.scenes.rotor import SPINUP
    monkeypatch.setitem(solvers.REGISTRY, "broken", solvers.Solver("broken", "test", "numpy"))
    monkeypatch.setitem(SPINUP.leaves, "broken", "broken_leaf")
    rc = cli.main(["run", "rotor-spinup", "--solver", "broken", "--solver", "quaternion",
                   "--set", "t_end=0.5", "--json", "--no-record", "--out", str(tmp_path)])
    obj = json.loads(capsys.readouterr().out)
    assert rc == 3
    runs = {r["solver"]: r for r in obj["runs"]}
    assert runs["broken"]["status"] == "error" and "model exploded" in runs["broken"]["message"]
    assert runs["quaternion"]["status"] == "ok"
    # 0.5 s of free spin-up from rest: |ω| = M t / I_p while the tilt is still ~0
    assert runs["quaternion"]["final"]["omega_norm"] == pytest.approx(1.5 * 0.5 / (5 * 0.25**2 / 2),
                                                                      rel=1e-3)


def test_rtol_on_fixed_step_solvers_keeps_their_step(tmp_path):
    """--rtol reaches only error-controlled integrators; fixed-step engines keep their step and
    still run instead of rejecting an unknown setting."""
    rc, so, se = xval("run", "press", "--solver", "mujoco", "--solver", "lagrange-exact",
                      "--rtol", "1e-9", "--set", "t_end=0.005", "--json", "--no-record",
                      "--out", str(tmp_path))
    assert rc == 0, se
    runs = {r["solver"]: r for r in json.loads(so)["runs"]}
    assert "rtol" not in runs["mujoco"]["settings"] and "--rtol ignored" in se
    assert runs["lagrange-exact"]["settings"]["rtol"] == 1e-9
    assert all(r["status"] == "ok" for r in runs.values())


def test_bench_vary_trades_a_model_parameter(tmp_path):
    """`xval bench --vary`: each solver's default settings at each value of a model parameter,
    errors against the reference (euler-vector, confirmed by quaternion) at the --set value. At
    the base value MuJoCo's error is its discretisation error (small); at k + 5 % the model
    itself moved."""
    rc, so, se = xval("bench", "rotor-spinup", "--set", "t_end=0.5", "--vary", "k=2000,2100",
                      "--solver", "mujoco", "--repeats", "1", "--json", "--out", str(tmp_path))
    assert rc == 0, se
    obj = json.loads(so)
    rows = {r["vary"]["k"]: r for r in obj["rows"]}
    assert obj["vary"] == {"name": "k", "values": ["2000", "2100"]}
    assert obj["reference"]["cross_check_rel"] < 1e-9
    assert rows[2000.0]["rel_error"] < 1e-6 < rows[2100.0]["rel_error"]


@pytest.mark.parametrize("vary", ["k", "k=", "nope=1,2", "k=-1", "t_end=1,2"])
def test_bench_bad_vary_is_one_line_exit_2(tmp_path, vary):
    rc, so, se = xval("bench", "rotor-spinup", "--vary", vary, "--out", str(tmp_path))
    assert rc == 2 and len(se.strip().splitlines()) == 1 and so == ""


def test_run_prints_its_answer_in_one_line(tmp_path):
    """After the comparisons, one line: how many agree (how many marginally) and the worst
    Δ/bound — the same counts and ratio the run's JSON holds."""
    rc, so, _ = xval("run", "rotor-spinup", "--set", "t_end=0.5", "--solver", "quaternion",
                     "--solver", "euler-vector", "--no-record", "--out", str(tmp_path / "o"))
    assert rc == 0
    line = next(x for x in so.splitlines() if "comparisons agree" in x)
    rc, js, _ = xval("run", "rotor-spinup", "--set", "t_end=0.5", "--solver", "quaternion",
                     "--solver", "euler-vector", "--json", "--out", str(tmp_path / "o"))
    comps = json.loads(js)["comparisons"]
    n = len(comps)
    assert line.startswith(f"{sum(c['verdict'] == 'agree' for c in comps)} of {n} comparisons "
                           "agree")
    marginal = sum(c["shown"] == "agree (marginal)" for c in comps)
    assert (f"({marginal} marginal)" in line) == (marginal > 0)
    assert f"worst Δ/bound {max(c['ratio'] for c in comps):.2g}" in line


def test_modes_prints_frequencies_and_critical_speeds(tmp_path):
    """`xval modes` answers in the terminal: every mode in Hz and rad/s (ω = 2πf) with ζ and log
    dec, and the critical speeds in rad/s and rpm (60/2π of it) — the JSON's numbers."""
    import math
    rc, so, _ = xval("modes", "rotor-whirl", "--set", "spin=41.3", "--solver", "closed-form",
                     "--out", str(tmp_path / "o"))
    assert rc == 0
    rc, js, _ = xval("modes", "rotor-whirl", "--set", "spin=41.3", "--solver", "closed-form",
                     "--json", "--out", str(tmp_path / "o"))
    run = json.loads(js)["runs"][0]
    for label, f in zip(run["labels"], run["frequencies_hz"]):
        assert f"{label}: {f:.8g} Hz ({2 * math.pi * f:.8g} rad/s), ζ" in so, so
    crit = json.loads(js)["campbell"]["critical_speeds"]["closed-form"]
    line = next(x for x in so.splitlines() if x.startswith("closed-form critical speeds:"))
    for e in crit:
        w = e["speed_rad_s"]
        assert f"{e['name']} {w:.6g} rad/s ({w * 60 / (2 * math.pi):.6g} rpm)" in line
