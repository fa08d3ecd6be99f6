"""Two-bearing rotor (scene `bearing-rotor`): the shared physics and the paper's second-order
quaternion solver, against closed forms written here, an independent first-order solver written
here (q' = ½ q∘Ω with scipy), periodicity and conservation laws.

Tolerances come from measured deviations (the numbers in the comments were measured with the
default settings: DOP853, rtol 1e-10)."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.interpolate import CubicSpline
from scipy.optimize import brentq

from compare.errors import BadInput
from compare.physics import bearing_rotor as phys
from compare.scenes.bearing import BEARING_ROTOR as SCENE
from custom_models.bearing import quaternion as leaf


def qmul(a, b):
    """Hamilton product, written independently of the code under test."""
    return np.concatenate([[a[0] * b[0] - a[1:] @ b[1:]],
                           a[0] * b[1:] + b[0] * a[1:] + np.cross(a[1:], b[1:])])


def qaxis(axis, angle):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    return np.concatenate([[np.cos(angle / 2)], np.sin(angle / 2) * axis])


def qmat(q):
    """R with R v = q∘(0, v)∘q̄, by products (independent of quat_matrix)."""
    q = q / np.linalg.norm(q)
    qc = q * np.array([1, -1, -1, -1])
    return np.column_stack([qmul(qmul(q, np.r_[0.0, e]), qc)[1:] for e in np.eye(3)])


def run(overrides=None, settings=None):
    p = SCENE.resolve(overrides or {})
    t = SCENE.output_grid(p)
    return p, t, leaf.simulate(p, t, settings or {})


@pytest.fixture(scope="module")
def default_run():
    return run()


# ------------------------------------------------------------------ scene
@pytest.mark.parametrize("name,value", [("m", "-1"), ("l", "0"), ("J_t", "0"), ("k_b", "-5"),
                                        ("c_b", "-1"), ("defect_height", "-1e-6"),
                                        ("J_p", "0.5"), ("gravity", "0,1"), ("t_end", "0")])
def test_bad_parameters_raise_bad_input(name, value):
    with pytest.raises(BadInput):
        SCENE.resolve({name: value})


def test_zero_damping_and_zero_defect_are_admissible():
    p = SCENE.resolve({"c_b": 0, "defect_height": 0})
    assert p["c_b"] == 0.0 and p["defect_height"] == 0.0


def test_bad_settings_raise_value_error():
    p = SCENE.resolve({"t_end": 0.01})
    t = SCENE.output_grid(p)
    for s in ({"integrator": "bogus"}, {"integrator": "rk4", "dt": -1e-4}, {"project": "maybe"},
              {"nonsense": 1}):
        with pytest.raises(ValueError):
            leaf.simulate(p, t, s)


# ------------------------------------------------------------------ shared physics
def test_twist_angle_is_the_swing_twist_split():
    rng = np.random.default_rng(3)
    for _ in range(20):
        phi = rng.uniform(-3.1, 3.1)
        swing_axis = np.r_[rng.normal(size=2), 0.0]
        q = qmul(qaxis(swing_axis, rng.uniform(0, 1.5)), qaxis([0, 0, 1], phi))
        for qq in (q, -q, 2.5 * q):
            assert phys.twist_angle(qq) == pytest.approx(phi, abs=1e-12)


def test_twist_rate_is_the_derivative_of_the_twist():
    rng = np.random.default_rng(4)
    for _ in range(10):
        q = qmul(qaxis(np.r_[rng.normal(size=2), 0], 0.3), qaxis([0, 0, 1], rng.uniform(-3, 3)))
        w = rng.normal(size=3) * 5
        h = 1e-6
        f = [phys.twist_angle(qmul(qaxis(w, s * h * np.linalg.norm(w)), q)) for s in (1, -1)]
        assert phys.twist_rate(q, w) == pytest.approx((f[0] - f[1]) / (2 * h), rel=1e-7)


def test_defect_lift_profile():
    p = SCENE.resolve({"defect_angle": 0.4})
    pk = phys.pack(p)
    H, w = p["defect_height"], p["defect_width"]
    load = -np.pi / 2                                  # gravity along −y
    for x in (-0.12, -0.1, -0.05, 0.0, 0.03, 0.0999, 0.2, 3.0):
        twist = load - 0.4 + x
        expect = H * (1 - (x / w) ** 2) ** 2 if abs(x) < w else 0.0
        assert phys.defect_lift(twist, pk) == pytest.approx(expect, abs=1e-18)


def test_loads_do_the_work_the_energy_balance_books():
    """F·v + M·ω = −dV_b/dt + Ẇ_motor − Ḋ along any motion (finite differences of V_b), also
    while the defect lifts journal a; measured agreement 1e-9 relative."""
    p = SCENE.resolve({"defect_angle": 1.6})
    pk = phys.pack(p)
    rng = np.random.default_rng(1)
    r, v = rng.normal(size=3) * 1e-5, rng.normal(size=3) * 1e-3
    w = rng.normal(size=3) * 0.1 + np.array([0, 0, 50.0])
    swing = qaxis([1, 2, 0], 2e-5)
    for ang in np.linspace(-3.32, -3.08, 9):          # across the bump (bump faces −y at −3.17)
        q = qmul(swing, qaxis([0, 0, 1], ang))

        def V(s, q=q):
            qs = qmul(qaxis(w, np.linalg.norm(w) * s), q)
            ra, _, rb, _ = phys.journals(r + v * s, v, qmat(qs), w, pk)
            return phys.bearing_potential(ra, rb, phys.twist_angle(qs), pk)

        F, M, w_motor, d_diss = phys.body_loads(r, q, v, w, pk)
        h = 1e-7
        dV = (V(h) - V(-h)) / (2 * h)
        assert F @ v + M @ w == pytest.approx(-dV + w_motor - d_diss, rel=1e-8)


@pytest.mark.parametrize("gravity", ["0,-9.81,0", "3,-4,0", "0,0,-9.81", "1,2,-3"])
def test_the_common_start_is_an_equilibrium(gravity):
    """At rest at static_sag, with no drive and no defect, every acceleration of the leaf's
    right-hand side vanishes (bearing and axial springs carry m g), for any gravity direction."""
    p = SCENE.resolve({"gravity": gravity, "motor_stall_torque": 0, "defect_height": 0})
    y0 = leaf.initial_state(p)
    pk = np.concatenate([phys.pack(p), [0.0, 0.1 * p["l"]]])
    dy = leaf.rhs(0.0, y0, pk)
    g = np.linalg.norm(p["gravity"])
    # centre of mass: measured 0 radially; 3e-12 m/s² axially = round-off of (z + l/2) − l/2
    # (~5e-17 m) times k_axial/m
    assert np.max(np.abs(dy[3:6])) < 1e-11 * g
    assert np.max(np.abs(dy[10:14])) < 1e-12             # quaternion: measured 0


def test_module_steady_spin_matches_the_balance_solved_here():
    p = SCENE.resolve({"mu": 0.2, "bearing_drag": 3e-3})
    m_g = 6.0 * 9.81

    def net(w):
        return 1.0 * (1 - w / 80.0) - 3e-3 * w - 0.2 * 0.02 * m_g * np.tanh(w / 0.1)

    assert phys.steady_spin_rate(p) == pytest.approx(brentq(net, 1.0, 80.0, xtol=1e-14),
                                                     rel=1e-12)


def test_spin_angle_unwraps_a_coarse_grid_with_the_rate():
    """4 rad per sample: np.unwrap alone cannot tell the branch; with the rate it can."""
    t = np.linspace(0, 1, 21)
    rate = 80.0 + 10 * t                               # angle 80 t + 5 t²
    angle = 80 * t + 5 * t ** 2
    quats = np.array([qmul(qaxis([1, 1, 0], 1e-3), qaxis([0, 0, 1], a)) for a in angle])
    assert np.allclose(phys.spin_angle(quats, t, rate), angle, atol=1e-9)


# ------------------------------------------------------------------ the quaternion equation
def test_second_order_quaternion_equation_matches_first_order_kinematics():
    """q̈ of the leaf equals d/dt(½ q∘Ω) = ½ q̇∘Ω + ½ q∘Ω̇ for q̇ = ½ q∘Ω (unit q); the rates
    recovered from (q, q̇) are Ω (body) and ω = RΩ (fixed)."""
    rng = np.random.default_rng(7)
    for _ in range(20):
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        W, Wd = rng.normal(size=3) * 30, rng.normal(size=3) * 100
        qd = 0.5 * qmul(q, np.r_[0.0, W])
        expect = 0.5 * qmul(qd, np.r_[0.0, W]) + 0.5 * qmul(q, np.r_[0.0, Wd])
        assert np.allclose(leaf.quaternion_acceleration(q, qd, Wd), expect, atol=1e-11)
        assert np.allclose(leaf.body_rate(q, qd), W, atol=1e-12)
        assert np.allclose(leaf.fixed_rate(q, qd), qmat(q) @ W, atol=1e-12)
        assert np.allclose(qd, 0.5 * qmul(np.r_[0.0, qmat(q) @ W], q), atol=1e-12)


def first_order_solution(p, t):
    """Independent solver: q' = ½ q∘(0, Ω), J Ω' = Rᵀ M − Ω × J Ω, m r'' = F + m g (scipy
    DOP853); shares only the force law (compare.physics) with the leaf."""
    pk = phys.pack(p)
    J = np.array([p["J_t"], p["J_t"], p["J_p"]])
    g = np.asarray(p["gravity"], float)

    def f(_, y):
        r, v, q, W = y[0:3], y[3:6], y[6:10], y[10:13]
        R = qmat(q)
        F, M, pw, pd = phys.body_loads(r, q, v, R @ W, pk)
        Wd = (R.T @ M - np.cross(W, J * W)) / J
        return np.concatenate([v, F / p["m"] + g, 0.5 * qmul(q, np.r_[0.0, W]), Wd, [pw, pd]])

    r0, q0, v0, w0 = phys.initial_state(p)
    y0 = np.concatenate([r0, v0, q0, w0, [0.0, 0.0]])
    sol = solve_ivp(f, (t[0], t[-1]), y0, method="DOP853", t_eval=t, rtol=1e-11, atol=1e-14,
                    max_step=t[1] - t[0])
    Y = sol.y.T
    omega = np.array([qmat(y[6:10]) @ y[10:13] for y in Y])
    return phys.channels(p, t, Y[:, 0:3], Y[:, 3:6], Y[:, 6:10], omega, Y[:, 13], Y[:, 14])


def test_agrees_with_an_independent_first_order_solver():
    """0.25 s of spin-up past the defect (11.6 rad); measured largest differences relative to
    each channel's range: spin_rate 1.0e-11, spin_angle 9.8e-14, journal_a_y 1.9e-8,
    journal_b_y 1.2e-8, journal_a_x/b_x 4.2e-8 (of a 7e-9 m range: 3e-16 m), motor_work 5.9e-14,
    dissipated 3.2e-9 (the first three were 3-4x smaller before the kernels' arithmetic was
    reordered for speed: these are round-off-level differences)."""
    p, t, res = run({"t_end": 0.25, "defect_angle": 2.0})
    ref = first_order_solution(p, t)
    assert res.status == "ok"
    assert ref["spin_angle"][-1] > 4.0 + 2 * np.pi       # the bump faces the load at 4.03 and
    # 10.3 rad (load at −π/2, bump at 2 rad): both passed
    for name, tol in (("spin_rate", 1e-10), ("spin_angle", 1e-12), ("journal_a_y", 2e-7),
                      ("journal_b_y", 1.2e-7), ("journal_a_x", 4e-7), ("journal_b_x", 4e-7),
                      ("motor_work", 6e-13), ("dissipated", 3e-8)):
        scale = np.ptp(ref[name])
        assert np.max(np.abs(res.channels[name] - ref[name])) <= tol * scale, name


# ------------------------------------------------------------------ acceptance
def test_defect_free_settles_at_static_sag_and_motor_friction_balance():
    """No defect: the journals settle at m g/(2 k_b) and the spin at the balance
    stall(1 − ω/ω0) = drag ω + μ r_j m g tanh(ω/0.1), solved here; no ripple is left."""
    p, t, res = run({"defect_height": 0, "t_end": 4, "output_dt": 0.01})
    c = res.channels
    m, g, k = 6.0, 9.81, 1.0e6
    sag = -m * g / (2 * k)                         # −2.943e-5 m (gravity along −y)

    def net(w):
        return 1.0 * (1 - w / 80.0) - 1e-3 * w - 0.05 * 0.02 * m * g * np.tanh(w / 0.1)

    w_steady = brentq(net, 1.0, 80.0, xtol=1e-14)   # 69.714074 rad/s
    assert res.status == "ok"
    # measured: 1.6e-10 relative at t = 4 s (the spin time constant is J_p/0.0135 = 0.089 s)
    assert c["spin_rate"][-1] == pytest.approx(w_steady, rel=1e-9)
    for j in ("journal_a_y", "journal_b_y"):           # measured: exact to the last bit; the
        assert c[j][-1] == pytest.approx(sag, rel=1e-12)        # window is round-off
    for j in ("journal_a_x", "journal_b_x"):
        assert abs(c[j][-1]) < 1e-12 * abs(sag)                 # measured 0 (exactly)
    last = t >= 3.0                                            # ripple: round-off only
    assert np.ptp(c["spin_rate"][last]) < 2e-13 * w_steady      # measured 1.9e-14 relative


def test_ripple_period_is_one_revolution(default_run):
    """The settled spin rate, read against the spin angle, repeats after 2π and after no
    shorter shift (the bearing ringing at ~0.77 rad is not a period). Measured mismatch at 2π:
    9e-4 of the ripple's RMS (cubic interpolation of the 0.5 ms samples); next best ≥ 0.028."""
    p, t, res = default_run
    s, a = res.channels["spin_rate"], res.channels["spin_angle"]
    late = t >= 1.5
    n_rev = 2048
    theta = np.arange(a[late][0], a[late][-1], 2 * np.pi / n_rev)
    x = CubicSpline(a[late], s[late])(theta)
    x -= x.mean()
    shifts = np.arange(50, int(1.5 * n_rev))
    mismatch = np.array([np.sqrt(np.mean((x[k:] - x[:-k]) ** 2)) for k in shifts]) / x.std()
    best = shifts[np.argmin(mismatch)]
    assert abs(best - n_rev) <= 2
    assert mismatch.min() < 1e-2
    away = np.abs(shifts - n_rev) > 30
    assert mismatch[away].min() > 10 * mismatch.min()


