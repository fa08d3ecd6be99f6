"""Outputs a reviewer can read: files with the user's umask, numbers to their meaningful
digits, sources cited as papers."""
import json
import os

import pytest
from conftest import xval

from compare.atomic import publish, write_json, write_text
from compare.output.report import fmt_value


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
