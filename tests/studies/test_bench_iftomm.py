"""The IFToMM benchmark problems' own measures: the results file `xval run --out` writes per
solver (read back against the trajectory; its accuracy against the problem's reference computed
here from the reference values themselves), and `xval bench` measuring every rung by the
problem's error against that reference."""
import json
import re

import numpy as np
import pytest

from compare.analysis.trajectory import Trajectory
from compare.physics import andrews as andrews_phys
from compare.results import TimeResult
from compare.scenes import benchmarks_bricard as bricard_scene
from compare.scenes import get_scene

# a made-up motion of P3 [m] (closed forms: the test evaluates them at the reference's times)
P3_LAW = {"p3_x": lambda t: np.cos(0.7 * t), "p3_y": lambda t: -1.0 - 0.3 * np.sin(t) ** 2,
          "p3_z": lambda t: 1.0 - 0.05 * t}


def _trajectory(sc, params, solver, laws, wall_s=1.234):
    t = sc.output_grid(params)
    channels = {str(c): np.zeros_like(t) for c in sc.channels}
    channels.update({c: f(t) for c, f in laws.items()})
    return Trajectory(scene=sc.name, solver=solver, t=t, channels=channels,
                      settings={"integrator": "rk4", "dt": 1e-4}, wall_s=wall_s,
                      versions={"mujoco": "4.0.0"})


def _saved(tmp_path, sc, params, trs):
    TimeResult(sc, params, trs, [], []).save(tmp_path / "run", record=False, report=False)
    return json.loads((tmp_path / "run" / "result.json").read_text())


def _accuracy(path):
    head = [x for x in path.read_text().splitlines() if x.startswith("#")]
    line = next(x for x in head if x.startswith("# accuracy:"))
    m = re.match(r"# accuracy: ([-+0-9.e]+) (\S+)", line)
    return (float(m.group(1)), m.group(2)) if m else (None, line)


def test_results_file_reads_back_as_the_trajectory_and_its_accuracy(tmp_path):
    """Bricard (A04) at the library's parameters: iftomm/<solver>.txt is named in the result
    JSON's files; its columns are t, p3_x, p3_y, p3_z of the run, row for row; its accuracy is
    the largest |P3 − reference| over the reference table's whole seconds (computed here from
    the closed forms at those times, not from the grid); its CPU time the run's wall time."""
    sc = get_scene("bricard")
    params = sc.resolve()
    tr = _trajectory(sc, params, "mujoco", P3_LAW)
    obj = _saved(tmp_path, sc, params, [tr])
    path = tmp_path / "run" / "iftomm" / "mujoco.txt"
    assert obj["files"]["iftomm"]["mujoco"] == str(path)

    data = np.loadtxt(path, comments="#")
    assert data.shape == (len(tr.t), 4)
    assert np.array_equal(data[:, 0], tr.t)
    for k, c in enumerate(("p3_x", "p3_y", "p3_z"), start=1):
        assert np.array_equal(data[:, k], tr.channels[c]), c

    expected = max(abs(P3_LAW[c](t) - bricard_scene.REF_P3[i, k])
                   for i, t in enumerate(bricard_scene.REF_T)
                   for k, c in enumerate(("p3_x", "p3_y", "p3_z")))
    acc, unit = _accuracy(path)
    assert unit == "m" and acc == pytest.approx(expected, rel=1e-6)
    text = path.read_text()
    assert "problem A04" in text and "CPU time: 1.234 s" in text
    assert "columns: t [s] p3_x [m] p3_y [m] p3_z [m]" in text


def test_accuracy_is_not_known_away_from_the_reference_parameters(tmp_path):
    """The table holds at the library's parameters only: at m = 2 kg the file says so, and the
    bench falls back to its reference solver."""
    sc = get_scene("bricard")
    params = sc.resolve({"m": "2"})
    _saved(tmp_path, sc, params, [_trajectory(sc, params, "mujoco", P3_LAW)])
    acc, line = _accuracy(tmp_path / "run" / "iftomm" / "mujoco.txt")
    assert acc is None and "not known at these parameters" in line
    assert sc.bench_reference(params) is None
    assert sc.bench_reference(sc.resolve()) is sc.benchmark


