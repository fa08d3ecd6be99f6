"""Exudyn and MuJoCo models of the two-bearing rotor (scene `bearing-rotor`) against closed forms
written here, the custom `quaternion` solver, the energy balance, and at the extremes.

Reference numbers come from outside the leaves: the static sag m g/(2 k_b), the motor/friction
balance solved here with brentq, the exponential spin-up J_p ω' = M(ω) once tanh has saturated
(linear in ω), the custom solver (a different formulation: second-order quaternion equation),
and the energy balance. Tolerances are ~10x the deviations measured on 2026-11-23 (in comments).
"""
import math

import numpy as np
import pytest
from scipy.optimize import brentq

from compare.scenes.bearing import BEARING_ROTOR as SCENE
from reference_models.exudyn import bearing_rotor as exudyn_leaf
from reference_models.mujoco import bearing_rotor as mujoco_leaf

ENGINES = {"exudyn": exudyn_leaf, "mujoco": mujoco_leaf}
JOURNALS = ("journal_a_x", "journal_a_y", "journal_b_x", "journal_b_y")


def run(leaf, settings=None, **overrides):
    params = SCENE.resolve(overrides)
    t = SCENE.output_grid(params)
    return params, t, leaf.simulate(params, t, settings or {})


def energy_closure(res):
    """Largest |E(t) − E(0)| relative to the final motor work."""
    e = res.channels["energy_balance"]
    return float(np.nanmax(np.abs(e - e[0])) / np.nanmax(np.abs(res.channels["motor_work"])))


# ---------------------------------------------------------------- defect-free closed forms
@pytest.fixture(scope="module")
def settled():
    """No defect, 2 s (22 spin-up time constants), coarse grid."""
    return {name: run(leaf, defect_height=0, t_end=2, output_dt=0.01)
            for name, leaf in ENGINES.items()}


@pytest.mark.parametrize("engine", ENGINES)
def test_static_sag_and_steady_spin(settled, engine):
    params, t, res = settled[engine]
    assert res.status == "ok", res.reason
    c = res.channels
    g_radial = math.hypot(*params["gravity"][:2])
    sag = params["m"] * g_radial / (2 * params["k_b"])
    # the start is the static sag and nothing radial excites the journals: measured 0.0 m
    for name in ("journal_a_y", "journal_b_y"):
        assert np.max(np.abs(c[name] + sag)) <= 1e-15
    for name in ("journal_a_x", "journal_b_x"):
        assert np.max(np.abs(c[name])) <= 1e-15

    def net_moment(w):   # motor − drag − Coulomb-like friction at the static bearing loads
        return (params["motor_stall_torque"] * (1 - w / params["motor_no_load_speed"])
                - params["bearing_drag"] * w
                - params["mu"] * params["r_j"] * params["m"] * g_radial * math.tanh(w / 0.1))

    w_ss = brentq(net_moment, 1.0, params["motor_no_load_speed"], xtol=1e-13, rtol=1e-15)
    # measured: 1.7e-10 relative after 2 s (the exponential tail, e^(−2/0.089) of 70 rad/s)
    assert abs(c["spin_rate"][-1] / w_ss - 1) <= 1e-9
    # once tanh(ω/0.1) = 1 the spin-up is linear: ω − ω_ss decays as e^(−t/τ) exactly
    tau = params["J_p"] / (params["motor_stall_torque"] / params["motor_no_load_speed"]
                           + params["bearing_drag"])
    i0, i1 = np.searchsorted(t, [0.3, 0.8])
    d = c["spin_rate"][i0:i1 + 1] - w_ss
    pred = d[0] * np.exp(-(t[i0:i1 + 1] - t[i0]) / tau)
    # measured: MuJoCo RK4 2.2e-13 rad/s; Exudyn DOPRI5 2.8e-7 rad/s (Hermite interpolation of
    # its up-to-10-ms steps onto this coarse grid, rtol 1e-10 on a ~100 rad spin angle)
    tol = {"mujoco": 3e-12, "exudyn": 3e-6}[engine]
    assert np.max(np.abs(d - pred)) <= tol
    # measured: 6.8e-14 (MuJoCo), 4.1e-9 (Exudyn) of the motor work
    assert energy_closure(res) <= {"mujoco": 1e-12, "exudyn": 4e-8}[engine]


# ---------------------------------------------------------------- default run with the defect
@pytest.fixture(scope="module")
def default_runs():
    return {name: run(leaf) for name, leaf in ENGINES.items()}