def ripple_amplitude(res):
    s, a = res.channels["spin_rate"], res.channels["spin_angle"]
    return np.ptp(s[a >= a[-1] - 5 * 2 * np.pi])


def test_ripple_amplitude_converges_as_the_tolerance_tightens(default_run):
    """Peak-to-peak spin ripple over the last 5 revolutions (0.036643 rad/s); measured
    differences from rtol 1e-12: 4.9e-7 (1e-6), 1.2e-10 (1e-8), 8.8e-12 (1e-10) rad/s. Below
    ~1e-11 the amplitude is not monotone in rtol (1e-9 gave 6e-12): it is then read off samples
    whose own spin-rate error is ~3e-10 rad/s."""
    _, _, ref = run(settings={"rtol": 1e-12})
    a_ref = ripple_amplitude(ref)
    diffs = [abs(ripple_amplitude(r) - a_ref) for r in
             (run(settings={"rtol": 1e-6})[2], run(settings={"rtol": 1e-8})[2], default_run[2])]
    assert diffs[0] > diffs[1] > diffs[2]
    assert diffs[2] < 8e-11
    assert 0.03 < a_ref < 0.04          # a visible ripple: ~5 % of what the bump's friction
    # impulse μ r_j k_b H · (2 w/ω) / J_p ≈ 0.06 rad/s could give at most


