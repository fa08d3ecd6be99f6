"""Recordings read back (rerun.chunk.RrdReader): for every time-domain scene, the 3D bodies of
every solver with one row per output sample (or the scene's stated decimation), a deviation
series for every compared pair and channel, and the events at their times."""
import numpy as np
import pytest

from compare import solvers
from compare.output.recording import load_rows, pair_entity
from compare.scenes import get_scene
from compare.workflows import runner

# short runs of each scene: every solver, the recording written, no report
CASES = {"rotor-spinup": {"t_end": "4.5", "output_dt": "0.01"},
         "bearing-rotor": {"t_end": "0.2"},
         "press": {"t_end": "0.02"},
         "press-cycle": {},
         "sail-deploy": {"t_end": "2", "stiffness": "1e5", "n": "10"}}
BODY = {"rotor-spinup": ("", "Transform3D:translation"),
        "bearing-rotor": ("", "Transform3D:translation"),
        "press": ("/links", "LineStrips3D:strips"),
        "press-cycle": ("/links", "LineStrips3D:strips"),
        "sail-deploy": ("/thread", "LineStrips3D:strips")}


def record(scene_name, tmp_path):
    sc = get_scene(scene_name)
    p = sc.resolve(CASES[scene_name])
    chosen = solvers.solvers_for(sc.name)
    res = runner.run_scene(sc, p, chosen, lambda s: solvers.settings_for(s, sc.name), tmp_path,
                           report=False, estimate_errors=False)
    return sc, res, res.files["recording"]


@pytest.mark.parametrize("scene_name", list(CASES))
def test_every_solver_drawn_and_every_pair_deviation_recorded(scene_name, tmp_path):
    sc, res, path = record(scene_name, tmp_path)
    n = len(res.trajectories[0].t)
    sub, component = BODY[scene_name]
    for tr in res.trajectories:
        assert tr.status == "ok", tr.reason
        t, _ = load_rows(path, f"world/{tr.solver}{sub}", component)
        assert len(t) == n and np.allclose(t, tr.t, atol=1e-9)
    for c in res.comparisons:
        t, v = load_rows(path, pair_entity(c.channel, c.a, c.b), "Scalars:scalars")
        assert len(t) == n
        # the series is log10 |Δ|: its largest value is the comparison's deviation
        assert 10 ** max(x[0] for x in v) == pytest.approx(max(c.deviation, 1e-300), rel=1e-9)
        tb, _ = load_rows(path, pair_entity(c.channel, c.a, c.b) + "/bound", "Scalars:scalars")
        assert len(tb) == n


def test_events_land_at_their_times(tmp_path):
    # the rotor's first passage of √(k/I_t) (≈ 4.18 s) is an event per solver
    sc, res, path = record("rotor-spinup", tmp_path)
    passage = next(f for f in res.findings if f.name == "t_first_pass_omega_tilt")
    t, text = load_rows(path, "events", "TextLog:text")
    assert len(t) == len(passage.at) == len(res.trajectories)
    for tt, txt in zip(t, text):
        solver = txt[0].split("(")[1].split(")")[0]
        assert tt == pytest.approx(passage.at[solver], abs=1e-6)


def test_press_cycle_lock_is_an_event_and_a_colour_change(tmp_path):
    sc, res, path = record("press-cycle", tmp_path)
    lock = next(f for f in res.findings if f.name == "t_lock")
    t, text = load_rows(path, "events", "TextLog:text")
    dt = float(sc.resolve()["output_dt"])
    for solver, t_lock in lock.at.items():
        at = [tt for tt, x in zip(t, text) if f"({solver})" in x[0]]
        assert len(at) == 1 and abs(at[0] - t_lock) < dt          # within one output step
        tc, colors = load_rows(path, f"world/{solver}/links", "LineStrips3D:colors")
        changed = [tt for tt, c, c0 in zip(tc[1:], colors[1:], colors) if c != c0]
        assert changed and abs(changed[0] - t_lock) <= dt        # the linkage turns dark


def test_long_sail_run_is_decimated(tmp_path):
    from compare.scenes.sail import MAX_FRAMES
    sc, res, path = record("sail-deploy", tmp_path)
    t, strips = load_rows(path, f"world/{res.trajectories[0].solver}/thread",
                          "LineStrips3D:strips")
    assert len(t) <= MAX_FRAMES and len(strips[0]) == 2          # two blades per instant