@pytest.mark.parametrize("engine", ENGINES)
def test_energy_balance_closes(default_runs, engine):
    _, _, res = default_runs[engine]
    assert res.status == "ok", res.reason
    # measured: 1.0e-8 (MuJoCo RK4 50 µs), 1.3e-8 (Exudyn DOPRI5 1e-10) of the motor work
    assert energy_closure(res) <= 1.3e-7
    assert res.channels["motor_work"][-1] > 20.0          # the run did spin up (28.8 J)


@pytest.mark.parametrize("engine", ENGINES)
def test_ripple_once_per_revolution(default_runs, engine):
    """Spin rate against spin angle after the spin-up: periodic in 2π, not in π."""
    _, t, res = default_runs[engine]
    keep = t >= 1.5
    phi, w = res.channels["spin_angle"][keep], res.channels["spin_rate"][keep]
    n_rev, m = int((phi[-1] - phi[0]) // (2 * np.pi)), 64
    s = np.interp(phi[0] + np.arange(n_rev * m) * 2 * np.pi / m, phi, w)
    s -= s.mean()
    assert np.ptp(s) > 1e-2                                 # the defect ripple (0.037 rad/s)
    # measured: 1 − corr = 1.8e-5 one revolution apart; corr 0.148 half a revolution apart
    assert np.corrcoef(s[:-m], s[m:])[0, 1] >= 1 - 2e-4
    assert np.corrcoef(s[:-m // 2], s[m // 2:])[0, 1] <= 0.5
    # spectrum over n_rev whole revolutions: only harmonics of once-per-revolution (measured
    # 1.7e-5 of the power elsewhere: the spin-up's tail and linear interpolation)
    power = np.abs(np.fft.rfft(s)) ** 2
    off = np.arange(power.size) % n_rev != 0
    assert power[off].sum() <= 2e-4 * power.sum()


@pytest.mark.parametrize("engine", ENGINES)
def test_extra_arrays(default_runs, engine):
    params, t, res = default_runs[engine]
    q = res.extra["orientation"]
    assert q.shape == (len(t), 4) and np.allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-12)
    for key, ch in (("journal_a", "journal_a_"), ("journal_b", "journal_b_")):
        j = res.extra[key]
        assert j.shape == (len(t), 3)
        assert np.array_equal(j[:, 0], res.channels[ch + "x"])
    # journal a sits at +l/2 along the shaft (axial sag 0 with g_z = 0)
    assert np.allclose(res.extra["journal_a"][:, 2], params["l"] / 2, atol=1e-9)


def test_engines_agree_with_custom_quaternion_solver(default_runs):
    from custom_models.bearing import quaternion as custom
    params = SCENE.resolve({})
    t = SCENE.output_grid(params)
    ref = custom.simulate(params, t, {})
    assert ref.status == "ok", ref.reason
    for engine, (_, _, res) in default_runs.items():
        c, r = res.channels, ref.channels
        journal = max(np.max(np.abs(c[k] - r[k])) for k in JOURNALS)
        # measured over the 3 s run: journals 2.1e-11 m (MuJoCo), 3.9e-11 m (Exudyn); spin rate
        # 1.3e-7 / 1.7e-7 rad/s; spin angle 1.1e-8 / 7e-11 rad (scene goal: 1e-8 m, 1e-4 rad/s)
        assert journal <= 4e-10, engine
        assert np.max(np.abs(c["spin_rate"] - r["spin_rate"])) <= 2e-6, engine
        assert np.max(np.abs(c["spin_angle"] - r["spin_angle"])) <= 1.1e-7, engine


# ---------------------------------------------------------------- extremes
def test_engines_agree_without_damping_and_with_a_large_defect():
    """c_b = 0 (nothing damps the journal orbit) and a 1 mm bump (34x the static sag: the
    journal is thrown up by ~1 mm and rings): both engines stay ok, close their energy
    balance and agree."""
    for over, tol_journal, tol_energy in (
            # measured: journals 2.6e-10 m apart; energy 3.5e-8 (MuJoCo) / 8.9e-9 (Exudyn)
            ({"c_b": 0.0, "t_end": 0.5}, 2.6e-9, 3.5e-7),
            # measured: journals 1.4e-7 m apart — MuJoCo's fixed RK4 step loses order at the
            # bump's edges (h'' jumps): 1.3e-7 m from the custom solver at rtol 1e-12, 4.5e-9 m
            # at dt = 1e-5; Exudyn's DOPRI5 4.3e-9 m. Energy 1.9e-5 (MuJoCo) / 1.4e-7 (Exudyn),
            # held to the scene's 1e-4 of the motor work
            ({"defect_height": 1e-3, "t_end": 0.5}, 1.4e-6, 1e-4)):
        runs = {name: run(leaf, **over)[2] for name, leaf in ENGINES.items()}
        for name, res in runs.items():
            assert res.status == "ok", (over, name, res.reason)
            assert energy_closure(res) <= tol_energy, (over, name)
        a, b = runs["mujoco"].channels, runs["exudyn"].channels
        assert max(np.max(np.abs(a[k] - b[k])) for k in JOURNALS) <= tol_journal, over
    assert np.max(b["journal_a_y"]) > 5e-4            # the journal jumps (0.96 mm)


def test_stiff_bearings_adapt_or_say_diverged():
    """k_b = 1e9: the rocking mode at ~3.2e4 rad/s puts the RK4 stability limit at 88 µs. The
    engines' defaults (MuJoCo RK4 50 µs, Exudyn DOPRI5) run; a 100 µs fixed step must end
    `diverged` with the time and the stability reason, never with finite garbage."""
    for engine, leaf in ENGINES.items():
        params, t, res = run(leaf, k_b=1e9, t_end=0.2)     # the bump passes at ~0.17 s
        assert res.status == "ok", (engine, res.reason)
        assert np.max(res.channels["journal_a_y"]) > 1e-5
        # measured: 3.2e-6 (MuJoCo RK4 at 0.57 of its stability limit), 4.2e-10 (Exudyn)
        assert energy_closure(res) <= 3.2e-5, engine
    for engine, leaf, settings in (("mujoco", mujoco_leaf, {"dt": 1e-4}),
                                   ("exudyn", exudyn_leaf, {"integrator": "rk4", "dt": 1e-4})):
        params, t, res = run(leaf, settings, k_b=1e9, t_end=0.2)
        assert res.status == "diverged", engine
        assert 0 < res.t_fail <= 0.2 and "stability limit" in res.reason, (engine, res.reason)
        before = t < res.t_fail
        for name, v in res.channels.items():
            assert np.all(np.isnan(v[~before])), (engine, name)
            assert np.all(np.isfinite(v[before])), (engine, name)
        # what is left before t_fail is the physics, not the blow-up: journals stay near the bump
        assert np.max(np.abs(res.channels["journal_a_y"][before])) < 1e-4, engine


@pytest.mark.parametrize("engine", ENGINES)
def test_bad_settings_raise_value_error(engine):
    leaf = ENGINES[engine]
    params = SCENE.resolve({"t_end": 0.01})
    t = SCENE.output_grid(params)
    for bad in ({"integrator": "leapfrog"}, {"dt": -1.0, "integrator": "rk4"}, {"step": 1}):
        with pytest.raises(ValueError):
            leaf.simulate(params, t, bad)


def test_mujoco_python_callback_matches_native():
    params, t, native = run(mujoco_leaf, t_end=0.05)
    _, _, python = run(mujoco_leaf, {"callback": "python"}, t_end=0.05)
    assert native.settings["callback"] == "native" and python.settings["callback"] == "python"
    for name in native.channels:
        assert np.array_equal(native.channels[name], python.channels[name]), name


@pytest.mark.slow
def test_long_run_energy_and_agreement():
    """30 s (≈ 330 revolutions, 271 J of motor work) at the default settings."""
    from custom_models.bearing import quaternion as custom
    params = SCENE.resolve({"t_end": 30, "output_dt": 0.001})
    t = SCENE.output_grid(params)
    ref = custom.simulate(params, t, {}).channels
    for engine, leaf in ENGINES.items():
        res = leaf.simulate(params, t, {})
        assert res.status == "ok", (engine, res.reason)
        c = res.channels
        # measured: energy 1.1e-9 (MuJoCo) / 1.9e-8 (Exudyn) of the motor work; vs custom:
        # journals 2.1e-11 / 4.5e-11 m, spin rate 1.3e-7 / 1.6e-7 rad/s, angle 1.2e-8 / 2.4e-10 rad
        assert energy_closure(res) <= 1.9e-7, engine
        assert max(np.max(np.abs(c[k] - ref[k])) for k in JOURNALS) <= 4.5e-10, engine
        assert np.max(np.abs(c["spin_rate"] - ref["spin_rate"])) <= 1.6e-6, engine
        assert np.max(np.abs(c["spin_angle"] - ref["spin_angle"])) <= 1.2e-7, engine


def test_mujoco_threads_do_not_share_the_global_callback():
    """MuJoCo's passive callback is process-global: two runs in threads (as under Dask) must
    give what each gives alone."""
    from concurrent.futures import ThreadPoolExecutor
    cases = [{"t_end": 0.05}, {"t_end": 0.05, "k_b": 2e6}]
    alone = [run(mujoco_leaf, **c)[2].channels for c in cases]
    with ThreadPoolExecutor(2) as pool:
        both = list(pool.map(lambda c: run(mujoco_leaf, **c)[2].channels, cases))
    for a, b in zip(alone, both):
        assert all(np.array_equal(a[k], b[k]) for k in a)


@pytest.mark.parametrize("callback", ["native", "python"])
def test_mujoco_run_stops_if_its_callback_is_taken_away(monkeypatch, callback):
    """Another leaf's simulation in another thread may replace the global passive callback:
    the run must end `diverged`, not go on without its bearing forces. (native: rollout blocks
    of 10 output steps here; python: one mj_step call per output step.)"""
    import mujoco
    import mujoco.rollout

    calls = {"n": 0}
    steal_at = 2 if callback == "native" else 20

    def stealing(real):
        def wrapper(*args, **kwargs):
            out = real(*args, **kwargs)
            calls["n"] += 1
            if calls["n"] == steal_at:
                mujoco.set_mjcb_passive(None)
            return out
        return wrapper

    monkeypatch.setattr(mujoco_leaf, "_ROLLOUT_BLOCK", 100)
    monkeypatch.setattr(mujoco.rollout, "rollout", stealing(mujoco.rollout.rollout))
    monkeypatch.setattr(mujoco, "mj_step", stealing(mujoco.mj_step))
    params, t, res = run(mujoco_leaf, {"callback": callback}, t_end=0.05)
    assert res.settings["callback"] == callback
    assert res.status == "diverged" and "callback was replaced" in res.reason
    # native: the second block (outputs 11–20) is checked after it ran, from its first output
    assert res.t_fail == pytest.approx(t[11] if callback == "native" else t[20])


def test_mujoco_auto_step_follows_the_bearing_stiffness():
    """k_b = 1e10: the RK4 limit falls to 28 µs, below MuJoCo's default 50 µs step (the run says
    `diverged` with the reason); dt="auto" takes half the limit (14 µs) and runs."""
    params, t, res = run(mujoco_leaf, k_b=1e10, t_end=0.2)
    assert res.status == "diverged" and "stability limit ~2.79e-05 s" in res.reason
    params, t, res = run(mujoco_leaf, {"dt": "auto"}, k_b=1e10, t_end=0.2)
    assert res.status == "ok", res.reason
    assert res.settings["dt"] == pytest.approx(0.5 * 2.785 / math.sqrt(1e10 * 0.6**2 / 2 / 0.1806),
                                               rel=0.05)
    assert np.max(res.channels["journal_a_y"]) > 1e-5        # the bump passed
    assert energy_closure(res) <= 3.7e-6                      # measured 3.7e-7
    # at the default stiffness "auto" is the accurate default step
    assert run(mujoco_leaf, {"dt": "auto"}, t_end=0.01)[2].settings["dt"] == 5e-5


# measured energy closure over 0.3 s at each integrator's default step (MuJoCo's Euler family
# is first order and identical here: the bearing damping lives in the callback, not in MuJoCo's
# joint damping that implicit/implicitfast would treat implicitly)
OFFERED = [("exudyn", "rk4", 1.8e-7), ("exudyn", "rk67", 4.7e-8), ("exudyn", "rk23", 1.3e-8),
           ("exudyn", "generalized_alpha", 2.8e-7), ("mujoco", "euler", 1.9e-4),
           ("mujoco", "implicitfast", 1.9e-4), ("mujoco", "implicit", 1.9e-4)]


@pytest.mark.parametrize("engine, integrator, measured", OFFERED)
def test_every_offered_integrator_runs(engine, integrator, measured):
    settings = {"integrator": integrator, **({"rtol": 1e-8} if integrator == "rk23" else {})}
    params, t, res = run(ENGINES[engine], settings, t_end=0.3)
    assert res.status == "ok", res.reason
    assert res.settings["integrator"] == integrator
    assert energy_closure(res) <= 10 * measured


@pytest.mark.parametrize("engine", ENGINES)
def test_wall_clock_alarm_reaches_the_caller(engine):
    """The adapter's time limit raises a BaseException from SIGALRM; Exudyn wraps what a user
    function raises into its own error, so the leaf must raise the alarm again — not report
    `diverged`. (The handler often runs at a user function's entry, outside any try block in
    it: 6 of 10 alarms were lost that way before the leaf wrapped the handler itself.)"""
    import signal

    class Alarm(BaseException):
        pass

    def ring(signum, frame):
        raise Alarm()

    params = SCENE.resolve({"t_end": 20})
    t = SCENE.output_grid(params)
    previous = signal.signal(signal.SIGALRM, ring)
    try:
        signal.setitimer(signal.ITIMER_REAL, 0.5)
        with pytest.raises(Alarm):
            ENGINES[engine].simulate(params, t, {})
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
