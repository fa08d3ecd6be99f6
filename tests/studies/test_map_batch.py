"""The map's batch path (`solvers.regimes`, the rotor leaves' `regimes`: the custom solvers'
compiled kernel, MuJoCo's rollouts, Exudyn's shared kinematic trees) against the
point-by-point path (`simulate` + the scene's regime), which is the independent reference:
the same labels on the default map and right at the capture/passage boundary, the same
numbers, and failed runs handed back to `simulate`."""
import numpy as np
import pytest

from compare import solvers
from compare.scenes import get_scene
from compare.workflows import maps
from custom_models.rotor import batch

SOLVERS = ("quaternion", "euler-vector")
ENGINES = ("mujoco", "exudyn")
EDGE = {"eccentricity": 0.005, "t_end": 10}      # one crossing, M* ≈ 2.6–3.1 N·m


def _one_by_one(sc, s, points, base, st):
    """Each point's label from its own full run."""
    out = []
    for pt in points:
        p = sc.resolve({**base, **pt})
        tr = solvers.simulate(sc, s, p, st, warm_up=False)
        out.append(sc.regime(p, tr) if tr.status == "ok" else tr.status)
    return out


def _boundary(sc, s, st, lo=2.6, hi=3.1, width=1e-6):
    """M* at eccentricity 0.005 bisected point by point (capture below, passage above)."""
    def label(x):
        return _one_by_one(sc, s, [{"torque": x}], EDGE, st)[0]
    assert (label(lo), label(hi)) == ("capture", "passage")
    while hi - lo > width:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if label(mid) == "capture" else (lo, mid)
    return 0.5 * (lo + hi)


@pytest.mark.parametrize("name", SOLVERS)
def test_batch_labels_equal_the_single_runs(name):
    sc, s = get_scene("rotor-spinup"), solvers.get_solver(name)
    st = solvers.settings_for(s, sc.name, t_out=sc.output_grid(sc.resolve(EDGE)))
    spec = sc.maps[0]                              # the default map: torque × eccentricity
    grid = [{"torque": x, "eccentricity": y, **spec.set}
            for x in (1.0, 2.5, 4.0, 5.0) for y in (0.0, 0.0125)]
    m = _boundary(sc, s, st)
    edge = [{"torque": m + d, **EDGE} for d in (-1e-3, -3e-4, -1e-4, -3e-5, -1e-5, -2e-6,
                                                2e-6, 1e-5, 3e-5, 1e-4, 3e-4, 1e-3)]
    points = grid + edge
    ref = _one_by_one(sc, s, points, {}, st)
    assert {"capture", "passage"} <= set(ref[len(grid):])     # the edge points straddle M*
    labels, wall = solvers.regimes(sc, s, [sc.resolve(pt) for pt in points], st)
    assert labels == ref and wall > 0
    rows = maps.evaluate_chunk(sc.name, s.name, {}, points, st, None)
    assert [r["label"] for r in rows] == ref and {r["status"] for r in rows} == {"ok"}


@pytest.mark.parametrize("name", SOLVERS)
def test_batch_numbers_equal_the_single_runs(name):
    """The kernel's energy numbers (largest |value| of each energy channel over the run) are
    the single run's: the same driver on the same right-hand side, the channels in scalar form
    (measured: ≤ 2.8e-14 of the value, the order of the sums; the batch's rtol 1 % off gives
    3.6e-10)."""
    sc, s = get_scene("rotor-spinup"), solvers.get_solver(name)
    ps = [sc.resolve({"t_end": 10, "torque": x, "eccentricity": e})
          for x in (1.0, 2.9, 4.0) for e in (0.005, 0.0125)]
    t_out = sc.output_grid(ps[0])
    st = solvers.settings_for(s, sc.name, t_out=t_out)
    res = s.leaf(sc).regimes(ps, t_out, st, "omega_norm",
                             np.array([sc.regime.levels(p) for p in ps]), sc.regime.window)
    for i, p in enumerate(ps):
        tr = solvers.simulate(sc, s, p, st, warm_up=False)
        for c, got in res["max_abs"].items():
            assert got[i] == pytest.approx(np.max(np.abs(tr.channels[c])), rel=1e-13, abs=0)


