"""`xval bench`'s folder (compare/output/bench_report.py) from numbers chosen here: each table
row carries them, formatted as written out by hand below, in as many columns as its header;
the time and frequency benches draw work_precision.png, the throughput bench does not."""
import json

from compare.output import bench_report as br

PNG = b"\x89PNG\r\n\x1a\n"


def table(md):
    """The Markdown table's lines: header, rule, rows."""
    return [line for line in md if line.startswith("|")]


def same_width(rows):
    return len({line.count("|") for line in rows}) == 1


def time_obj():
    rows = [{"solver": "a", "method": "rk4", "settings": {"integrator": "rk4", "dt": 0.002},
             "status": "ok", "wall_s": 0.0123456, "compile_s": 0.5, "rel_error": 3.2e-4,
             "energy_residual": None, "steps": 500, "rhs_evals": 2000, "integrate_s": 0.01,
             "ns_per_rhs": 1234.4},
            {"solver": "b", "method": "dop853",
             "settings": {"integrator": "dop853", "rtol": 1e-8, "atol": 1e-10}, "status": "ok",
             "wall_s": 0.25, "compile_s": None, "rel_error": 2.5e-9, "energy_residual": 1.5e-6,
             "steps": 80, "rhs_evals": None, "integrate_s": None, "ns_per_rhs": None}]
    summary = {"0.001": {"fastest": "a", "method": "rk4", "wall_s": 0.0123456,
                         "rel_error": 3.2e-4, "settings": rows[0]["settings"],
                         "time_ratio": {"a": 1.0, "b": 20.25}, "unreached": []}}
    return {"scene": "toy-bench", "params": {"t_end": 1.0}, "key_channel": "omega",
            "vary": None, "reference": {"solvers": ["a", "b"], "value": 43.25,
                                        "cross_check_rel": 1.2e-11},
            "repeats": 3, "rows": rows, "summary": summary, "orders": [],
            "summary_lines": ["error ≤ 0.001: fastest a"], "result": "bench"}


def test_time_bench_table_carries_the_rows_and_the_figure_is_drawn(tmp_path):
    obj = time_obj()
    out = br.write_time_bench(br.bench_dir(tmp_path / "b"), obj, {"integrator": "rk4",
                                                                  "dt": 0.00025})
    md = (tmp_path / "b" / "report.md").read_text().splitlines()
    assert md[0] == "# Work-precision: toy-bench"
    assert "Reference: a (integrator=rk4, dt=0.00025), final omega = 43.25; b agrees to "\
        "1.2e-11 relative" in md
    assert "- error ≤ 0.001: fastest a" in md
    t = table(md)
    assert t[2:] == ["| a | rk4 | 0.002 | 3.20e-04 | — | 0.01235 | 0.5 | 500 | 2000 | 1234 |",
                     "| b | dop853 | 1e-08 | 2.50e-09 | 1.50e-06 | 0.25 | — | 80 | — | — |"]
    assert same_width(t) and t[0].count("|") == 11           # ten columns
    assert md[-1] == "![work-precision](work_precision.png)"
    assert (tmp_path / "b" / "work_precision.png").read_bytes()[:8] == PNG
    data = json.loads((tmp_path / "b" / "bench.json").read_text())
    assert data["rows"] == obj["rows"] and "report" not in data
    assert out["report"] == str(tmp_path / "b" / "report.md")


def test_modes_bench_table_carries_the_rows_and_the_figure_is_drawn(tmp_path):
    rows = [{"solver": "f", "method": "elements", "knob_kind": "mesh",
             "knob": {"elements": {"flap": 36, "lag": 24}}, "settings": {}, "status": "ok",
             "wall_s": 0.007989, "cpu_s": 0.008, "rel_error": 1.57e-6, "worst_mode": "flap 1",
             "n_modes": 2},
            {"solver": "f", "method": "elements", "knob_kind": "mesh", "knob": {"elements": 12},
             "settings": {}, "status": "ok", "wall_s": 0.5, "cpu_s": 0.5, "rel_error": None,
             "reason": "paired 1 of the reference's 2 modes", "n_modes": 1}]
    obj = {"scene": "toy-modes", "kind": "modes", "params": {}, "repeats": 3,
           "reference": {"solver": "m", "settings": {"rtol": 1e-13, "stations": 13},
                         "labels": ["flap 1", "lag 1"], "frequencies_hz": [0.8275, 10.5],
                         "confirmed_by": {"solver": "f", "settings": {"elements": 48},
                                          "rel": 1.8e-9, "worst_mode": "lag 1"}},
           "first_call_s": {"m": 0.58}, "blas_threads": None, "rows": rows,
           "summary": {}, "orders": [], "published_timings": [], "summary_lines": [],
           "result": "bench"}
    br.write_modes_bench(br.bench_dir(tmp_path), obj)
    md = (tmp_path / "report.md").read_text().splitlines()
    assert md[0] == "# Work-precision: toy-modes (natural frequencies)"
    assert "Reference: m (rtol=1e-13, stations=13): flap 1 0.8275 Hz, lag 1 10.5 Hz" in md
    assert "Confirmed by f (elements=48) to 1.8e-09 relative (at lag 1)" in md
    assert md[md.index("Confirmed by f (elements=48) to 1.8e-09 relative (at lag 1)") + 2] == (
        "First call (import, compile): m 0.58 s; OPENBLAS_NUM_THREADS=unset; median of 3 warm "
        "calls (15 under 50 ms).")
    t = table(md)
    assert t[2:] == ["| f | elements | elements=flap 36/lag 24 | 1.57e-06 | flap 1 | 0.007989 |"
                     " 0.008 |",
                     "| f | elements | elements=12 | — | paired 1 of the reference's 2 modes | "
                     "0.5 | 0.5 |"]
    assert same_width(t) and t[0].count("|") == 8            # seven columns
    assert (tmp_path / "work_precision.png").read_bytes()[:8] == PNG


def test_throughput_table_carries_the_rows_and_draws_no_figure(tmp_path):
    rows = [{"solver": "q", "points": 20, "wall_s": 0.03, "points_per_second": 615.3,
             "points_per_core_second": 389.4, "accurate_points_per_second": 521.8,
             "rerun_fraction": 0.55, "labels_differ": 0},
            {"solver": "e", "points": 20, "wall_s": 1.0, "points_per_second": 20.04,
             "points_per_core_second": 10.0, "accurate_points_per_second": 20.0}]
    obj = {"scene": "toy-map", "map": "capture", "x": {"name": "torque"}, "y": {"name": "ecc"},
           "set": {"t_end": 10}, "workers": 2, "rows": rows, "summary_lines": [],
           "result": "bench"}
    br.write_throughput(br.bench_dir(tmp_path), obj, "toy-map")
    md = (tmp_path / "report.md").read_text().splitlines()
    assert md[0] == "# Throughput: toy-map"
    assert md[2].startswith("20 points over the default map `capture` (torque × ecc), set "
                            "{'t_end': 10}, after")
    t = table(md)
    assert t[2:] == ["| q | 20 | 615.3 | 389.4 | 521.8 | 55.0% | 0 |",
                     "| e | 20 | 20.0 | 10.0 | 20.0 | — | — |"]
    assert same_width(t)
    assert not (tmp_path / "work_precision.png").exists()
