"""The benchmark bicycle's engine models against the paper's published roots and speeds
(Meijaard et al. 2007, Table 2): Exudyn (rigid bodies, revolute hubs and steer axis, ideal
rolling-disc joints; roots fitted from a free response) — every root, real ones included,
within its own error bars; MuJoCo (soft contacts) within the allowance its contacts' measured
deviation sets."""
import numpy as np
import pytest
from scipy.optimize import brentq

from compare import solvers
from compare.scenes import get_scene
from compare.scenes.benchmarks_bicycle import _contact_shifts

SCENE = get_scene("bicycle")
EXUDYN = solvers.get_solver("exudyn")
MEIJAARD = solvers.get_solver("meijaard")
# Table 2 of the paper
AT_5 = [-0.32286642900409, complex(-0.77534188219585, 4.46486771378823),
        complex(-0.77534188219585, -4.46486771378823), -14.07838969279822]
AT_0 = [5.53094371765393, 3.13164324790656, -3.13164324790656, -5.53094371765393]
V_WEAVE, V_CAPSIZE = 4.292382536341, 6.024262015388


def _roots(solver, v):
    m = solvers.modes(SCENE, solver, SCENE.resolve({"speed": str(v)}))
    assert m.status == "ok", m.reason
    e = np.asarray(m.extra["eigenvalues"])
    return e[:, 0] + 1j * e[:, 1], np.asarray(m.extra["eigenvalue_error_per_s"]), m


def _within(lam, err, ref, what):
    ref = np.asarray(ref, complex)
    for x, e in zip(lam, err):
        d = np.min(np.abs(ref - x))
        assert d <= e, f"{what}: root {x:.8g} is {d:.2e} from the reference, bar {e:.2e}"
        assert e <= 1e-3 * max(abs(x), 1.0), f"{what}: bar {e:.2e} too wide to tell"


@pytest.mark.parametrize("v, ref", [(5.0, AT_5), (0.0, AT_0)])
def test_exudyn_roots_are_the_papers_within_their_error_bars(v, ref):
    lam, err, m = _roots(EXUDYN, v)
    assert len(lam) == 4
    _within(lam, err, ref, f"exudyn at {v} m/s")


@pytest.mark.slow
@pytest.mark.parametrize("v", [1.0, 2.0, 3.0, 4.0, 6.0, 7.0, 8.0, 9.0, 10.0])
def test_exudyn_roots_from_1_to_10_m_s_are_the_linear_equations(v):
    lam, err, _ = _roots(EXUDYN, v)
    ref, _, _ = _roots(MEIJAARD, v)
    _within(lam, err, ref, f"exudyn at {v} m/s")


@pytest.mark.slow
def test_exudyn_weave_and_capsize_speeds_by_root_finding():
    """The zeros of Exudyn's fitted growth rate (Brent to 1e-6 m/s), each with the bar its
    root's error gives through the slope: within it of the paper's speeds."""
    def growth(v):
        lam, err, _ = _roots(EXUDYN, v)
        i = int(np.argmax(lam.real))
        return float(lam[i].real), float(err[i])
    for v_ref, lo, hi in ((V_WEAVE, 4.2, 4.4), (V_CAPSIZE, 5.9, 6.1)):
        v = brentq(lambda x: growth(x)[0], lo, hi, xtol=1e-6)
        slope = (growth(v + 0.01)[0] - growth(v - 0.01)[0]) / 0.02
        bar = growth(v)[1] / abs(slope) + 1e-6
        assert abs(v - v_ref) <= bar, (v, v_ref, bar)
        assert bar < 1e-3


MUJOCO = solvers.get_solver("mujoco")


def test_mujoco_weave_is_the_papers_within_the_soft_contact_allowance():
    """MuJoCo's soft contacts move its roots (the scene's allowance for it, the contacts' lag:
    relative on the weave frequency and absolute on ζ); its own bars are far smaller."""
    lam, err, m = _roots(MUJOCO, 5.0)
    weave = AT_5[1]
    f_rel, d_zeta = _contact_shifts(SCENE.resolve({"speed": "5"}))
    assert m.labels == ["weave"]
    assert abs(m.frequencies_hz[0] * 2 * np.pi - weave.imag) <= f_rel * weave.imag
    assert abs(m.damping[0] + weave.real / abs(weave)) <= d_zeta
    # every real root off the paper's by < 0.5 % of its size
    for x in lam[lam.imag == 0]:
        assert np.min(np.abs(np.array(AT_5) - x)) <= 5e-3 * abs(x)


@pytest.mark.slow
def test_mujoco_deviation_is_the_soft_contact_linear_in_its_time_constant():
    """The weave's deviation from the paper halves with the contact's time constant (measured
    0.0105 and 0.0056 /s at 1e-3 and 5e-4 s): the soft contact is what moves it."""
    p = SCENE.resolve({"speed": "5"})
    dev = []
    for tc in (1e-3, 5e-4):
        m = solvers.modes(SCENE, MUJOCO, p, {"timeconst": tc})
        e = np.asarray(m.extra["eigenvalues"])
        lam = e[:, 0] + 1j * e[:, 1]
        dev.append(np.min(np.abs(lam - AT_5[1])))
    assert 1.6 <= dev[0] / dev[1] <= 2.4, dev