@pytest.mark.parametrize("name", SOLVERS)
def test_failed_runs_go_back_to_simulate(name):
    """A run that fails — by the integrator (non-finite state, tilt π) or by the adapter's
    energy rule — has no batch label: the chunk runs it alone and reports what `simulate`
    reports; the points beside it keep their batch labels."""
    sc, s = get_scene("rotor-spinup"), solvers.get_solver(name)
    cases = [({"t_end": 10}, "euler", 5e-4, "energy balance drifted"),
             ({"t_end": 10}, "euler", 1e-3, "tilt reached pi"),
             ({"t_end": 0.2, "output_dt": 0.005, "k": 1e7}, "rk4", 5e-3, "")]   # ω h = 13.7
    for base, integrator, dt, why in cases:
        points = [{"torque": 1.5}, {"torque": 4.0}]
        ps = [sc.resolve({**base, **pt}) for pt in points]
        st = solvers.settings_for(s, sc.name, t_out=sc.output_grid(ps[0]),
                                  integrator=integrator, dt=dt)
        trs = [solvers.simulate(sc, s, p, st) for p in ps]
        assert trs[0].status == "diverged" and why in trs[0].reason
        labels, _ = solvers.regimes(sc, s, ps, st)
        assert labels == [sc.regime(p, tr) if tr.status == "ok" else None
                          for p, tr in zip(ps, trs)]
        rows = maps.evaluate_chunk(sc.name, s.name, base, points, st, None)
        assert [(r["status"], r["label"], r.get("reason")) for r in rows] == [
            (tr.status, sc.regime(p, tr) if tr.status == "ok" else tr.status, tr.reason)
            for p, tr in zip(ps, trs)]


def test_other_paths_are_left_alone():
    """An observable, or points on different output grids, are not batched."""
    sc, s = get_scene("rotor-spinup"), solvers.get_solver("quaternion")
    ps = [sc.resolve({"t_end": 1}), sc.resolve({"t_end": 2})]
    st = solvers.settings_for(s, sc.name, t_out=sc.output_grid(ps[0]))
    assert solvers.regimes(sc, s, ps, st) is None
    sail = get_scene("sail-deploy")
    assert solvers.regimes(sail, solvers.get_solver("thread-spool"), [sail.resolve({})],
                           {}) is None
    assert np.isfinite(sc.regime.levels(ps[0])).all()


@pytest.mark.parametrize("name", ENGINES)
def test_engine_batch_equals_its_single_runs(name, monkeypatch):
    """Both regimes, the two sides of the boundary M* (bisected to 1e-6 N·m with the quaternion
    solver: the engines' runs differ from its by ~1e-10 of scale), a closed-form ramp 5e-5
    above the speed it must stay above, other eccentricities (MuJoCo: another compiled model;
    Exudyn: rotors of another centre of mass in one tree) and, for Exudyn, a
    run that changes Cardan charts (its tree stops: the rotor is left to `simulate`, the others
    run again without it). Labels equal; the batch's numbers — drift of the energy balance,
    largest |value| of each energy channel — equal the single run's bit for bit (measured
    difference 0: the batch runs the same arithmetic per point)."""
    sc, s = get_scene("rotor-spinup"), solvers.get_solver(name)
    q = solvers.get_solver("quaternion")
    t_out = sc.output_grid(sc.resolve(EDGE))
    m = _boundary(sc, q, solvers.settings_for(q, sc.name, t_out=t_out))
    st = solvers.settings_for(s, sc.name, t_out=t_out)
    # a balanced upright rotor ramps exactly, |ω| = spin0 + M t/I_p: |ω(t_window)| 5e-5 above
    # the level it must stay above (passage, by 5e-5 of the level)
    ramp = sc.resolve({"eccentricity": 0.0, "spin0": 30.0, "t_end": 10})
    stay = sc.regime.levels(ramp)[1]
    i_p = ramp["m"] * ramp["R"] ** 2 / 2
    m_ramp = (stay * (1 + 5e-5) - 30.0) * i_p / (sc.regime.window * 10)
    points = [{"torque": 1.0, "eccentricity": 0.0125, "t_end": 10},
              {"torque": m - 2e-6, **EDGE}, {"torque": m + 2e-6, **EDGE},
              {"torque": 4.0, "eccentricity": 0.0, "t_end": 10},
              {"torque": m_ramp, "eccentricity": 0.0, "spin0": 30.0, "t_end": 10},
              {"torque": 0.0, "tilt0": 1.2, "spin0": 60.0, "t_end": 10}]
    ps = [sc.resolve(pt) for pt in points]
    trs = [solvers.simulate(sc, s, p, st, warm_up=False) for p in ps]
    ref = [sc.regime(p, tr) for p, tr in zip(ps, trs)]
    assert {tr.status for tr in trs} == {"ok"}
    assert ref[:5] == ["capture", "capture", "passage", "passage", "passage"]
    charts = trs[5].settings.get("chart_changes", 0)
    assert (charts >= 1) == (name == "exudyn")
    leaf, seen = s.leaf(sc), []
    batch = leaf.regimes
    monkeypatch.setattr(leaf, "regimes", lambda *a: seen.append(batch(*a)) or seen[-1])
    labels, wall = solvers.regimes(sc, s, ps, st)
    alone = {5} if charts else set()                 # the rotor `simulate` must run alone
    assert labels == [None if i in alone else r for i, r in enumerate(ref)] and wall > 0
    res = seen[-1]
    for i, tr in enumerate(trs):
        if i in alone:
            assert res["code"][i] != 0
            continue
        e = tr.channels["energy_balance"]
        assert res["code"][i] == 0 and res["finite"][i]
        assert res["drift"][i] == np.max(np.abs(e - e[0]))
        for c, v in res["max_abs"].items():
            assert v[i] == np.max(np.abs(tr.channels[c]))
    rows = maps.evaluate_chunk(sc.name, s.name, {}, points, st, None)
    assert [r["label"] for r in rows] == ref


