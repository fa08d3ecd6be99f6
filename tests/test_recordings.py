"""Recordings read back (rerun.chunk.RrdReader): for every time-domain scene, the 3D bodies of
every solver with one row per output sample (or the scene's stated decimation), a deviation
series for every compared pair and channel, and the events at their times."""
import numpy as np
import pytest

from compare import runner, solvers
from compare.recording import load_rows, pair_entity
from compare.scenes import get_scene

# short runs of each scene: every solver, the recording written, no report
CASES = {"rotor-spinup": {"t_end": "4.5", "output_dt": "0.01"},
         "bearing-rotor": {"t_end": "0.2"}}


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
    for tr in res.trajectories:
        assert tr.status == "ok", tr.reason
        t, _ = load_rows(path, f"world/{tr.solver}", "Transform3D:translation")
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
