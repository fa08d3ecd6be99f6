"""The helicopter's frame explanation (compare/scenes/mstmm_frames.py) on the four solvers'
frequencies measured at `xval calibrate helicopter-hover --seed 2026`'s seventeenth set
(Ω 57.7 rad/s): the paper's two models agree with each other, the two engines with each
other, and every engine–paper difference is the rotor-frame assumption — verified, never
inferred — although the paper's two models name the degenerate torsion root at 15.20888 Hz
differently (mstmm: collective, fem: differential) and the engines' list holds no torsion
differential mode. A seeded 1 % error in one paper model must stay unexplained."""
import numpy as np
import pytest

from compare.analysis import metrics
from compare.analysis.trajectory import Modes
from compare.analysis.verdict import Verdict
from compare.scenes import get_scene, mstmm, mstmm_frames
from compare.workflows import calibrate

SCENE = get_scene("helicopter-hover")

PAPER_AT_SPEED = [("lag collective 1", 3.34550), ("flap cyclic 1", 8.38427),
                  ("flap cyclic 2", 9.24136), ("flap differential 1", 10.48351),
                  ("flap collective 1", 10.55520), ("flap cyclic 3", 11.48727),
                  ("flap cyclic 4", 12.34129)]
TORSION = 15.20888
ENGINE_AT_SPEED = [("fuselage 1", 0.57531), ("fuselage 2", 1.53934), ("flap cyclic 1", 3.64367),
                   ("fuselage 3", 4.96431), ("flap differential 1", 10.48481),
                   ("flap collective 1", 10.55659), ("flap cyclic 2", 10.56533),
                   ("torsion cyclic 1", 15.15316)]
# each solver's own error estimate per mode there (Hz, in the order above): the engines'
# Richardson extrapolate's, mstmm's root tolerance, fem's mesh
ERRORS = {"exudyn": [1.276e-3, 7.849e-3, 8.27e-3, 4.797e-8, 1.193e-2, 1.187e-2, 1.169e-2,
                     2.301e-4],
          "mstmm": [3.346e-10, 8.384e-10, 9.241e-10, 1.048e-9, 1.056e-9, 1.149e-9, 1.234e-9,
                    1.521e-9],
          "fem": [2.831e-6, 3.529e-6, 3.096e-7, 1.768e-5, 1.759e-5, 3.372e-5, 3.386e-5,
                  8.057e-12]}
ERRORS["mujoco"] = ERRORS["exudyn"]
PAPER_AT_REST = [0.95320, 0.95826, 0.96087, 0.98046, 4.97440, 5.83468, 5.87015, 5.97362]
ENGINE_AT_REST = [0.95320, 0.95825, 0.96086, 0.98046, 4.96122, 5.83434, 5.86984, 5.97328]
# the engine's own first-order estimate of its sections' rotary inertia at rest, Hz
SECTIONS_AT_REST = [8e-6, 1.7e-5, 4.9e-5, 8e-6, 2.3698e-2, 3.98e-4, 3.16e-4, 3.33e-4]


def _modes(solver, rows, extra=None, errors=None):
    return Modes(SCENE.name, solver, np.array([f for _, f in rows]), [n for n, _ in rows],
                 extra={**(extra or {}),
                        **({} if errors is None else {"frequency_error_hz": errors})})


def _runs(paper_scale=1.0, mujoco=None):
    """The four solvers at speed and at rest, as measured; mstmm's frequencies × paper_scale;
    MuJoCo's modes at speed `mujoco` where given."""
    torsion = {"mstmm": "torsion collective 1", "fem": "torsion differential 1"}
    at_speed = {p: _modes(p, [(n, f * (paper_scale if p == "mstmm" else 1.0))
                              for n, f in PAPER_AT_SPEED + [(torsion[p], TORSION)]],
                             errors=ERRORS[p])
                for p in torsion}
    at_speed.update({e: _modes(e, ENGINE_AT_SPEED, errors=ERRORS[e])
                     for e in mstmm_frames.ENGINES})
    if mujoco is not None:
        at_speed["mujoco"] = _modes("mujoco", [r for r, _ in mujoco], errors=[e for _, e in mujoco])
    rest = {p: _modes(p, [(f"mode {i}", f) for i, f in enumerate(PAPER_AT_REST)])
            for p in torsion}
    rest.update({e: _modes(e, [(f"mode {i}", f) for i, f in enumerate(ENGINE_AT_REST)],
                           {"model_differences": {"sections": SECTIONS_AT_REST}})
                 for e in mstmm_frames.ENGINES})
    return at_speed, rest