def test_mujoco_rolls_carry_their_own_numbers_and_a_flagged_roll_comes_back_failed():
    """MuJoCo's rollout of several points sharing one model: each roll's k (userdata) and
    torque (wrench) are its own, and a roll whose callback flags (here |ω| past an omega_max of
    30 rad/s) comes back failed instead of running on past the flag (the per-step userdata
    control clears the flag; the poisoned work keeps it). Independent reference: each point's
    own `simulate` — the batch numbers equal them bit for bit, and the flagged run says why."""
    sc, s = get_scene("rotor-spinup"), solvers.get_solver("mujoco")
    points = [{"torque": 1.0, "k": 10.0, "eccentricity": 0.0125, "t_end": 10},
              {"torque": 4.0, "eccentricity": 0.0125, "t_end": 10},
              {"torque": 0.2, "k": 30.0, "eccentricity": 0.0125, "t_end": 10}]
    ps = [sc.resolve(pt) for pt in points]
    st = {**solvers.settings_for(s, sc.name, t_out=sc.output_grid(ps[0])), "omega_max": 30.0}
    trs = [solvers.simulate(sc, s, p, st, warm_up=False) for p in ps]
    assert [tr.status for tr in trs] == ["ok", "diverged", "ok"]
    assert "omega_max" in trs[1].reason
    levels = np.array([sc.regime.levels(p) for p in ps])
    res = s.leaf(sc).regimes(ps, sc.output_grid(ps[0]), st, "omega_norm", levels,
                             sc.regime.window)
    assert list(res["code"] != 0) == [False, True, False]
    for i in (0, 2):
        e = trs[i].channels["energy_balance"]
        assert res["drift"][i] == np.max(np.abs(e - e[0]))
        assert res["max_abs"]["kinetic"][i] == np.max(np.abs(trs[i].channels["kinetic"]))


@pytest.mark.parametrize("name", SOLVERS)
def test_lanes_give_the_scalar_drivers_numbers_bit_for_bit(name):
    """DOP853 over SIMD lanes (`integrators.lanes`, the batch's path for dop853) against the
    scalar driver on the same right-hand side (`batch.regimes` without lanes; the scalar path is
    checked against single runs above): 21 points — not a multiple of the 8 lanes, of unequal
    step counts, so lanes refill while others run; one tilted near π at rest — at the map's
    cheap and accurate tolerances, and with a step budget some points exhaust (a failure
    mid-block). Every number is equal: each lane runs the scalar driver's arithmetic in its
    order (measured difference 0). Seeded: the step allowed to grow right after a rejection,
    the interpolant's x/(1−x) alternation dropped, a lane's row counted without its mask —
    each fails here."""
    sc, s = get_scene("rotor-spinup"), solvers.get_solver(name)
    leaf = s.leaf(sc)
    rng = np.random.default_rng(7)
    ps = [sc.resolve({"t_end": 10, "torque": float(rng.uniform(1, 5)),
                      "eccentricity": float(rng.uniform(0, 0.02))}) for _ in range(20)]
    ps.append(sc.resolve({"t_end": 10, "torque": 0.0, "tilt0": 3.0, "spin0": 0.0}))
    t_out = sc.output_grid(ps[0])
    levels = np.array([sc.regime.levels(p) for p in ps])
    args = (leaf.rhs_into, leaf.guard, leaf.kinematics, leaf.initial_state, ps, t_out)
    codes = set()
    for st in ({"rtol": 1e-4}, {"rtol": 1e-11}, {"rtol": 1e-4, "max_steps": 300}):
        st = {**leaf.DEFAULT_SETTINGS, **st}
        scalar = batch.regimes(*args, st, "omega_norm", levels, sc.regime.window)
        lanes = batch.regimes(*args, st, "omega_norm", levels, sc.regime.window,
                              (leaf.rhs_lanes, leaf.row_lanes), lanes_from=1)
        assert np.array_equal(lanes["code"], scalar["code"])
        assert np.array_equal(lanes["t_fail"], scalar["t_fail"], equal_nan=True)
        ok = scalar["code"] == 0
        for k in ("regime", "finite", "drift"):
            assert np.array_equal(lanes[k][ok], scalar[k][ok])
        for c in scalar["max_abs"]:
            assert np.array_equal(lanes["max_abs"][c][ok], scalar["max_abs"][c][ok])
        codes |= set(scalar["code"])
    assert len(codes) >= 2                     # finished and failed points both compared
