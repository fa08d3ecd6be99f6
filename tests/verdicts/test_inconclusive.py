"""No agree without power: a deviation within the bound is `inconclusive`, not `agree`, when one
solver's own error bar exceeds the allowance and INCONCLUSIVE_FRACTION of the channel's scale —
such a pair would agree with almost anything. `inconclusive` is never counted as agreement."""
import json

import numpy as np
import pytest

import xval
from compare.analysis.metrics import INCONCLUSIVE_FRACTION, deviation, frequency_comparisons
from compare.analysis.trajectory import Modes, Trajectory
from tests.conftest import xval as xval_cli

T = np.linspace(0.0, 1.0, 11)


def _traj(solver, value, error):
    """A run whose channel "x" holds `value` everywhere, its own error estimate `error`."""
    return Trajectory("synthetic", solver, T, {"x": np.full_like(T, value)},
                      errors={"x": np.full_like(T, error)})


@pytest.mark.parametrize("err_a, offset, allowance, verdict", [
    (0.5, 1e-3, 1e-6, "inconclusive"),   # a's bar 5 % of the scale 10: it would agree with ~all
    (1e-3, 1e-3, 1e-6, "agree"),         # a's bar 0.01 % of the scale: a real agreement
    (0.5, 2.0, 1e-6, "disagree"),        # beyond the bound: disagree outranks inconclusive
    (0.5, 1e-3, 0.2, "agree"),           # the bar within the scene's allowance (2): no less sharp
])
def test_a_wide_error_bar_makes_an_agreement_inconclusive(err_a, offset, allowance, verdict):
    c = deviation(_traj("a", 10.0, err_a), _traj("b", 10.0 + offset, 1e-4), "x", allowance)
    assert c.verdict == verdict, c.decided_by
    assert ("a's own error bar" in c.decided_by) == (verdict == "inconclusive")
    if verdict == "inconclusive":
        assert "5 % of scale" in c.decided_by and c.shown == "inconclusive"


def test_the_fraction_is_of_the_scale():
    # just below and just above the fraction, with the allowance far below both
    below, above = (deviation(_traj("a", 10.0, f * INCONCLUSIVE_FRACTION * 10.0),
                              _traj("b", 10.0, 0.0), "x", 1e-9) for f in (0.9, 1.1))
    assert below.verdict == "agree" and above.verdict == "inconclusive"


def test_an_energy_balance_is_judged_against_the_energy_it_balances():
    """A residual at round-off (3e-10 J) with an error bar of 3e-9 J is sharp against the 5 J
    it balances (6e-10 of it), not inconclusive for being 10 × its own size."""
    from types import SimpleNamespace

    from compare.scenes.base import TimeScene
    runs = [Trajectory("synthetic", s, T, {"energy_balance": np.full_like(T, v),
                                            "energy": np.full_like(T, 5.0)},
                       errors={"energy_balance": np.full_like(T, 3e-9)})
            for s, v in (("a", 3e-10), ("b", -3e-10))]
    scene = SimpleNamespace(energy_channel="energy_balance", energy_scale_channels=("energy",))
    scales = TimeScene.power_scales(scene, runs)
    assert scales == {"energy_balance": 5.0}
    judged = deviation(*runs, "energy_balance", 1e-9, scales["energy_balance"])
    alone = deviation(*runs, "energy_balance", 1e-9)
    assert judged.verdict == "agree" and alone.verdict == "inconclusive", alone.decided_by


def test_a_frequency_with_a_wide_error_bar_is_inconclusive():
    tol = {"frequency": 1e-6}
    a = Modes("s", "a", np.array([10.0, 20.0]), ["m1", "m2"],
              extra={"frequency_error_hz": [0.5, 1e-5]})
    b = Modes("s", "b", np.array([10.001, 20.0]), ["m1", "m2"],
              extra={"frequency_error_hz": [1e-5, 1e-5]})
    by = {c.channel: c for c in frequency_comparisons([a, b], tol)}
    assert by["m1"].verdict == "inconclusive" and "a's own error bar 0.5 Hz" in by["m1"].decided_by
    assert by["m2"].verdict == "agree"


