"""--strict: a CI can trust the exit status (0 nothing to refuse, 1 disagree / incomplete /
unconfirmed / FAILED, 2 bad input), on every command that gives verdicts.

The incomplete case is an independent fact, not our verdict: RK4 on the rotor with k = 1e7
(tilt frequency 2744 rad/s) at h = 5 ms has ω h = 13.7, beyond RK4's stability limit 2.78, so
it must end `diverged` (scene-rotor.md's extreme "rk4 above its stability limit")."""
import json

from tests.conftest import xval

UNSTABLE = ["--set", "k=1e7", "--set", "t_end=0.2", "--set", "output_dt=0.005",
            "--integrator", "rk4", "--dt", "5e-3", "--solver", "quaternion",
            "--solver", "euler-vector", "--no-record"]


def test_run_strict_refuses_a_solver_without_an_answer(tmp_path):
    rc, out, err = xval("run", "rotor-spinup", *UNSTABLE, "--out", str(tmp_path), "--json")
    assert rc == 0, err
    assert {r["status"] for r in json.loads(out)["runs"]} == {"diverged"}
    rc, out, err = xval("run", "rotor-spinup", *UNSTABLE, "--out", str(tmp_path), "--strict")
    assert rc == 1
    assert "--strict" in err and "diverged (incomplete)" in err


def test_campaign_strict_refuses_it_too(tmp_path):
    camp = tmp_path / "c.json"
    camp.write_text(json.dumps({"name": "s", "cases": [
        {"name": "rk4-unstable", "scene": "rotor-spinup", "solvers": ["quaternion"],
         "set": {"k": 1e7, "t_end": 0.2, "output_dt": 0.005}, "integrator": "rk4",
         "dt": 5e-3}]}))
    rc, out, err = xval("campaign", str(camp), "--out", str(tmp_path / "a"))
    assert rc == 0, err
    rc, out, err = xval("campaign", str(camp), "--out", str(tmp_path / "a"), "--strict")
    assert rc == 1 and "rk4-unstable: quaternion diverged" in err


def test_extremes_and_modes_strict_pass_when_there_is_nothing_to_refuse(tmp_path):
    rc, out, err = xval("modes", "rotor-whirl", "--out", str(tmp_path), "--strict", "--json")
    assert rc == 0, err
    assert all(c["verdict"] == "agree" for c in json.loads(out)["comparisons"])