def test_andrews_accuracy_is_at_the_test_sets_time(tmp_path):
    """Andrews (A03): the test set's solution holds at t = 0.03 s only; angles off it by known
    offsets there (and by far more earlier, where no reference value exists) have the largest
    offset as their accuracy, in rad; a scene without a benchmark writes no iftomm folder."""
    sc = get_scene("andrews-squeezer")
    params = sc.resolve()
    offsets = np.array([3e-7, -5e-7, 1e-7, 2e-7, -4e-7, 6e-8, -9e-7])
    laws = {a: (lambda t, q=q, d=d: q + d + 10.0 * (0.03 - t))
            for a, q, d in zip(andrews_phys.ANGLES, andrews_phys.Q_REF, offsets)}
    _saved(tmp_path, sc, params, [_trajectory(sc, params, "mujoco", laws)])
    acc, unit = _accuracy(tmp_path / "run" / "iftomm" / "mujoco.txt")
    assert unit == "rad" and acc == pytest.approx(9e-7, rel=1e-5)

    other = get_scene("rotor-spinup")
    assert other.benchmark is None


def test_bench_measures_a_rung_by_the_problems_error(tmp_path):
    """`xval bench bricard` at the library's parameters: a rung's error is the problem's
    (largest |P3 − reference table|, m) and its relative error that over the table's largest
    |value| — no reference solver runs."""
    from compare.workflows.bench import _benchmark_reference
    sc = get_scene("bricard")
    params = sc.resolve()
    ref, measure, ref_settings, done = _benchmark_reference(sc, sc.benchmark, params,
                                                            lambda _: None)
    assert ref["kind"] == "benchmark" and ref["problem"] == "A04" and not done
    got = measure(_trajectory(sc, params, "mujoco", P3_LAW))
    expected = max(abs(P3_LAW[c](t) - bricard_scene.REF_P3[i, k])
                   for i, t in enumerate(bricard_scene.REF_T)
                   for k, c in enumerate(("p3_x", "p3_y", "p3_z")))
    assert got["error"] == pytest.approx(expected, rel=1e-12)
    assert got["rel_error"] == pytest.approx(expected / np.max(np.abs(bricard_scene.REF_P3)),
                                             rel=1e-12)


def test_bench_report_names_the_problems_reference():
    from compare.output.bench_report import time_markdown
    ref = {"kind": "benchmark", "what": "IFToMM problem A04's reference: the table",
           "problem": "A04", "unit": "m", "scale": 1.65, "uncertainty": 1e-10,
           "solvers": [], "value": None, "cross_check_rel": None}
    row = {"solver": "mujoco", "method": "rk4", "settings": {"dt": 1e-3}, "error": 2e-6,
           "rel_error": 2e-6 / 1.65, "energy_residual": None, "wall_s": 0.5,
           "compile_s": None, "steps": 10, "rhs_evals": None, "ns_per_rhs": None}
    md = "\n".join(time_markdown({"scene": "bricard", "key_channel": "p3_y",
                                  "reference": ref, "summary_lines": [], "rows": [row]}, {}))
    assert "IFToMM problem A04's reference" in md and "| error [m] |" in md
    assert "| 2.00e-06 | 1.21e-06 |" in md


@pytest.mark.slow
def test_bench_andrews_rungs_against_the_test_set(tmp_path):
    """A whole bench of one solver: each ok rung's error is the largest |angle − test set|
    at t = 0.03 s of that rung's own trajectory (read back from the bench folder)."""
    from compare.api import bench
    obj = bench("andrews-squeezer", ["mujoco"], repeats=1, out=tmp_path)
    bench = json.loads((tmp_path / "bench.json").read_text())
    assert bench["reference"]["kind"] == "benchmark" and obj["rows"]
    ok = [r for r in bench["rows"] if r["status"] == "ok"]
    assert ok
    for path in sorted(tmp_path.glob("mujoco-*.npz")):
        tr = Trajectory.load(path)
        i = int(np.argmin(np.abs(tr.t - 0.03)))
        dev = max(abs(tr.channels[a][i] - q) for a, q in zip(andrews_phys.ANGLES,
                                                              andrews_phys.Q_REF))
        assert any(r["error"] == pytest.approx(dev, rel=1e-12) for r in ok), path.name
