"""`xval campaign`: the process pool, resume after a stop, per-job wall-clock limits, bad input.

The physics is asserted elsewhere; here the numbers that count are the two engines agreeing
(their verdicts) and the job bookkeeping a user scripts against (summary.json).
"""
import json

from conftest import xval


def _campaign(tmp_path, cases):
    f = tmp_path / "camp.json"
    f.write_text(json.dumps({"name": "t", "cases": cases}))
    return str(f)


CASES = [
    {"name": "rotor", "scene": "rotor-spinup", "set": {"t_end": 0.5},
     "solvers": ["exudyn", "mujoco"]},
    # 2 s of MuJoCo deployment takes ~4 s of wall time: stopped at 0.5 s
    {"name": "sail-cut", "scene": "sail-deploy", "set": {"t_end": 2}, "solvers": ["mujoco"],
     "timeout_s": 0.5},
]


def test_campaign_runs_resumes_and_stops_jobs_at_their_time_limit(tmp_path):
    camp = _campaign(tmp_path, CASES)
    out = str(tmp_path / "logs")
    rc, so, se = xval("campaign", camp, "--out", out, "--json", "--workers", "2")
    assert rc == 0, se
    s = json.loads(so)
    assert s["n_jobs"] == 3 and s["n_skipped"] == 0 and s["n_crashed"] == 0
    by_case = {c["case"]: c for c in s["cases"]}
    rotor = by_case["rotor"]
    assert [r["status"] for r in rotor["runs"]] == ["ok", "ok"]
    assert rotor["comparisons"] and all(c["verdict"] == "agree" for c in rotor["comparisons"])
    cut = by_case["sail-cut"]["runs"][0]
    assert cut["status"] == "timeout" and "0.5 s" in cut["reason"]
    # resume: finished jobs are kept, the timed-out one is tried again
    rc, so, se = xval("campaign", camp, "--out", out, "--json")
    assert rc == 0, se
    s = json.loads(so)
    assert s["n_skipped"] == 2
    assert json.loads(so)["cases"][0]["runs"][0]["wall_s"] == rotor["runs"][0]["wall_s"]


def test_campaign_bad_timeout_is_one_line_exit_2(tmp_path):
    camp = _campaign(tmp_path, [{**CASES[0], "timeout_s": -1}])
    rc, so, se = xval("campaign", camp, "--out", str(tmp_path / "logs"))
    assert rc == 2 and "timeout_s" in se and len(se.strip().splitlines()) == 1
    assert not (tmp_path / "logs").exists()
