"""Exudyn and MuJoCo leaves of the `press` / `press-cycle` scenes against independent numbers.

Independent references used here: the other engine (two unrelated formulations: an index-3 DAE
in absolute coordinates with generalized-α, and a soft-constrained kinematic tree with RK4), the
loop-closure geometry re-evaluated from the output channels (|B − A| = l2), the closed-form
initial slider speed of a rigid rod, and the energy balance (a conservation law).
"""
import math

import numpy as np
import pytest

import reference_models.exudyn.press as ex  # hard dependencies: a broken import fails
import reference_models.mujoco.press as mj
from compare.scenes.press import PRESS, PRESS_CYCLE

# the scene's defaults, written out where a test computes with them (scene-press.md)
L1, L2, L3 = 0.015, 0.040, 0.030
PHI0, PSI0, OMEGA0 = -64.1, -46.34, 43.5
T_OUT = np.linspace(0.0, 0.05, 41)
CYCLE = PRESS_CYCLE.resolve({})

_cache = {}


def run(engine, params=None, settings=None, t_out=T_OUT):
    """A leaf run on the scene's resolved parameters (`params`: resolved, or overrides of
    `press`)."""
    params = params if params is not None and "l1" in params else PRESS.resolve(params or {})
    key = (engine.__name__, repr(sorted(params.items())),
           repr(sorted((settings or {}).items())), len(t_out), float(t_out[-1]))
    if key not in _cache:
        _cache[key] = engine.simulate(dict(params), t_out, dict(settings or {}))
    return _cache[key]


def rod_length(ch):
    """|B − A| from the channels alone: A = l1(cos φ, sin φ), B = (x_C + l3 cos ψ, l3 sin ψ)."""
    phi, psi, xc = ch["crank_angle"], ch["rocker_angle"], ch["slider_x"]
    ax, ay = L1 * np.cos(phi), L1 * np.sin(phi)
    bx, by = xc + L3 * np.cos(psi), L3 * np.sin(psi)
    return np.hypot(bx - ax, by - ay), bx - ax


@pytest.mark.parametrize("engine", [ex, mj], ids=["exudyn", "mujoco"])
def test_contract_and_initial_state(engine):
    r = run(engine)
    assert r.status == "ok" and r.t_fail is None and r.reason is None
    assert set(r.channels) == {"crank_angle", "crank_rate", "crank_accel", "rocker_angle",
                                  "slider_x", "loop_violation", "energy_balance"}
    for v in r.channels.values():
        assert v.shape == T_OUT.shape and np.all(np.isfinite(v))
    assert r.stats["steps"] > 0
    c = r.channels
    assert c["crank_angle"][0] == pytest.approx(math.radians(PHI0), abs=1e-12)
    assert c["rocker_angle"][0] == pytest.approx(math.radians(PSI0), abs=1e-12)
    assert c["crank_rate"][0] == pytest.approx(OMEGA0, abs=1e-9)
    # assembly 1: x_B > x_A, with x_C ~ 25 mm (scene spec)
    length, dx = rod_length(c)
    assert dx[0] > 0 and c["slider_x"][0] == pytest.approx(0.025, abs=2e-4)


@pytest.mark.parametrize("engine", [ex, mj], ids=["exudyn", "mujoco"])
def test_consistent_initial_velocities(engine):
    """ψ̇(0) = 0, so the rocker translates: v_C = v_B, and a rigid rod gives
    ẋ_B = v_A·(B − A)/(x_B − x_A) with ẏ_B = 0.  Finite differences on a micro-grid."""
    h = 1e-7
    t = np.array([0.0, h, 2 * h])
    c = run(engine, settings={"dt": h / 4}, t_out=t).channels
    phi, psi = math.radians(PHI0), math.radians(PSI0)
    A = np.array([L1 * math.cos(phi), L1 * math.sin(phi)])
    B = np.array([c["slider_x"][0] + L3 * math.cos(psi), L3 * math.sin(psi)])
    vA = OMEGA0 * L1 * np.array([-math.sin(phi), math.cos(phi)])
    vx_expected = vA @ (B - A) / (B[0] - A[0])
    vx = (-3 * c["slider_x"][0] + 4 * c["slider_x"][1] - c["slider_x"][2]) / (2 * h)
    psid = (-3 * c["rocker_angle"][0] + 4 * c["rocker_angle"][1] - c["rocker_angle"][2]) / (2 * h)
    assert abs(vx_expected) > 0.1          # the slider does start moving
    assert vx == pytest.approx(vx_expected, rel=1e-5)
    assert abs(psid) < 1e-4


def test_engines_agree_idle():
    a, b = run(ex).channels, run(mj).channels
    assert np.max(np.abs(a["crank_angle"] - b["crank_angle"])) <= 1e-4
    assert np.max(np.abs(a["crank_rate"] - b["crank_rate"])) <= 1e-3
    assert np.max(np.abs(a["slider_x"] - b["slider_x"])) <= 1e-7
    assert np.max(np.abs(a["rocker_angle"] - b["rocker_angle"])) <= 1e-5
    # the acceleration is a derived channel (MuJoCo's soft constraint biases it ~1e-4 relative)
    assert np.max(np.abs(a["crank_accel"] - b["crank_accel"])) <= 1.0
    # the energy balances start from the same absolute value (same T, same potential datum)
    assert a["energy_balance"][0] == pytest.approx(b["energy_balance"][0], abs=1e-9)


