"""`xval bench SCENE --identify`: xval's fit and a plain least_squares loop over the same
solver, timed on one synthetic record (issue 50, item 5); bad use is one line, exit 2."""
import json

import pytest

from compare.results import BenchResult, Result
from compare.workflows import bench_identify
from tests.conftest import xval

SCENE = "bearing-rotor"
# the truth: the parameters the record is synthesised at (the start is the scene's default
# angle 0, so the plain loop has to find the angle)
TRUTH = {"defect_height": 2e-5, "defect_width": 0.1, "defect_angle": 0.3}
SETS = ["--set", "t_end=0.5", "--set", "defect_angle=0.3"]


def test_bench_identify_reports_both_fits(tmp_path):
    out = tmp_path / "b"
    rc, stdout, err = xval("bench", SCENE, "--identify", "--repeats", "1", "--solver",
                           "quaternion", *SETS, "--out", str(out), "--json")
    assert rc == 0, err
    obj = json.loads((out / "bench.json").read_text())
    assert json.loads(stdout)["rows"] == obj["rows"]
    assert [r["kind"] for r in obj["rows"]] == ["identify", "least_squares"]
    fit, plain = obj["rows"]
    assert fit["solver"] == plain["solver"] == "quaternion"
    assert obj["unknowns"] == list(TRUTH) and obj["record"]["t_end"] == pytest.approx(0.5)
    # xval's fit recovers the synthesis parameters within its 95 % intervals, at the noise
    assert fit["converged"] and fit["identifiable"] == [True] * 3
    for name, v, h in zip(fit["unknowns"], fit["values"], fit["half_width"]):
        assert abs(v - TRUTH[name]) <= h, (name, v, h)
    assert fit["truth_inside"] == [True] * 3 and 0.8 < fit["chi2_dof"] < 1.2
    assert fit["runs"] > 0 and fit["wall_s"] > 0
    # the plain loop is reported as it ended (its runs, cost, estimates), converged or not
    assert plain["runs"] > 0 and plain["wall_s"] > 0 and len(plain["values"]) == 3
    assert isinstance(plain["converged"], bool) and isinstance(plain["reached_truth"], bool)
    assert plain["reached_truth"] == all(
        abs(v - TRUTH[n]) <= h for n, v, h in zip(fit["unknowns"], plain["values"],
                                                  fit["half_width"]))
    assert obj["ratio"]["wall"] == pytest.approx(fit["wall_s"] / plain["wall_s"])
    assert any(x.startswith("least_squares quaternion") for x in obj["summary_lines"])
    report = (out / "report.md").read_text()
    assert "| identify | quaternion |" in report and "| least_squares | quaternion |" in report
    loaded = Result.load(out)                       # the bench folder reads back
    assert isinstance(loaded, BenchResult)
    assert loaded.summary_lines() == obj["summary_lines"]


def test_an_unconverged_plain_loop_is_still_reported(tmp_path, monkeypatch):
    real = bench_identify.least_squares
    monkeypatch.setattr(bench_identify, "least_squares",
                        lambda *a, **k: real(*a, max_nfev=2, **k))
    obj = bench_identify.run_identify_bench(
        SCENE, ["quaternion"], {"t_end": "0.5", "defect_angle": "0.3",
                                "defect_width": "0.1"}, repeats=1,
        log=lambda *a: None)
    plain = obj["rows"][-1]
    assert plain["kind"] == "least_squares" and plain["converged"] is False
    assert plain["reached_truth"] is False and len(plain["values"]) == 3
    assert "not converged" in obj["summary_lines"][2]


@pytest.mark.parametrize("extra, said", [
    (["rotor-spinup", "--identify"], "declares nothing to identify"),
    ([SCENE, "--identify", "--points", "10"], "--identify: not with --points"),
    ([SCENE, "--identify", "--vary", "mu=0.01,0.02"], "--identify: not with --vary"),
])
def test_bad_use_is_one_line_exit_2(tmp_path, extra, said):
    rc, _, err = xval("bench", *extra, "--out", str(tmp_path / "o"))
    assert rc == 2 and said in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "o").exists()
