"""What a reviewer sees (issue 49): plots that carry the verdict, reports that state their
inputs and cite papers, no empty files, no path into a deleted temporary folder. Numbers
asserted here are the inputs given (a --set), hand conversions (rad/s → rpm) or the
comparison's own stored parts (error estimate + allowance), never a figure's own output."""
import math
import os

import numpy as np
import pytest

import xval
from compare.analysis import metrics
from compare.analysis.trajectory import Modes
from compare.output import campbell_plot, frequency_plot, joblog, mode_shapes, report
from compare.results.studies import BenchResult
from compare.scenes import get_scene
from compare.workflows.modes import entry


@pytest.fixture(scope="module")
def spun(tmp_path_factory):
    """A short spin-up, two custom solvers, torque set away from its default (1.5 N·m)."""
    out = tmp_path_factory.mktemp("run")
    r = xval.run("rotor-spinup", ["euler-vector", "quaternion"], t_end=0.3, torque=3.2,
                 out=out)
    return r, out


def test_deviation_plot_draws_each_pairs_bound_and_verdict(spun):
    r, _ = spun
    fig = report.deviation_figure(r)
    ax = fig.axes[0]
    c = report.comparison_of(r.comparisons, "euler-vector", "quaternion", "omega_norm")
    # the bound from the comparison's own parts: both error estimates + the allowance
    bound = c.error_estimate + c.allowance
    dashed = [ln for ln in ax.lines if ln.get_linestyle() == "--"]
    assert len(dashed) == 1 and math.isclose(dashed[0].get_ydata()[0], bound, rel_tol=1e-12)
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any(t.startswith("euler-vector − quaternion: agree") for t in legend)
    assert "torque = 3.2 N·m" in fig._suptitle.get_text()


def test_channels_title_and_header_name_the_changed_parameter(spun):
    r, out = spun
    fig = report.channels_figure(r)
    assert "torque = 3.2 N·m" in fig._suptitle.get_text()
    md = (next(out.rglob("report.md"))).read_text()
    assert "Parameters: defaults; torque = 3.2 N·m" in md
    assert "t_end = 0.3 s" in md
    # cited by paper (docs/sources.md), never by the scene data's internal "seed NNN"
    assert "A. A. Kiryukhin" in md and "seed 0" not in md


def test_no_empty_file_in_a_written_folder(spun):
    _, out = spun
    files = [p for p in out.rglob("*") if p.is_file()]
    assert files and not [p for p in files if p.stat().st_size == 0]


def test_an_empty_job_log_is_not_left_behind(tmp_path):
    with joblog.captured(tmp_path / "quiet.log") as text:
        pass
    assert text == [""] and not (tmp_path / "quiet.log").exists()
    with joblog.captured(tmp_path / "said.log") as text:
        os.write(1, b"engine banner\n")          # as an engine's C++ writes to fd 1
    assert text == ["engine banner"] and (tmp_path / "said.log").read_text().strip() \
        == "engine banner"


def test_a_study_held_in_memory_writes_its_folder_on_save(tmp_path):
    """A study made without a folder names none until `save` writes one with its writer."""
    def write(folder):
        (folder / "report.md").write_text("# bench\n")
        return {"summary_lines": ["one line"], "report": str(folder / "report.md")}
    s = BenchResult({"summary_lines": ["one line"]}, writer=write)
    assert s.report is None and s.out_dir is None and not any(tmp_path.iterdir())
    assert str(s).splitlines()[-1].startswith("report: not kept")
    s.save(tmp_path / "b")
    assert s.report == tmp_path / "b" / "report.md" and s.report.exists()
    assert str(s).splitlines()[-1] == f"report: {tmp_path / 'b' / 'report.md'}"


def test_response_header_lists_the_studys_own_inputs():
    sc = get_scene("rotor-whirl")
    spec = sc.response
    # `xval show rotor-whirl` lists no unbalance and no external damping ...
    assert sc.param("eccentricity").default == 0 and sc.param("c_ext").default == 0
    params = sc.resolve(spec.set)
    head = "\n".join(report.header_lines(sc, params, inputs=spec.set))
    # ... the response study adds e = 1e-8 m and c_ext = 5 and says so
    assert "eccentricity = 1e-08 m" in head and "c_ext = 5 " in head
    assert "not the scene's defaults" in head and "Parameters: defaults." in head


def test_critical_speed_table_rpm_headers_and_notes():
    sc = get_scene("rotor-whirl")
    cb, params = sc.campbell, sc.resolve({})
    fwd, bwd = cb.excitations[0], cb.excitations[0]
    # rotor-whirl sweeps spin in rad/s: 41.057748 rad/s = 41.057748 · 60 / 2π rpm
    e_f = entry(cb, params, "forward whirl", fwd, 41.057748, "forward")
    e_b = entry(cb, params, "backward whirl", bwd, 36.480766, "backward")
    assert math.isclose(e_f["speed_rpm"], 41.057748 * 60 / (2 * math.pi), rel_tol=1e-12)
    assert campbell_plot.crossing_label(e_f) == "392.1 rpm, 1× unbalance, forward whirl"
    md = campbell_plot.critical_table(cb, {"closed-form": [e_b, e_f]})
    header = [h.strip() for h in md[2].strip("|").split("|")]
    assert len(set(header)) == len(header) and "speed [rpm]" in header and "note" in header
    rows = {ln.split("|")[2].strip(): ln.split("|")[-2].strip() for ln in md[4:]}
    assert rows == {"backward whirl": "backward whirl: not excited by unbalance",
                    "forward whirl": ""}


