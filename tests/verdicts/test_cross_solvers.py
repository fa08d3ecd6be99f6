"""Each custom solver against an engine, per scene, in the default run (issue 26: a custom press
with J1 × 2 passed every default test while `xval run press` said `disagree` 20 times).

The engine is another implementation of the same physics, so this is the independent number:
the verdict is the scene's own (deviation ≤ both solvers' error estimates + the scene's
allowance), on a short case of each scene. `test_a_one_percent_error_in_the_custom_solver_is_a_
disagreement` proves the check's power on the press: J1 × 1.01 reaching both custom solvers.
"""
import functools

import numpy as np
import pytest

from compare import solvers
from compare.scenes import SCENES, get_scene

# short cases: time scenes a fraction of their horizon; the helicopters at rest, where the
# engines' physical aircraft and the paper's rotor-frame model are the same system
CASES = {"rotor-spinup": {"t_end": "1", "torque": "3.2"}, "press": {}, "press-cycle": {},
         # the scene's own stiffness: the engines' deployed length differs from the custom
         # models' by the thread's elastic stretch, ∝ 1/k (measured 2.1e-8 m at 1e5 N/m,
         # 2.1e-9 m at 1e6), and the allowance was measured at the default 1e7
         "sail-deploy": {"t_end": "0.5"}, "bearing-rotor": {"t_end": "0.2"},
         "rotor-whirl": {"spin": "41.3"}, "rotating-beam": {"speed": "40"},
         "spinning-shaft": {}, "helicopter-clamped": {"speed": "0", "n_modes": "6"},
         "helicopter-hover": {"speed": "0", "n_modes": "6"}}
# the engine each scene's custom solvers meet: the cheaper one at these cases
ENGINE = {"rotor-spinup": "mujoco", "press": "exudyn", "press-cycle": "exudyn",
          "sail-deploy": "mujoco", "bearing-rotor": "mujoco", "rotor-whirl": "mujoco",
          "rotating-beam": "exudyn", "spinning-shaft": "exudyn",
          "helicopter-clamped": "exudyn", "helicopter-hover": "exudyn"}
CASES["bicycle"], ENGINE["bicycle"] = {}, "exudyn"      # 5 m/s: the weave
CASES["andrews-squeezer"], ENGINE["andrews-squeezer"] = {}, "mujoco"   # the test set's run
CASES["bricard"], ENGINE["bricard"] = {"t_end": "2"}, "mujoco"   # to past the first swing
CASES["n-four-bar"], ENGINE["n-four-bar"] = {"N": "4", "t_end": "2"}, "exudyn"  # φ = 0, −π
PAIRS = [(sc, c) for sc in CASES for c in SCENES[sc].leaves
         if solvers.get_solver(c).engine not in ("exudyn", "mujoco")]


def _run(scene_name, solver, change=None):
    """`solver` on the scene's case (its parameters changed by `change`), at its defaults."""
    sc = get_scene(scene_name)
    p = sc.resolve(CASES[scene_name])
    q = change(p) if change else p
    s = solvers.get_solver(solver)
    if sc.is_modes:
        return solvers.modes(sc, s, q)
    return solvers.simulate(sc, s, q, solvers.settings_for(s, sc.name),
                            estimate_error=sc.error_estimate)


@functools.cache
def _engine_run(scene_name):
    """The scene's engine on its case: once per module, shared by the scene's custom solvers
    (the engine's inputs are the same for each; sail-deploy's MuJoCo run was half of each
    of its two tests)."""
    return _run(scene_name, ENGINE[scene_name])


def verdicts(scene_name, custom, change=None):
    """The scene's comparisons of `custom` (its parameters changed by `change`) with the
    scene's engine at the case's parameters."""
    sc = get_scene(scene_name)
    runs = [_run(scene_name, custom, change), _engine_run(scene_name)]
    assert all(r.status == "ok" for r in runs), [(r.solver, r.status, r.reason) for r in runs]
    return sc.verdicts(sc.resolve(CASES[scene_name]), runs)


@pytest.mark.parametrize("scene_name, custom", PAIRS, ids=lambda x: x)
def test_each_custom_solver_agrees_with_an_engine(scene_name, custom):
    cmp = verdicts(scene_name, custom)
    assert cmp, "nothing was compared"
    bad = [f"{c.channel}: {c.decided_by}" for c in cmp if c.verdict != "agree"]
    assert not bad, f"{custom} vs {ENGINE[scene_name]} on {scene_name}: " + "; ".join(bad)


@pytest.mark.parametrize("custom", ["lagrange-exact", "lagrange-partial"])
def test_a_one_percent_error_in_the_custom_solver_is_a_disagreement(custom):
    cmp = verdicts("press", custom, lambda p: {**p, "J1": p["J1"] * 1.01})
    worst = max(cmp, key=lambda c: c.max_abs / max(c.tolerance * c.scale, 1e-300))
    assert worst.verdict == "disagree", worst.decided_by
    assert np.isfinite(worst.max_abs)
