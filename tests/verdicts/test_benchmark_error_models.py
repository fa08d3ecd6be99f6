"""The benchmark scenes' numerical and modelling differences as models (issue 47, item 2), each
against what another solver measures at ≥ 5 parameter sets (`xval calibrate`'s draws, seed 11):
Exudyn's n-four-bar closure rounding (in every run's error estimate: the rigid chain's spread
is 0 in exact arithmetic) and MuJoCo's soft-contact root shift on the bicycle (an allowance):
each must cover the measurement and stay within its stated factor of it."""
import numpy as np
import pytest

from compare import solvers
from compare.physics import bicycle as bike
from compare.physics import nfourbar as n4
from compare.scenes import benchmarks_bicycle as bicycle_scene
from compare.scenes import get_scene
from compare.workflows import calibrate as cal

EPS = np.finfo(float).eps
N4 = get_scene("n-four-bar")
BIKE = get_scene("bicycle")


def _sets(scene, ks):
    drawn = cal.sample(scene, max(ks) + 1, seed=11)
    return [drawn[k][1] for k in ks]


# sets 19 (a passage 3.6e-4 from φ = −π: 1.1e-10 rad), 6 (no passage: 1.8e-14), 5, 9, 10
@pytest.mark.parametrize("params", _sets(N4, [19, 6, 5, 9, 10]), ids=["19", "6", "5", "9", "10"])
def test_exudyn_closure_rounding_covers_the_chains_spread(params):
    ex = solvers.get_solver("exudyn")
    tr = solvers.simulate(N4, ex, params, solvers.settings_for(ex, N4.name,
                                                               t_out=N4.output_grid(params)))
    assert tr.status == "ok"
    spread = np.asarray(tr.channels["parallelogram"])
    model = n4.closure_rounding(tr.channels, params)
    assert np.all(spread <= model)
    # the model's constant over what each set needs: measured 1.5–15 over the 20 draws
    need = np.max(spread * np.abs(np.sin(tr.channels["phi"]))) / (EPS * (params["N"] + 1))
    assert 1.0 <= n4.CLOSURE_ROUNDING / need <= 16.0


def _weave(lam):
    lam = np.asarray(lam, complex)
    return lam[lam.imag > 0]


# the defaults and five draws: stable and unstable weaves, 2.5–9 m/s, set 19 nearly real
@pytest.mark.parametrize("params", [BIKE.resolve({})] + _sets(BIKE, [0, 2, 5, 8, 19]),
                         ids=["default", "0", "2", "5", "8", "19"])
def test_mujoco_contact_lag_allowance(params):
    m = solvers.modes(BIKE, solvers.get_solver("mujoco"), params)
    assert m.status == "ok"
    lam_m = _weave([complex(*r) for r in m.extra["eigenvalues"]])
    lam_p = _weave(bike.eigenvalues(params, float(params["speed"])))
    assert len(lam_m) == len(lam_p) == 1
    dev = abs(lam_m[0] - lam_p[0])
    r = bicycle_scene.CONTACT_LAG * bicycle_scene.MUJOCO_TC * abs(lam_p[0]) ** 2
    assert 1.0 <= r / dev <= 10.0, (r, dev)
    # the verdicts' allowances (frequency relative, ζ absolute) cover what MuJoCo moves
    f_rel, d_zeta = bicycle_scene._contact_shifts(params)
    assert abs(lam_m[0].imag - lam_p[0].imag) <= f_rel * lam_p[0].imag
    zeta = [-x.real / abs(x) for x in (lam_m[0], lam_p[0])]
    assert abs(zeta[0] - zeta[1]) <= d_zeta


def test_damping_shift_is_the_arg_change_within_the_disc():
    """ζ over a circle of radius r about λ, sampled densely: its largest change is the one
    `damping_shift` gives (a near-real root and a lightly damped one), and never above the
    2 r/|λ| it replaces."""
    for lam, r in ((1.6334 + 0.19744j, 7.4e-3), (-0.775 + 4.46j, 1e-3), (0.3 + 0.01j, 0.05)):
        z = lam + r * np.exp(1j * np.linspace(0, 2 * np.pi, 400001))
        brute = np.max(np.abs(-z.real / np.abs(z) + lam.real / abs(lam)))
        got = float(bike.damping_shift(lam, r)[0])
        assert got == pytest.approx(brute, rel=1e-6)
        assert got <= 2 * r / abs(lam)