def test_energy_balance_closes(default_run):
    """Acceptance ≤ 1e-6 of the motor work; measured 1.2e-9 (3.5e-8 J of 28.8 J)."""
    _, _, res = default_run
    e, w = res.channels["energy_balance"], res.channels["motor_work"]
    assert res.status == "ok"
    assert np.max(np.abs(e - e[0])) < 1e-8 * w[-1]


def test_spin_angle_is_the_integral_of_the_spin_rate(default_run):
    """The twist angle and ∫ω·e3 dt differ only by the tiny swing (tilt ~1e-5 rad). Measured
    difference after 203 rad: 4.5e-7 rad with a cubic-spline quadrature of the 0.5 ms samples
    (it falls to 1.8e-9 rad on a 0.1 ms grid, so it is quadrature error)."""
    _, t, res = default_run
    integral = CubicSpline(t, res.channels["spin_rate"]).antiderivative()(t)
    assert np.max(np.abs(res.channels["spin_angle"] - integral)) < 4.5e-6


def test_projection_changes_nothing_but_the_norm(default_run):
    _, _, free = default_run
    _, _, proj = run(settings={"project": True})
    assert free.invariants["quaternion_norm"] < 1e-12          # measured 3.6e-14
    assert proj.invariants["quaternion_norm"] < 1e-12
    for name, tol in (("spin_rate", 4e-11), ("journal_a_y", 9e-8)):   # measured 4.3e-12, 9.1e-9
        d = np.max(np.abs(free.channels[name] - proj.channels[name]))
        assert d <= tol * np.ptp(free.channels[name]), name


