"""A leaf's accuracy knobs as xval reads them (compare/leafinfo.py) and the error they add to a
run's estimate (compare/solvers.py `_knob_errors`), against closed forms: a stand-in leaf whose
output is y = 1 + a·h² + b·h⁴ (a finite-difference step h) or 1 + c·s⁻⁴ (a ratio s that grows
toward the limit) has a known true error, which the estimate must contain without being more
than twice as wide."""
import types

import numpy as np
import pytest

from compare import leafinfo, solvers


def _info(**attrs):
    return leafinfo._build(types.ModuleType("stand_in_leaf", None) if not attrs else
                           types.SimpleNamespace(__name__="stand_in_leaf", **attrs))


def test_fixed_and_adaptive_tighter_settings_and_factors():
    info = _info(DEFAULT_SETTINGS={"integrator": "rk4", "dt": 1e-3},
                 INTEGRATORS=("rk4", "dop853"), ADAPTIVE=("dop853",))
    tight, factor, how = info.tighter({"integrator": "rk4", "dt": 1e-3})
    # an order-p method's error is 2^p/(2^p − 1) ≤ 2 times |y − y_half|
    assert tight["dt"] == 5e-4 and factor == 2.0 and how == "dt 0.0005"
    tight, factor, _ = info.tighter({"integrator": "dop853", "rtol": 1e-8})
    # a tolerance 100× tighter keeps up to 100^(-1/2) of the error: factor 1/(1 − 1/10)
    assert tight["rtol"] == pytest.approx(1e-10) and factor == pytest.approx(10 / 9)


def test_snap_divides_the_output_step():
    assert leafinfo.snap(3e-4, 1e-3) == pytest.approx(2.5e-4)      # 4 whole steps
    assert leafinfo.snap(1e-3, 1e-3) == pytest.approx(1e-3)


def test_a_step_knob_halves_and_a_ratio_knob_doubles():
    info = _info(KNOBS={"h": 2, "s": -4})
    s = {"h": 0.1, "s": 4.0, "other": 1}
    reruns = {k.name: t for k, t in info.knob_reruns(s)}
    assert reruns["h"] == {**s, "h": 0.05} and reruns["s"] == {**s, "s": 8.0}
    assert info.refined(s, 4) == {**s, "h": 0.1 / 16, "s": 64.0}
    assert info.knob_reruns({"h": None, "s": 0}) == []      # unset knobs are not varied


def test_a_reference_refines_a_knob_no_further_than_its_declared_limit():
    """y = 1 + a·h² + δ/h² (a central difference rounded by δ): its error is least at
    h* = (δ/a)^¼, so a reference run at h/16 is worse than at h/2 where h is near h*; a leaf
    declares the halvings (`KNOB_LIMITS`) and `refined` stops there, while the error estimate
    still halves the knob once."""
    info = _info(KNOBS={"h": 2, "s": -4}, KNOB_LIMITS={"h": 1})
    s = {"h": 0.1, "s": 4.0}
    assert info.refined(s, 4) == {**s, "h": 0.05, "s": 64.0}
    assert {k.name: t for k, t in info.knob_reruns(s)}["h"] == {**s, "h": 0.05}
    a, delta = 1.0, 1e-4 ** 4                    # h* = 1e-4, the run's step 2h*

    def err(h):
        return a * h * h + delta / (h * h)
    h = 2e-4
    assert err(h / 2) < err(h / 16) and err(h / 2) < err(h)


def _estimate(monkeypatch, knobs, output, settings):
    """The knob part of the error estimate of a stand-in run at `settings`."""
    info = _info(KNOBS=knobs)
    t = np.linspace(0.0, 1.0, 11)

    def run(scene, solver, params, s, timeout_s, warm_up, t_out):
        return types.SimpleNamespace(channels={"y": output(s) * (1 + t)}, status="ok",
                                     reason="", wall_s=0.0)
    monkeypatch.setattr(solvers, "_simulate", run)
    tr = types.SimpleNamespace(channels={"y": output(settings) * (1 + t)}, t=t, errors={},
                               stats={"error_estimate_by": "dt"})
    scene = types.SimpleNamespace(channels=("y",))
    solvers._knob_errors(scene, types.SimpleNamespace(info=lambda sc: info), {}, settings, tr,
                         None)
    return float(np.max(tr.errors["y"])), 2.0       # the true error's max over t: |y − 1|·2


# (a, b, widest): the h⁴ term of either sign; where it cancels half the h² term at 2h (the
# coarse member outside the asymptotic range) the measured ratio grows and the bar widens
@pytest.mark.parametrize("a, b, widest", [(1.0, 0.0, 2), (1.0, 30.0, 2), (1.0, -30.0, 2),
                                          (-2.0, 20.0, 2), (-2.0, 50.0, 3)])
def test_step_knob_error_contains_the_truth(monkeypatch, a, b, widest):
    h = 0.1
    est, t_max = _estimate(monkeypatch, {"h": 2}, lambda s: 1 + a * s["h"] ** 2 + b * s["h"] ** 4,
                           {"h": h})
    true = abs(a * h**2 + b * h**4) * t_max
    assert true <= est <= widest * true


def test_ratio_knob_error_contains_the_truth(monkeypatch):
    est, t_max = _estimate(monkeypatch, {"s": -4}, lambda s: 1 + 3.0 / s["s"] ** 4, {"s": 4.0})
    true = 3.0 / 4.0**4 * t_max
    assert true <= est <= 2 * true


def test_a_knob_that_does_not_converge_gives_the_spread(monkeypatch):
    # the output jumps about with h: the three runs' spread, doubled, bounds it
    vals = {0.1: 1.0, 0.05: 1.3, 0.2: 0.8}
    est, _ = _estimate(monkeypatch, {"h": 2}, lambda s: vals[round(s["h"], 6)], {"h": 0.1})
    assert est == pytest.approx(2 * 0.5 * 2.0)
