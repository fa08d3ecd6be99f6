"""Calibration of the benchmark scenes (docs/commands/calibrate.md): the bicycle refuses a body
that no mass distribution has and draws only rigid ones; Exudyn's bicycle roots are judged
against the paper's equations (their truth) and a design 1 % off in one solver disagrees;
andrews-squeezer's energy rule weighs the balance against the spring's energy too, so MuJoCo's
soft loops, which take up 1e-9 J of a 2.3 J spring, are no divergence."""
import numpy as np
import pytest

from compare import solvers
from compare.errors import BadInput
from compare.scenes import get_scene
from compare.workflows import calibrate as cal

BODIES = (("I_Rxx", "I_Ryy", "I_Rxx", None), ("I_Bxx", "I_Byy", "I_Bzz", "I_Bxz"),
          ("I_Hxx", "I_Hyy", "I_Hzz", "I_Hxz"), ("I_Fxx", "I_Fyy", "I_Fxx", None))


def _second_moments(p, xx, yy, zz, xz):
    """J = ∫ r rᵀ dm = tr(I)/2 · 1 − I: a mass distribution's is positive semi-definite (the
    triangle inequality of I's principal moments, stated another way)."""
    c = p[xz] if xz else 0.0
    inertia = np.array([[p[xx], 0.0, c], [0.0, p[yy], 0.0], [c, 0.0, p[zz]]])
    return np.trace(inertia) / 2 * np.eye(3) - inertia


def test_the_bicycle_refuses_a_body_no_mass_distribution_has():
    scene = get_scene("bicycle")
    scene.resolve({"I_Ryy": 2 * 0.0603})                   # a thin disc: at the bound, rigid
    for over in ({"I_Ryy": 0.13}, {"I_Byy": 12.5}, {"I_Hyy": 0.07}, {"I_Bxz": 6.0}):
        with pytest.raises(BadInput, match="triangle inequality"):
            scene.resolve(over)


def test_the_bicycle_region_draws_rigid_bodies_only():
    scene = get_scene("bicycle")
    for _, p in cal.sample(scene, 40, seed=5):
        for body in BODIES:
            assert np.linalg.eigvalsh(_second_moments(p, *body))[0] >= -1e-15, (body, p)


def test_exudyns_bicycle_roots_are_judged_against_the_equations():
    r = cal.calibrate("bicycle", 2, seed=11, solvers=["meijaard", "exudyn"])
    assert r["comparisons"] and not r["disagree"]
    assert r["by_solver"]["exudyn"]["pairs"] and not r["by_solver"]["exudyn"]["left_out"]
    assert r["coverage"] >= 0.95


def test_a_design_one_percent_off_in_one_bicycle_solver_disagrees(monkeypatch):
    leaf = solvers.get_solver("meijaard").leaf(get_scene("bicycle"))
    honest = leaf.modes
    monkeypatch.setattr(leaf, "modes", lambda p, s: honest({**p, "I_Bxx": 1.01 * p["I_Bxx"]}, s))
    r = cal.calibrate("bicycle", 2, seed=11, solvers=["meijaard", "exudyn"])
    assert r["disagree"] and r.problems()


def test_mujocos_soft_loops_are_no_divergence_of_the_squeezer():
    # the first calibration set of seed 11: the drawn spring holds the crank against the motor
    # (kinetic energy 1.4e-9 J after 3 ms against a spring energy ½ c0 (ℓ − l0)² of 2.26 J)
    scene = get_scene("andrews-squeezer")
    _, params = cal.sample(scene, 1, seed=11)[0]
    mj = solvers.get_solver("mujoco")
    run = solvers.simulate(scene, mj, params, solvers.settings_for(
        mj, scene.name, t_out=scene.output_grid(params)))
    assert run.status == "ok", run.reason
    assert np.max(run.channels["kinetic_energy"]) < 1e-8
    assert np.min(run.channels["spring_energy"]) > 1.0


@pytest.mark.slow
def test_exudyns_four_bar_bars_are_checked_against_the_rigid_chain():
    # its own dt/16 run stops where every rod lies horizontal; lagrange-partial's far tighter
    # run of the same rigid chain is its truth
    r = cal.calibrate("n-four-bar", 1, seed=11, solvers=["lagrange-partial", "exudyn"])
    assert not r["disagree"] and not r["by_solver"]["exudyn"]["left_out"]
    assert r["by_solver"]["exudyn"]["pairs"]
