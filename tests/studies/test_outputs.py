"""Outputs a reviewer can read: files with the user's umask, numbers to their meaningful
digits, sources cited as papers."""
import json
import os

import pytest

from compare.atomic import publish, write_json, write_text
from compare.output.report import fmt_value
from tests.conftest import xval


@pytest.mark.parametrize("mask, mode", [(0o022, 0o644), (0o027, 0o640), (0o077, 0o600)])
def test_atomic_files_get_the_mode_open_would_give(tmp_path, mask, mode):
    """mkstemp makes 0600; teammates on a shared machine could not read the reports."""
    old = os.umask(mask)
    try:
        write_text(tmp_path / "a.md", "x\n")
        write_json(tmp_path / "b.json", {"x": 1})
        publish(tmp_path / "b.json", tmp_path / "sub" / "c.json")
        with open(tmp_path / "plain.txt", "w"):          # what the user's umask gives
            pass
    finally:
        os.umask(old)
    for name in ("a.md", "b.json", "sub/c.json", "plain.txt"):
        assert (tmp_path / name).stat().st_mode & 0o777 == mode, name
    assert json.loads((tmp_path / "sub" / "c.json").read_text()) == {"x": 1}
    assert not [p for p in tmp_path.rglob(".*")]         # no temporary file left behind


@pytest.mark.parametrize("value, text", [(9.999999999999999e-14, "1e-13"), (0.01, "0.01"),
                                         (3.2, "3.2"), (1000000.0, "1e+06"), (5, "5"),
                                         ("rk4", "rk4"), ([0.0, 0.0, -9.81], "0,0,-9.81")])
def test_settings_and_parameters_print_their_meaningful_digits(value, text):
    assert fmt_value(value) == text


def test_show_cites_the_papers():
    rc, so, _ = xval("show", "rotor-spinup")
    assert rc == 0 and "seed 0" not in so
    assert "Kiryukhin" in so and "2024" in so and "Chuveyko" in so
    rc, so, _ = xval("show", "sail-deploy", "--json")
    assert any("Tenenbaum" in s and "2014" in s for s in json.loads(so)["sources"])


def test_every_time_channel_carries_its_unit_from_the_scene():
    """Units have one home, the scene's Channels: every built-in time scene names the SI unit
    of each channel, and the plots read it there (a plain-string channel is drawn [–])."""
    from compare.output.report import channel_label
    from compare.scenes import SCENES
    for sc in SCENES.values():
        if sc.is_time:
            assert all(c.unit for c in sc.channels), (sc.name, [c for c in sc.channels
                                                                 if not c.unit])
    rotor = SCENES["rotor-spinup"]
    assert channel_label(rotor, "tilt") == "tilt [rad]"
    assert channel_label(rotor, "work") == "work [J]"
    from dataclasses import replace
    plain = replace(rotor, channels=("tilt", "work"))
    assert channel_label(plain, "tilt") == "tilt [–]"


@pytest.mark.parametrize("scene, solvers, t_end", [
    ("rotor-spinup", ["euler-vector", "quaternion"], 0.5), ("bearing-rotor", ["quaternion"], 0.05)])
def test_report_plots_keep_every_label_inside_the_figure_and_apart(scene, solvers, t_end):
    """The run report's figures are laid out with fixed margins (report.fixed_margins), not
    measured by tight_layout: drawn, every axes' extent with its tick labels, axis label, offset
    text and title — and the figure's title — lies inside the figure and clear of the others.
    rotor-spinup: 7 channels, a potential whose ticks read 24.52504, two solvers' deviation on
    log axes; bearing-rotor: 11 channels, a flat energy balance labelled with its initial value,
    offset texts (1e-9) above the axes. Seeded: the label room without the tick labels' width,
    digits taken as 0.45 em, the left margin 0.75 → 0.3 in, the gap between rows 0.35 → 0.05 in
    — each fails here."""
    import itertools

    import xval as api
    from compare.output import report
    r = api.run(scene, solvers, t_end=t_end, estimate_errors=False)
    for fig in (report.channels_figure(r), report.deviation_figure(r)):
        fig.canvas.draw()
        renderer = fig.canvas.get_renderer()
        boxes = [ax.get_tightbbox(renderer) for ax in fig.axes if ax.axison]
        if fig._suptitle is not None:
            boxes.append(fig._suptitle.get_window_extent(renderer))
        for b in boxes:
            assert fig.bbox.x0 <= b.x0 and b.x1 <= fig.bbox.x1, (scene, b)
            assert fig.bbox.y0 <= b.y0 and b.y1 <= fig.bbox.y1, (scene, b)
        for a, b in itertools.combinations(boxes, 2):
            assert not a.overlaps(b), (scene, a, b)
        report._plt().close(fig)