def _modes(solver, f, err):
    return Modes("s", solver, np.array(f), ["a", "b", "c"],
                 extra={"frequency_error_hz": np.array(err)})


def test_repeated_frequencies_are_noted_only_within_the_error_bars():
    # a and b 1e-4 Hz apart with bars 1e-3 Hz: one frequency; c 1 Hz away: its own
    same = mode_shapes.repeated_frequencies([_modes("x", [5.0, 5.0001, 6.0], [1e-3] * 3)])
    assert len(same) == 1 and same[0].startswith("- a / b at 5–5.0001 Hz (x)")
    assert "may differ within it" in same[0]
    # the same gap with bars 1e-6 Hz: two frequencies, no note
    assert mode_shapes.repeated_frequencies([_modes("x", [5.0, 5.0001, 6.0], [1e-6] * 3)]) == []


def test_a_modes_case_without_shapes_or_campbell_gets_figure_and_recording(tmp_path):
    runs = [_modes("p", [5.0, 6.0, 7.0], [1e-6] * 3), _modes("q", [5.0, 6.00001, 7.0],
                                                             [1e-6] * 3)]
    cmp = metrics.frequency_comparisons(runs, {"frequency": 1e-6})
    sc = get_scene("helicopter-clamped")
    png = frequency_plot.write_figure(tmp_path / "frequencies.png", sc, sc.resolve({}), runs,
                                      cmp)
    rrd = frequency_plot.write_recording(tmp_path / "frequencies.rrd", runs, "t")
    assert png == "frequencies.png" and (tmp_path / png).stat().st_size > 0
    assert rrd.stat().st_size > 0


def test_error_band_drawn_only_where_wider_than_the_line():
    from matplotlib.figure import Figure
    t = np.linspace(0.0, 1.0, 101)
    v = t.copy()                                     # range 1: a line ~1/250 of it wide
    ax = Figure().subplots()
    report._error_band(ax, t, v, np.full_like(t, 1e-6), "C0")
    assert not ax.collections                        # ±1e-6: inside the line, not drawn
    report._error_band(ax, t, v, np.where(t > 0.5, 0.05, 1e-6), "C0")
    (band,) = ax.collections                         # ±0.05 on the second half only
    xs = band.get_paths()[0].vertices[:, 0]
    assert xs.min() >= 0.5 - 1e-12 and math.isclose(xs.max(), 1.0)


def test_a_map_counts_its_runs_with_an_eta():
    """The map's counter ends at the runs its Runner tallied per solver (a separate count)."""
    import io

    from compare.output import progress
    from compare.workflows import maps
    plan = maps.plan_map("rotor-spinup", "torque=1:5", overrides={"t_end": 3},
                         solver_names=["euler-vector"], resolution=0.05, coarse=(5, 1))
    out = io.StringIO()
    with progress.reporting(stream=out):
        res = maps.run_map(plan)
    n = sum(res["runs"].values())
    lines = out.getvalue().splitlines()
    assert n > plan["estimate"]["runs"] // 2 and "ETA" in lines[0]
    assert lines[-1].startswith(f"map rotor-spinup: {n}/{n} runs, done in ")


def test_a_study_report_without_a_header_gets_one_under_its_title():
    from compare.output.study import _with_header
    md = _with_header(["# Work-precision: rotor-spinup", "", "body"],
                      {"scene": "rotor-spinup", "params": {"torque": 3.2, "t_end": 10.0}})
    assert md[0] == "# Work-precision: rotor-spinup" and md[-1] == "body"
    assert "Parameters: defaults; torque = 3.2 N·m." in md      # t_end 10 s is the default
    assert _with_header(["# x", "Parameters: defaults."], {"scene": "rotor-spinup",
                                                          "params": {}}) == \
        ["# x", "Parameters: defaults."]


def test_a_modes_folder_without_shapes_or_campbell_draws_the_frequencies(tmp_path):
    """The helicopters' engine cases: no shapes, no Campbell lines — still a figure and a
    recording (as every other case of a campaign has)."""
    from compare.output.modes_folder import write_modes_folder
    from compare.results import ModesResult
    sc = get_scene("helicopter-clamped")
    runs = [_modes("exudyn", [5.0, 6.0, 7.0], [1e-6] * 3),
            _modes("mujoco", [5.0, 6.00001, 7.0], [1e-6] * 3)]
    cmp = metrics.frequency_comparisons(runs, {"frequency": 1e-6})
    r = ModesResult(sc, sc.resolve({}), runs, cmp, summary="3 of 3 agree", parts={})
    write_modes_folder(tmp_path, r)
    assert r.files["frequencies_figure"] == tmp_path / "frequencies.png"
    assert r.files["recording"] == tmp_path / "frequencies.rrd"
    assert all((tmp_path / f).stat().st_size > 0 for f in ("frequencies.png", "frequencies.rrd"))
    assert "![frequencies](frequencies.png)" in (tmp_path / "report.md").read_text()
