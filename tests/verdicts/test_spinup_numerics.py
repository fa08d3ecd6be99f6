"""rotor-spinup's verdicts carry no numerical allowance (issue 47: a numerical difference is never
an allowance, it belongs to the error estimate): every pair is judged on its two error
estimates alone, which still hold the custom pair where the step controller's jitter is
largest, and a solver 1e-6 off in its torque or inertia disagrees."""
import sys
import types

import numpy as np
import pytest

from compare import solvers
from compare.analysis.metrics import allowance, allowance_channels
from compare.scenes.rotor import SPINUP
from compare.workflows import runner


def test_no_pair_has_a_numerical_allowance():
    names = list(SPINUP.leaves)
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            for ch in allowance_channels(SPINUP.tolerances):
                assert allowance(SPINUP.tolerances, a, b, ch) == 0.0, (a, b, ch)


def _verdicts(params, names):
    chosen = [solvers.get_solver(n) for n in names]
    res = runner.run_scene(SPINUP, params, chosen,
                           lambda s: solvers.settings_for(s, SPINUP.name), None,
                           record=False, report=False)
    return {(c.a, c.b, c.channel): c for c in res.comparisons}


def test_the_custom_pair_agrees_on_its_estimates_where_the_controller_jitters():
    """Torque 3.19999 N·m, 5 s: euler-vector's rtol-1e-13 rerun is 2e-9 J of work off the
    truth (its runs at rtol 1e-13·(1 + 4k eps) scatter by up to 4.6e-9 J) while halving its
    tolerance moved it 2.4e-10 J: with the tight run's error read as the change alone the pair
    stood at Δ/bound 1.002. The tail 3.41 × the largest change on halving and quartering the
    tolerance holds it."""
    by = _verdicts(SPINUP.resolve({"torque": 3.19999, "t_end": 5.0}),
                   ["euler-vector", "quaternion"])
    assert all(c.verdict == "agree" for c in by.values()), [c.decided_by for c in by.values()]
    work = by[("euler-vector", "quaternion", "work")]
    assert work.allowance == 0.0 and 0.1 < work.ratio < 1.0


@pytest.fixture
def slipped(monkeypatch):
    """A test double: the quaternion leaf with one input changed by a relative 1e-6."""
    from custom_models.rotor import quaternion as q

    def make(change):
        leaf = types.ModuleType("slip_leaf")
        leaf.DEFAULT_SETTINGS, leaf.INTEGRATORS, leaf.ADAPTIVE = (q.DEFAULT_SETTINGS,
                                                                  q.INTEGRATORS, q.ADAPTIVE)
        leaf.check_settings = q.check_settings
        leaf.simulate = lambda p, t, s: q.simulate(change(p), t, s)
        monkeypatch.setitem(sys.modules, "slip_leaf", leaf)
        monkeypatch.setitem(solvers.REGISTRY, "slip", solvers.Solver("slip", "test", "numba"))
        monkeypatch.setitem(SPINUP.leaves, "slip", "slip_leaf")
    return make


@pytest.mark.parametrize("what, change", [
    ("torque", lambda p: {**p, "torque": p["torque"] * (1 + 1e-6)}),
    # I_p = m R²/2: R·√(1 + 1e-6) puts the polar inertia 1e-6 off
    ("inertia", lambda p: {**p, "R": p["R"] * np.sqrt(1 + 1e-6)})])
def test_a_solver_1e_6_off_disagrees(slipped, what, change):
    """Before resonance the rotor spins up freely, |ω| ≈ M t / I_p: a relative 1e-6 in M or in
    I_p moves |ω(1 s)| by ~1e-6 of it, while the two solvers' error estimates there are
    ~1e-11 rad/s."""
    slipped(change)
    p = SPINUP.resolve({"t_end": 1.0})
    by = _verdicts(p, ["euler-vector", "quaternion", "slip"])
    honest = by[("euler-vector", "quaternion", "omega_norm")]
    assert honest.verdict == "agree"
    c = by[("euler-vector", "slip", "omega_norm")]
    ramp = p["torque"] * 1.0 / (p["m"] * p["R"] ** 2 / 2)
    assert c.verdict == "disagree"
    assert 0.5e-6 * ramp < c.deviation < 2e-6 * ramp
    assert c.deviation > 1e3 * c.error_estimate
