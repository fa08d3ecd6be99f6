"""The campaign's calibration jobs: the false-alarm rate beside the detection power. The
numbers asserted are `xval calibrate`'s own for the same scene, sets and seed (the standalone
command, run apart), and the campaign's refusal of a disagreement it is handed."""
import json

import pytest

from compare.results import Result
from compare.scenes import SCENES
from compare.workflows.campaign import prepare
from compare.workflows.campaign_plan import default_campaign
from tests.conftest import xval


def test_the_default_campaign_calibrates_each_scene_that_declares_it():
    jobs = [j for j in prepare(None).jobs if j.task == "calibration"]
    declared = {s.name: s.calibration.campaign for s in SCENES.values()
                if s.calibration and s.calibration.campaign}
    assert {j.scene: j.samples for j in jobs} == declared
    assert len(declared) >= 7           # every scene whose runs fit the campaign's budget
    assert default_campaign("long").get("calibrate") is None


def test_a_calibration_job_reports_what_xval_calibrate_reports_and_is_reused(tmp_path):
    camp = tmp_path / "camp.json"
    camp.write_text(json.dumps({"name": "c", "cases": [
        {"scene": "press", "set": {"t_end": 0.005}, "solvers": ["lagrange-exact"]}],
        "calibrate": [{"scene": "press-cycle", "samples": 1, "seed": 3}]}))
    rc, so, se = xval("campaign", str(camp), "--out", str(tmp_path / "a"), "--json")
    assert rc == 0, se
    (cal,) = json.loads(so)["calibration"]
    rc, so, se = xval("calibrate", "press-cycle", "--samples", "1", "--seed", "3", "--json")
    assert rc == 0, se
    alone = json.loads(so)
    for k in ("comparisons", "disagree", "coverage", "sharpness", "widest_window", "skipped"):
        assert cal[k] == alone[k], k
    rc, so, se = xval("campaign", str(camp), "--out", str(tmp_path / "a"), "--json")
    assert rc == 0, se
    assert "calibration/press-cycle" in json.loads(so)["reused"]


def test_a_calibration_that_disagrees_or_failed_is_a_campaign_problem():
    base = {"result": "campaign", "name": "c", "n_jobs": 1, "n_run": 1, "n_reused": 0,
            "n_failed": 0, "n_crashed": 0, "wall_s": 1.0, "cases": [], "maps": []}
    miss = {"sample": 0, "a": "a", "b": "b", "channel": "x", "ratio": 3.0, "params": {}}
    bad = Result.from_json({**base, "calibration": [
        {"scene": "press", "samples": 1, "comparisons": 4, "disagree": [miss],
         "coverage": 1.0, "sharpness": 0.5, "widest_window": 2.0, "skipped": []},
        {"scene": "press-cycle", "samples": 1, "error": "worker died"}]})
    assert len(bad.problems()) == 2
    assert "1 of 4 comparisons disagree" in bad.summary_lines()[-1]


@pytest.mark.parametrize("entry, words", [
    ({"scene": "press", "samples": 0}, "samples"),
    ({"scene": "press", "seed": -1}, "seed"),
    ({"scene": "press", "sets": 2}, "calibrate[0]"),
    ({"scene": "nosuch"}, "nosuch"),
])
def test_a_bad_calibrate_entry_is_one_line_exit_2(tmp_path, entry, words):
    camp = tmp_path / "camp.json"
    camp.write_text(json.dumps({"name": "c", "cases": [{"scene": "press"}],
                                "calibrate": [entry]}))
    rc, so, se = xval("campaign", str(camp), "--out", str(tmp_path / "o"))
    assert rc == 2 and len(se.strip().splitlines()) == 1 and words in se, se
    assert not (tmp_path / "o").exists()


def test_a_fresh_process_judges_a_campaign_with_calibrations(tmp_path):
    """The Result types load on first use: a fresh interpreter (as `xval campaign` is) must
    find the calibration's type when it judges the campaign (it crashed there once: the
    in-process tests had every type loaded already)."""
    import subprocess
    import sys
    (tmp_path / "summary.json").write_text(json.dumps({
        "result": "campaign", "name": "c", "n_jobs": 1, "n_run": 1, "n_reused": 0,
        "n_failed": 0, "n_crashed": 0, "wall_s": 1.0, "cases": [], "maps": [],
        "calibration": [{"scene": "press", "samples": 1, "comparisons": 4, "disagree": [],
                         "coverage": 1.0, "sharpness": 0.5, "widest_window": 2.0,
                         "skipped": []}]}))
    code = ("import sys; from compare.results.studies import CampaignResult; "
            "import json; r = CampaignResult(json.load(open(sys.argv[1]))); "
            "print(len(r.problems()), r.summary_lines()[-1])")
    out = subprocess.run([sys.executable, "-c", code, str(tmp_path / "summary.json")],
                         capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.startswith("0 calibration: 0 of 4 comparisons disagree")