def test_fixed_step_rk4_agrees_with_dop853(default_run):
    """rk4 at dt = 5e-5 s; measured differences relative to the channel's largest value:
    spin_rate 1.8e-9, journal_a_y 5.9e-7."""
    p, t, ref = default_run
    _, _, res = run(settings={"integrator": "rk4", "dt": 5e-5})
    assert res.status == "ok" and res.settings["dt"] == pytest.approx(5e-5)
    for name, tol in (("spin_rate", 1e-8), ("journal_a_y", 5e-6)):
        d = np.max(np.abs(res.channels[name] - ref.channels[name]))
        assert d <= tol * np.max(np.abs(ref.channels[name])), name


def test_recording_extras(default_run):
    _, t, res = default_run
    assert res.extra["orientation"].shape == (len(t), 4)
    assert np.allclose(res.extra["journal_a"][:, 1], res.channels["journal_a_y"])
    assert np.allclose(res.extra["journal_b"][:, 0], res.channels["journal_b_x"])
    assert np.allclose(res.extra["journal_a"][:, 2], 0.3, atol=1e-6)


# ------------------------------------------------------------------ extremes
@pytest.mark.parametrize("overrides,t_end,tol", [({"k_b": 1e9}, 0.3, 4e-9),
                                                 ({"c_b": 0}, 3.0, 4e-8),
                                                 ({"defect_height": 1e-3}, 3.0, 2.5e-7)])