# --- end to end: the rotor at a step 50x its default ----------------------------------------

# RK4 at h = 0.05 s through the spin-up (torque 3.2 N·m, 2 s): euler-vector's own error on |ω|
# is 1.3 rad/s, 3 % of the 41 rad/s reached; quaternion's 0.015 rad/s (0.04 %)
COARSE = ["rotor-spinup", "--set", "torque=3.2", "--set", "t_end=2", "--dt", "0.05",
          "--solver", "euler-vector", "--solver", "quaternion", "--solver", "mujoco",
          "--no-record"]


def test_a_coarse_run_is_inconclusive_not_agree(tmp_path):
    rc, out, err = xval_cli("run", *COARSE, "--out", tmp_path / "a", "--json")
    assert rc == 0, err
    by = {(c["a"], c["b"], c["channel"]): c for c in json.loads(out)["comparisons"]}
    for b in ("quaternion", "mujoco"):
        c = by[("euler-vector", b, "omega_norm")]
        assert c["verdict"] == "inconclusive", c["decided_by"]
        assert c["decided_by"].startswith("euler-vector's own error bar")
    assert not any(c["verdict"] == "agree" for (a, _, ch), c in by.items()
                   if a == "euler-vector" and ch in ("omega_norm", "spin_rate", "tilt"))
    assert by[("quaternion", "mujoco", "omega_norm")]["verdict"] == "agree"

    rc, out, err = xval_cli("run", *COARSE, "--out", tmp_path / "b", "--strict")
    assert rc == 1
    assert "--strict" in err and "euler-vector vs quaternion omega_norm: inconclusive" in err


def test_assert_agree_fails_on_inconclusive(tmp_path):
    r = xval.run("rotor-spinup", ["euler-vector", "quaternion"], dt=0.05, out=tmp_path,
                 record=False, params={"torque": 3.2, "t_end": 2})
    n = sum(c.verdict == "inconclusive" for c in r.comparisons)
    assert n and f", {n} inconclusive" in r.title()
    with pytest.raises(AssertionError, match="inconclusive"):
        xval.assert_agree(r, "omega_norm")


def test_a_default_run_stays_agree(tmp_path):
    rc, out, err = xval_cli("run", "rotor-spinup", "--set", "t_end=1", "--no-record",
                            "--out", tmp_path, "--json")
    assert rc == 0, err
    verdicts = [c["verdict"] for c in json.loads(out)["comparisons"]]
    assert verdicts and set(verdicts) == {"agree"}


@pytest.mark.parametrize("failed, offset, verdict", [
    (True, 1e-3, "incomplete"),     # beyond the allowance with one bar missing: not judged
    (True, 1e-9, "agree"),          # within the allowance alone: no bar needed
    (False, 1e-3, "disagree"),      # a run with no estimate to make is judged on the allowance
])
def test_a_failed_error_estimate_is_never_a_disagreement(failed, offset, verdict):
    """A solver whose error estimate failed (a rerun it needs stopped: Exudyn's half step
    through a singular passage of a drawn n-four-bar, 10 s) has no error bar; 16 comparisons
    became `disagree` at Δ/bound up to 1e9 against the allowance alone."""
    stats = {"error_estimate_failed": "dt 0.0005: diverged"} if failed else {}
    a = Trajectory("synthetic", "a", T, {"x": np.full_like(T, 10.0)}, stats=stats)
    c = deviation(a, _traj("b", 10.0 + offset, 1e-4), "x", 1e-9)
    assert c.verdict == verdict, c.decided_by
    assert ("a's error estimate failed (dt 0.0005: diverged)" in c.decided_by) == \
        (verdict == "incomplete")