def _explain(paper_scale=1.0, mujoco=None):
    params = calibrate.sample(SCENE, 20, 2026)[17][1]
    assert params["speed"] == pytest.approx(57.72247797120145)
    tol = SCENE.tolerances_for(params)
    at_speed, rest = _runs(paper_scale, mujoco)
    comparisons = metrics.frequency_comparisons(list(at_speed.values()), tol)
    rows, _ = mstmm_frames.explain(
        params, comparisons, lambda n, p: (rest if p["speed"] == 0 else at_speed)[n], tol)
    return comparisons, rows


def test_every_engine_paper_difference_at_set_17_is_the_frame():
    comparisons, rows = _explain()
    bad = [c for c in comparisons if c.verdict == Verdict.DISAGREE]
    assert all((c.a in mstmm_frames.ENGINES) != (c.b in mstmm_frames.ENGINES) for c in bad)
    assert len(rows) == len(bad) >= 8
    assert all(r["frame"] for r in rows), [r["why"] for r in rows if not r["frame"]]
    # the paper's torsion root (15.20888 Hz, fem's differential) lies above the engines' last
    # mode, their torsion cyclic 1 (15.15316 Hz), and they list no torsion collective or
    # differential: its twin is past their list, so it pairs with none (it met the torsion
    # cyclic across kinds, and that pair's difference was put down to the frame)
    at_speed, _ = _runs()
    unpaired = metrics.unpaired_modes(list(at_speed.values()), SCENE.tolerances_for(
        calibrate.sample(SCENE, 20, 2026)[17][1]))
    torsion = [u for u in unpaired if u["mode"].startswith("torsion")
               and u["solver"] in mstmm_frames.PAPER
               and set(mstmm_frames.ENGINES) & {u["a"], u["b"]}]
    assert len(torsion) == 4 and all("past the other's list" in u["reason"] for u in torsion)


def test_a_seeded_one_percent_paper_error_stays_unexplained():
    comparisons, rows = _explain(paper_scale=1.01)
    unexplained = [r for r in rows if r["a"] == "mstmm" or r["b"] == "mstmm"]
    assert unexplained and not any(r["frame"] for r in unexplained)


def test_a_differential_modes_allowance_is_its_blade_modes_shift():
    """Set 7 (Ω 64.3 rad/s, chord 0.41 m on a 4.48 m blade): lag differential 1, mstmm
    12.38036 Hz against the engines' 12.36114 Hz, 1.55e-3 apart; the blade's closed-form
    rotary-inertia shift of lag 1 there is 1.62e-3. Its allowance holds the measured
    difference within 1–10 × (the allowance models' claim); 1 % more does not pass."""
    params = calibrate.sample(SCENE, 20, 2026)[7][1]
    allowance = mstmm.differential_allowances(params)["lag differential 1"]
    measured = abs(12.38036 / 12.36114 - 1)
    assert 1 <= allowance / measured <= 10, (allowance, measured)
    tol = SCENE.tolerances_for(params)
    for f, verdict in ((12.38036, Verdict.AGREE), (12.38036 * 1.01, Verdict.DISAGREE)):
        c, = metrics.frequency_comparisons(
            [_modes("mstmm", [("lag differential 1", f)]),
             _modes("exudyn", [("lag differential 1", 12.36114)])], tol)
        assert c.verdict == verdict, c.decided_by


def test_an_engine_without_differential_modes_borrows_the_other_engines():
    """Where one engine's list holds no differential mode (seed 2026 set 18: MuJoCo's first
    eight roots reach none), the rotor is confirmed by the other engine's, since the two are
    one discrete model agreeing root by root — and not when they disagree (one of MuJoCo's
    fuselage modes 1 % off)."""
    no_differential = [(r, e) for r, e in zip(ENGINE_AT_SPEED, ERRORS["mujoco"])
                       if "differential" not in r[0]]
    _, rows = _explain(mujoco=no_differential)
    mujoco = [r for r in rows if "mujoco" in (r["a"], r["b"])]
    assert mujoco and all(r["frame"] for r in mujoco), [r["why"] for r in mujoco]
    off = [((n, f * 1.01 if n == "fuselage 2" else f), e) for (n, f), e in no_differential]
    _, rows = _explain(mujoco=off)
    mujoco = [r for r in rows if "mujoco" in (r["a"], r["b"])]
    assert mujoco and not any(r["frame"] for r in mujoco)
