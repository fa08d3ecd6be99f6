"""`xval campaign`: the process pool, resume after a stop, per-job wall-clock limits, bad input.

The physics is asserted elsewhere; here the numbers that count are the two engines agreeing
(their verdicts) and the job bookkeeping a user scripts against (summary.json).
"""
import json

import pytest

from tests.conftest import xval


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
    assert s["n_skipped"] == 2, (s["reused"], se)
    assert json.loads(so)["cases"][0]["runs"][0]["wall_s"] == rotor["runs"][0]["wall_s"]


def test_campaign_bad_timeout_is_one_line_exit_2(tmp_path):
    camp = _campaign(tmp_path, [{**CASES[0], "timeout_s": -1}])
    rc, so, se = xval("campaign", camp, "--out", str(tmp_path / "logs"))
    assert rc == 2 and "timeout_s" in se and len(se.strip().splitlines()) == 1
    assert not (tmp_path / "logs").exists()


def _final_omega(summary, case="spin"):
    runs = next(c for c in summary["cases"] if c["case"] == case)["runs"]
    return {r["solver"]: r["final"]["omega_norm"] for r in runs}


def test_resume_reruns_a_job_whose_inputs_changed_and_reuses_it_when_they_come_back(tmp_path):
    """The stale-resume defect: a job counted as done when a file with its case and solver name
    existed, so torque 3.0 was reported with the trajectories of torque 1.5. Results are now
    stored under the digest of their inputs. Over 1 s the rotor barely tilts, so |ω| is close
    to the free ramp M·t/I_p (I_p = m R²/2 = 0.15625 kg·m²): 9.6 and 19.2 rad/s; measured
    9.5908 and 19.1735 (deviation 1.0e-3 and 1.4e-3 relative, the tilt's share)."""
    out = str(tmp_path / "logs")
    finals = []
    for torque in (1.5, 3.0, 1.5):
        camp = _campaign(tmp_path, [{"name": "spin", "scene": "rotor-spinup",
                                     "set": {"torque": torque, "t_end": 1},
                                     "solvers": ["euler-vector", "quaternion"]}])
        rc, so, se = xval("campaign", camp, "--out", out, "--json", "--workers", "1")
        assert rc == 0, se
        s = json.loads(so)
        finals.append((s["n_reused"], _final_omega(s)))
        for w in finals[-1][1].values():
            assert w == pytest.approx(torque * 1.0 / (5 * 0.25 ** 2 / 2), rel=5e-3)
    assert [n for n, _ in finals] == [0, 0, 2]          # changed: rerun; back: reused
    assert finals[2][1] == finals[0][1]
    case = next(c for c in s["cases"] if c["case"] == "spin")
    assert sorted(case["reused"]) == ["euler-vector", "quaternion"]
    assert "Reused stored results for spin" in (tmp_path / "logs" /
                                                 "report.md").read_text()


def _toml(tmp_path, text):
    f = tmp_path / "camp.toml"
    f.write_text(text)
    return str(f)


SWEEP_TOML = """# a comment: TOML campaign files may explain themselves
name = "t"

[[cases]]
name = "spin"
scene = "rotor-spinup"
solvers = ["euler-vector"]
set = {{ t_end = 0.5 }}
sweep = {{ {sweep} }}
"""


@pytest.mark.parametrize("text, words", [
    ("name = \"t\"\n[[cases]\nscene = 1\n", ["camp.toml", "TOML syntax", "line 2"]),
    (SWEEP_TOML.format(sweep="nope = [1, 2]"), ["camp.toml", "cases[0].sweep", "nope"]),
    (SWEEP_TOML.format(sweep="torque = [1.0, 2e4]"),
     ["camp.toml", "cases[0].sweep.torque", "outside the admissible range"]),
    (SWEEP_TOML.format(sweep="torque = []"), ["camp.toml", "cases[0].sweep.torque"]),
    (SWEEP_TOML.format(sweep="torque = [1]").replace("rotor-spinup", "rotor-x"),
     ["cases[0].scene", "unknown scene"]),
    (SWEEP_TOML.format(sweep="torque = [1]").replace('"euler-vector"', '"nope"'),
     ["cases[0].solvers", "unknown solver"]),
    (SWEEP_TOML.format(sweep="torque = [1]").replace("scene = ", "scen = "),
     ["cases[0].scen", "unknown key"]),
    (SWEEP_TOML.format(sweep="torque = [1]").replace("t_end = 0.5", "t_end = -1"),
     ["cases[0].set.t_end"]),
    ("name = \"t\"\n", ["camp.toml", "cases", "missing"]),
    # 5e8 samples × 8 arrays × 8 bytes per point = 30 GiB against the 2 GiB budget
    (SWEEP_TOML.format(sweep="torque = [1]").replace("t_end = 0.5", "t_end = 0.5, "
                                                      "output_dt = 1e-9"),
     ["cases[0] sweep point spin/torque=1", "exceeds the budget", "--max-output-gib"]),
])
def test_malformed_campaign_file_is_one_line_exit_2_and_writes_nothing(tmp_path, text, words):
    rc, so, se = xval("campaign", _toml(tmp_path, text), "--out", str(tmp_path / "logs"))
    assert rc == 2 and so == ""
    lines = se.strip().splitlines()
    assert len(lines) == 1, se
    for w in words:
        assert w in lines[0], lines[0]
    assert not (tmp_path / "logs").exists()


def test_json_syntax_error_names_the_line(tmp_path):
    f = tmp_path / "camp.json"
    f.write_text('{"name": "t",\n "cases": [\n {"scene": "rotor-spinup",}]}')
    rc, so, se = xval("campaign", str(f), "--out", str(tmp_path / "logs"))
    assert rc == 2 and len(se.strip().splitlines()) == 1
    assert "camp.json" in se and "line 3" in se
    assert not (tmp_path / "logs").exists()


def test_the_code_digest_follows_a_model_and_what_it_imports_only(tmp_path, monkeypatch):
    """A result is reused only while its model's code is unchanged: the digest covers the
    leaf and the project modules it imports (here the shared rotor driver two imports away),
    not an unrelated model. (After the rooms move it read no file at all — the empty digest —
    so a model fix did not rerun stored jobs.)"""
    import hashlib
    import shutil

    from compare.workflows import digest as campaign  # the store's digest (the planner's)
    for pkg in campaign.PROJECT_PACKAGES:
        shutil.copytree(campaign.ROOT / pkg, tmp_path / pkg,
                        ignore=shutil.ignore_patterns("__pycache__"))
    monkeypatch.setattr(campaign, "ROOT", tmp_path)
    monkeypatch.setattr(campaign, "_CODE", {})
    leaf = {"custom_models.rotor.quaternion"}

    def digest_after(edit=None):
        if edit:
            f = tmp_path / edit
            f.write_text(f.read_text() + "\n# edited\n")
        campaign._CODE.clear()
        return campaign.code_digest(leaf)
    d0 = digest_after()
    assert d0 != hashlib.sha256(b"").hexdigest()
    d1 = digest_after("custom_models/integrators/dense.py")      # leaf → model → dense
    assert d1 != d0
    assert digest_after("custom_models/press/model.py") == d1
    # the same process, the leaf now importing the press model: its imports are read anew
    # (they are kept per source text), so the press model counts from then on
    leaf_src = tmp_path / "custom_models/rotor/quaternion.py"
    leaf_src.write_text(leaf_src.read_text() + "\nfrom ..press import model as _press  # noqa\n")
    d2 = digest_after()
    assert d2 != d1
    assert digest_after("custom_models/press/model.py") != d2
