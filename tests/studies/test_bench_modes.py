"""`xval bench` on a frequency scene: the ladders run, the Hermite elements converge at their
closed-form rate, and bad input is one line."""
import json
from pathlib import Path

import numpy as np

from compare.api import bench
from compare.workflows import bench_modes
from tests.conftest import xval


def test_frequency_bench_small_ladder(tmp_path, monkeypatch):
    """rotating-beam at 40 rad/s, mstmm and fem, fem meshes 24/48/96 (with and without
    Richardson). A Hermite cubic beam element converges in frequency as h⁴ (the Rayleigh–Ritz
    eigenvalue error is the square of the h² energy-norm error of the cubic; Strang & Fix
    ch. 6): the observed order between uniformly meshed rungs must be 4 ± 0.5 where the error
    is not at the floor. Measured: 24 → 48 → 96 elements give 1.1e-5, 7.2e-7, 4.6e-8, orders
    3.93 and 3.98 (the floor: fem and mstmm agree to ~6e-9, the scene file's measurement)."""
    monkeypatch.setattr(bench_modes, "MESH_FACTORS", (0.5, 1.0, 2.0))
    obj = bench("rotating-beam", ["mstmm", "fem"], speed=40, n_modes=3, repeats=1,
                out=tmp_path)
    out = Path(obj["report"]).parent
    assert {p.name for p in out.iterdir()} >= {"bench.json", "report.md", "work_precision.png"}
    assert json.loads((out / "bench.json").read_text())["scene"] == "rotating-beam"
    from compare.results import BenchResult, Result
    loaded = Result.load(out)                        # the bench folder reads back
    assert isinstance(loaded, BenchResult) and loaded.summary_lines() == obj["summary_lines"]
    # the independent fem confirms the mstmm reference (scene file: ≤ 6e-9 measured)
    assert obj["reference"]["confirmed_by"]["solver"] == "fem"
    assert obj["reference"]["confirmed_by"]["rel"] < 2e-8
    assert {r["solver"] for r in obj["rows"]} == {"mstmm", "fem"}
    assert obj["summary"]["0.001"]["unreached"] == []

    uniform = sorted((next(iter(set(r["knob"]["elements"].values()))), r["rel_error"])
                     for r in obj["rows"] if r["solver"] == "fem" and r["method"] == "elements"
                     and len(set(r["knob"]["elements"].values())) == 1)
    n, err = np.array(uniform).T
    assert list(n) == [24, 48, 96] and np.all(np.diff(err) < 0)
    floor = 1e-7           # 15× above the mstmm–fem agreement: h⁴ still dominates
    orders = [np.log(err[i] / err[i + 1]) / np.log(n[i + 1] / n[i])
              for i in range(len(n) - 1) if err[i + 1] > floor]
    assert orders and all(abs(p - 4.0) <= 0.5 for p in orders), orders

    # the paper's Table 1 time is set against each solver's default-settings time
    table1 = [t for t in obj["published_timings"] if t["what"].startswith("Table 1")]
    assert {t["solver"] for t in table1} == {"mstmm", "fem"}
    assert all(len(t["per_case_s"]) == 3 and t["published_s"]["MATLAB"] == 6.3 for t in table1)


def test_frequency_bench_unknown_solver_is_one_line_exit_2(tmp_path):
    rc, so, se = xval("bench", "rotating-beam", "--solver", "nope", "--out", str(tmp_path))
    assert rc == 2 and len(se.strip().splitlines()) == 1 and so == ""
    assert "nope" in se and not any(tmp_path.iterdir())


def test_a_mesh_the_leaf_refuses_ends_the_ladder(tmp_path, monkeypatch):
    """helicopter-clamped's fem puts its mode-shape stations on every (elements/6)-th node, so
    it refuses 3 blade elements (a quarter of its 12): the mesh ladder 3, 6, 12 stops at 6
    with no row for the refused mesh, as the time bench ends a ladder at a setting its leaf
    refuses; the two meshes it ran converge (6 elements coarser than 12)."""
    monkeypatch.setattr(bench_modes, "MESH_FACTORS", (0.25, 0.5, 1.0))
    obj = bench("helicopter-clamped", ["fem"], repeats=1, out=tmp_path)
    mesh = [r for r in obj["rows"] if r["solver"] == "fem" and r["method"] == "mesh"]
    assert all(r["status"] == "ok" for r in obj["rows"]), [r.get("reason") for r in obj["rows"]]
    assert sorted(r["knob"]["blade_elements"] for r in mesh) == [6, 12]
    six, twelve = sorted(mesh, key=lambda r: r["knob"]["blade_elements"])
    assert six["rel_error"] > twelve["rel_error"]