def test_extremes_stay_ok_with_a_closed_energy_balance(overrides, t_end, tol):
    """Stiff bearings (the adaptive step shrinks: 7551 steps in 0.3 s), no damping, and a 1 mm
    bump that throws journal a past the bearing centre (y > 0; it hangs 29 µm below at rest).
    Measured energy residuals relative to the motor work: 4.2e-10, 3.7e-9, 2.4e-8 (the stiff
    case is round-off: 3.7e-11 before the kernels' arithmetic was reordered)."""
    p, t, res = run({**overrides, "t_end": t_end})
    c = res.channels
    assert res.status == "ok"
    e = c["energy_balance"]
    assert np.max(np.abs(e - e[0])) < tol * c["motor_work"][-1]
    if "defect_height" in overrides:
        assert np.max(c["journal_a_y"]) > 5e-4                  # measured 9.65e-4 m


def test_too_coarse_a_fixed_step_ends_with_a_clear_status():
    """rk4 at 1e-4 s is unstable for 1e9 N/m bearings (rocking mode ~3e4 rad/s); the run stops
    with a status, a time and a reason, and NaN after it."""
    _, t, res = run({"k_b": 1e9, "t_end": 0.3}, {"integrator": "rk4", "dt": 1e-4})
    assert res.status in ("unstable", "diverged")
    assert 0 < res.t_fail < 0.3 and res.reason
    assert res.validate(SCENE.channels, len(t)) is None
    assert np.isnan(res.channels["spin_rate"][-1])


def test_norm_drift_over_100_s_with_and_without_projection():
    """100 s with the defect (default settings, 1 ms output). Measured: the first integral
    |q| = 1 drifts to 1.3e-10 unprojected (1.6e-11 before the kernels' arithmetic was reordered:
    the drift is an accumulation of round-off-level step errors); projected, the largest
    per-step correction is 2.0e-15; the energy balance closes to 1.5e-9 / 2.6e-9 of the motor
    work (~900 J); ~25 s each."""
    out = {}
    for project in (False, True):
        p, t, res = run({"t_end": 100, "output_dt": 0.001}, {"project": project})
        assert res.status == "ok"
        e = res.channels["energy_balance"]
        assert np.max(np.abs(e - e[0])) < 2.5e-8 * res.channels["motor_work"][-1]
        out[project] = res.invariants["quaternion_norm"]
    assert out[False] < 1.3e-9
    assert out[True] < 2e-14