@pytest.mark.parametrize("engine", [ex, mj], ids=["exudyn", "mujoco"])
def test_loop_closure_and_energy(engine):
    c = run(engine).channels
    assert np.max(c["loop_violation"]) <= 1e-8
    length, dx = rod_length(c)
    assert np.max(np.abs(length - L2)) <= 1e-8
    assert np.all(dx > 0)                  # stays on assembly 1
    e = c["energy_balance"]
    assert np.max(np.abs(e - e[0])) <= 2e-4          # J; the motor does ~25 J of work


def test_assembly_2_engines_agree():
    p = {"assembly": 2}
    a, b = run(ex, p).channels, run(mj, p).channels
    _, dx = rod_length(a)
    assert np.all(dx < 0)
    assert np.max(np.abs(a["crank_angle"] - b["crank_angle"])) <= 1e-4
    assert np.max(np.abs(a["crank_rate"] - b["crank_rate"])) <= 1e-3
    assert np.max(np.abs(a["slider_x"] - b["slider_x"])) <= 1e-7


def test_press_cycle_engines_agree():
    ra, rb = run(ex, CYCLE), run(mj, CYCLE)
    assert ra.status == rb.status == "ok"
    ta, tb = ra.extra["t_lock"][0], rb.extra["t_lock"][0]
    assert CYCLE["lock_after"] < ta < CYCLE["release_after"]
    assert abs(ta - tb) <= 1e-7
    ea, eb = ra.extra["lock_energy_loss"][0], rb.extra["lock_energy_loss"][0]
    assert ea > 0 and ea == pytest.approx(eb, rel=1e-5)
    a, b = ra.channels, rb.channels
    locked = (T_OUT > ta) & (T_OUT < CYCLE["release_after"])
    assert locked.sum() >= 5
    for c in (a, b):
        assert np.max(np.abs(c["rocker_angle"][locked] - math.radians(CYCLE["lock_angle"]))) <= 1e-6
        length, _ = rod_length(c)
        assert np.max(np.abs(length - L2)) <= 1e-8
        e = c["energy_balance"]                       # includes press work and the lock loss
        assert np.max(np.abs(e - e[0])) <= 2e-4
    assert np.max(np.abs(a["crank_angle"] - b["crank_angle"])) <= 1e-4
    assert np.max(np.abs(a["crank_rate"] - b["crank_rate"])) <= 1e-3
    assert np.max(np.abs(a["slider_x"] - b["slider_x"])) <= 1e-7
    # the working load does work while locked (same on both)
    assert ra.extra["press_work"][0] == pytest.approx(rb.extra["press_work"][0], rel=1e-5)


def test_mujoco_divergence_is_reported_and_callbacks_reset():
    import mujoco
    r = mj.simulate(PRESS.resolve({"slider_stiffness": 1e10}), T_OUT, {"dt": 1e-3})
    assert r.status == "diverged" and r.t_fail is not None and r.reason
    bad = T_OUT >= r.t_fail
    for v in r.channels.values():
        assert np.all(np.isnan(v[bad])) and np.all(np.isfinite(v[~bad]))
    assert mujoco.get_mjcb_passive() is None and mujoco.get_mjcb_act_dyn() is None


def test_exudyn_solver_failure_is_reported():
    r = ex.simulate(PRESS.resolve({}), T_OUT, {"newton_tol": 1e-30, "newton_abs_tol": 1e-30})
    assert r.status == "diverged" and r.reason
    assert np.all(np.isnan(r.channels["crank_angle"][T_OUT > r.t_fail]))


@pytest.mark.parametrize("engine", [ex, mj], ids=["exudyn", "mujoco"])
def test_bad_settings_raise(engine):
    p = PRESS.resolve({})
    with pytest.raises(ValueError):
        engine.simulate(p, T_OUT, {"integrator": "no-such"})
    with pytest.raises(ValueError):
        engine.simulate(p, T_OUT, {"dt": -1.0})
    with pytest.raises(ValueError, match="unknown settings"):
        engine.simulate(p, T_OUT, {"no_such_key": 1.0})


@pytest.mark.parametrize("params", [{"mass_model": "midpoint"},
                                    {"gear_ratio": 3.4, "rotor_inertia": 0.0033},
                                    {"slider_damping": 2000.0}, {"rocker_rate0": -10.0}])
def test_variants_engines_agree(params):
    a, b = run(ex, params).channels, run(mj, params).channels
    assert np.max(np.abs(a["crank_angle"] - b["crank_angle"])) <= 1e-4
    assert np.max(np.abs(a["crank_rate"] - b["crank_rate"])) <= 1e-3
    assert np.max(np.abs(a["slider_x"] - b["slider_x"])) <= 1e-7
    for c in (a, b):
        e = c["energy_balance"]
        assert np.max(np.abs(e - e[0])) <= 2e-4
        assert np.max(c["loop_violation"]) <= 1e-8


def test_step_refinement_converges_to_the_other_engine():
    """Halving Exudyn's step moves it towards MuJoCo at tight settings (2nd order GA)."""
    ref = run(mj, settings={"dt": 2e-5, "solref_factor": 8}).channels["crank_angle"]
    errs = [np.max(np.abs(run(ex, settings={"dt": h}).channels["crank_angle"] - ref))
            for h in (1e-4, 5e-5)]
    assert errs[1] < 0.5 * errs[0]
