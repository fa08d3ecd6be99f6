"""Custom Lagrange solvers of the press (`press_exact`, `press_partial`) and the linear-
acceleration integrator. Every expected value comes from geometry, conservation, or the theory
of the methods (second-order central differences; Newmark β = 1/6 stable to h = √3/π·T), never
from a number this code printed.
"""
import math

import numba as nb
import numpy as np
import pytest

from compare.errors import BadInput
from compare.physics import press as phys
from compare.scenes.press import PRESS, PRESS_CYCLE
from custom_models.integrators import accel_from_mass_force, integrate_wilson, no_guard
from custom_models.integrators.dense import RHS_INTO, first_class
from custom_models.integrators.events import EVENT_FN, M_LA, config, integrate_segment
from custom_models.integrators.explicit import GUARD
from custom_models.integrators.linear_acceleration import ACC
from custom_models.press import equations as eqs
from custom_models.press import exact as press_exact
from custom_models.press import kinematics as kin
from custom_models.press import lagrange as press
from custom_models.press import model as model
from custom_models.press import partial as press_partial

DEFAULT = PRESS.resolve({})
RNG = np.random.default_rng(3)
T_OUT = np.linspace(0.0, 0.05, 41)
LIMIT = math.sqrt(3.0) / math.pi       # 0.5513: linear-acceleration limit h/T (Newmark β = 1/6)


def _random_states(n, par=DEFAULT):
    """(φ, ψ) well inside the chart (|sin θ2| < 0.9), any assembly."""
    p = model.pack(par)
    out = []
    while len(out) < n:
        q = RNG.uniform(-math.pi, math.pi, 2)
        if abs(kin.rod_sine(q[0], q[1], p)) < 0.9:
            out.append(q)
    return p, out


def _geometry(q, par, sigma):
    """Independent positions straight from the scene text (not the module's formulas)."""
    l1, l2, l3 = par["l1"], par["l2"], par["l3"]
    A = l1 * np.array([math.cos(q[0]), math.sin(q[0])])
    yB = l3 * math.sin(q[1])
    xB = A[0] + sigma * math.sqrt(l2 ** 2 - (yB - A[1]) ** 2)
    B = np.array([xB, yB])
    C = B - l3 * np.array([math.cos(q[1]), math.sin(q[1])])
    return A, B, C


@pytest.mark.parametrize("assembly", [1, 2])
def test_loop_closure_by_geometry(assembly):
    par = PRESS.resolve({"assembly": assembly})
    p, qs = _random_states(50, par)
    for q in qs:
        xA, yA, xB, yB, xC, ok = kin.positions(q[0], q[1], p)
        A, B, C = np.array([xA, yA]), np.array([xB, yB]), np.array([xC, 0.0])
        assert ok
        assert abs(np.linalg.norm(B - A) - par["l2"]) < 1e-15
        assert abs(np.linalg.norm(B - C) - par["l3"]) < 1e-15
        # ψ is the direction C→B; assembly 1 has x_B > x_A
        assert abs(math.atan2(B[1] - C[1], B[0] - C[0]) - math.remainder(q[1], 2 * math.pi)) \
            < 1e-12
        assert (xB > xA) == (assembly == 1)


def test_initial_slider_position_change_point():
    """Scene text: with assembly 1 the start has x_C ≈ 25 mm where l1 + l2 = OC + l3."""
    p = model.pack(DEFAULT)
    assert abs(p[model.XC0] + DEFAULT["l3"] - DEFAULT["l1"] - DEFAULT["l2"]) < 1e-4


def test_exact_gradients_and_hessians_against_differences_of_positions():
    p, qs = _random_states(20)
    h = 1e-5
    for q in qs:
        base, G, H = kin.exact_derivatives(q[0], q[1], p)
        for k in range(2):
            e = np.eye(2)[k] * h
            bp, Gp, _ = kin.exact_derivatives(*(q + e), p)
            bm, Gm, _ = kin.exact_derivatives(*(q - e), p)
            A_p, B_p, C_p = _geometry(q + e, DEFAULT, 1.0)
            A_m, B_m, C_m = _geometry(q - e, DEFAULT, 1.0)
            fd = np.concatenate([(A_p - A_m), (B_p - B_m), [C_p[0] - C_m[0]]]) / (2 * h)
            assert np.allclose(G[:5, k], fd, rtol=0, atol=1e-10)
            assert np.allclose(H[:, :, k], (Gp - Gm) / (2 * h), rtol=0, atol=1e-7)


def test_velocity_analogues_converge_at_second_order():
    """Partial-system central differences vs analytic ∂r/∂q: error ∝ Δ²."""
    errs = []
    _, qs = _random_states(10)
    for d in (0.4, 0.2, 0.1):
        p = model.pack(DEFAULT, dphi_deg=d, dpsi_deg=d)
        e = 0.0
        for q in qs:
            P, ok = kin.stencil_positions(q[0], q[1], p)
            Gfd = np.array(kin.fd_gradients(P, 0, p)).T
            _, G, _ = kin.exact_derivatives(q[0], q[1], p)
            e = max(e, np.max(np.abs(Gfd - G)))
        errs.append(e)
    slopes = np.diff(np.log(errs)) / np.diff(np.log([0.4, 0.2, 0.1]))
    assert np.all(np.abs(slopes - 2.0) < 0.1), slopes


def test_lagrange_equations_against_independent_energy_derivation():
    """q'' of the exact solver vs Lagrange's equations derived numerically from an independent
    T(q, q') (lumped masses of eq. 21, velocities by differencing positions) and V."""
    par = dict(DEFAULT)
    p, qs = _random_states(5)
    m1, m2, m34 = par["m1"], par["m2"], par["m3"] + par["m4"]
    J1, J2, J3, g, k = par["J1"], par["J2"], par["J3"], par["gravity"], par["slider_stiffness"]
    xc0 = p[model.XC0]

    def T(q, qd, eps=1e-6):
        Ap, Bp, Cp = _geometry(q + eps * qd, par, 1)
        Am, Bm, Cm = _geometry(q - eps * qd, par, 1)
        vA, vB, vC = (Ap - Am) / (2 * eps), (Bp - Bm) / (2 * eps), (Cp - Cm) / (2 * eps)
        th = lambda A, B: math.atan2(B[1] - A[1], B[0] - A[0])
        w2 = (th(Ap, Bp) - th(Am, Bm)) / (2 * eps)
        return 0.5 * (m1 * vA @ vA + J1 * qd[0] ** 2 + m2 * vB @ vB + J2 * w2 ** 2
                      + m34 * vC @ vC + J3 * qd[1] ** 2)

    def V(q):
        A, B, C = _geometry(q, par, 1)
        return g * (m1 * A[1] + m2 * B[1]) + 0.5 * k * (C[0] - xc0) ** 2

    for q in qs:
        qd = RNG.uniform(-30, 30, 2)
        h = 1.0         # T is quadratic in q': differences in q' are exact at any step
        # M = ∂²T/∂q'² (T is quadratic in q'), p_i = ∂T/∂q'_i = (M q')_i
        M = np.array([[(T(q, qd + h * (ei + ej)) - T(q, qd + h * (ei - ej))
                        - T(q, qd - h * (ei - ej)) + T(q, qd - h * (ei + ej))) / (4 * h * h)
                       for ej in np.eye(2)] for ei in np.eye(2)])
        def mom(qq, qd=qd, h=h):
            return np.array([(T(qq, qd + h * e) - T(qq, qd - h * e)) / (2 * h)
                             for e in np.eye(2)])
        hq = 1e-5
        dmom_dq = np.column_stack([(mom(q + hq * e) - mom(q - hq * e)) / (2 * hq)
                                   for e in np.eye(2)])
        dT_dq = np.array([(T(q + hq * e, qd) - T(q - hq * e, qd)) / (2 * hq) for e in np.eye(2)])
        dV_dq = np.array([(V(q + hq * e) - V(q - hq * e)) / (2 * hq) for e in np.eye(2)])
        # the scene's Kloss law written out (scene-press.md: 1500 W, 1500 rpm, s_n 0.058, λ 2.2)
        w_sync = 2 * math.pi * 1500 / 60
        m_k = 2.2 * 1500 / (w_sync * (1 - 0.058))
        s_k = 0.058 * (2.2 + math.sqrt(2.2 ** 2 - 1))
        s = 1 - qd[0] / w_sync
        Q = -dV_dq + np.array([2 * m_k / (s / s_k + s_k / s), 0.0])
        qdd_ref = np.linalg.solve(M, Q - dmom_dq @ qd + dT_dq)
        qdd = eqs.acc_exact(0.0, q, qd, p)[:2]
        assert np.allclose(qdd, qdd_ref, rtol=2e-4, atol=1e-3 * np.max(np.abs(qdd_ref))), \
            (qdd, qdd_ref)


def test_energy_balance_and_closure_over_the_paper_run():
    for mod, st in ((press_exact, {"integrator": "rk4", "dt": 1e-5}),
                    (press_partial, {"integrator": "rk4", "dt": 1e-5, "dphi_deg": 0.01,
                                     "dpsi_deg": 0.01})):
        r = mod.simulate(DEFAULT, T_OUT, st)
        assert r.status == "ok"
        eb = r.channels["energy_balance"]
        work = r.extra["motor_work"][-1]
        assert work > 1.0
        assert np.max(np.abs(eb - eb[0])) <= 1e-6 * work
        assert np.max(r.channels["loop_violation"]) < 1e-15
        assert set(r.channels) == set(PRESS.channels)
        assert all(len(v) == len(T_OUT) for v in r.channels.values())


def test_partial_minus_exact_is_second_order_in_the_virtual_step():
    ref = press_exact.simulate(DEFAULT, T_OUT, {"integrator": "rk4", "dt": 1e-5})
    ds = np.array([0.2, 0.1, 0.05])
    dev = []
    for d in ds:
        r = press_partial.simulate(DEFAULT, T_OUT, {"integrator": "rk4", "dt": 1e-5,
                                               "dphi_deg": d, "dpsi_deg": d})
        dev.append(np.max(np.abs(r.channels["crank_rate"] - ref.channels["crank_rate"])))
    slopes = np.diff(np.log(dev)) / np.diff(np.log(ds))
    assert np.all(np.abs(slopes - 2.0) < 0.1), slopes


def test_start_at_the_double_root_is_reported_not_nan():
    # rod 1.7° from vertical: the partial systems' stencil crosses the root at t = 0; the exact
    # chart runs until the rod reaches singular_tol
    for mod in (press_partial, press_exact):
        r = mod.simulate(PRESS.resolve({"psi0": 62.0}), T_OUT, {"integrator": "rk4", "dt": 1e-5})
        assert r.status == "diverged"
        assert "singular" in r.reason
        ok = np.isfinite(r.channels["crank_rate"])
        assert not ok[-1]
        assert r.t_fail is not None and r.t_fail >= 0.0


def test_bad_settings_raise():
    with pytest.raises(ValueError):
        press_exact.simulate(DEFAULT, T_OUT, {"integrator": "nope"})
    with pytest.raises(ValueError):
        press_partial.simulate(DEFAULT, T_OUT, {"dphi_deg": 0.0})
    with pytest.raises(ValueError, match="unknown settings"):
        press_exact.simulate(DEFAULT, T_OUT, {"no_such_key": 1})
    with pytest.raises(BadInput):
        PRESS.resolve({"assembly": 3})


def test_old_integrator_spellings_are_accepted():
    a = press_exact.simulate(DEFAULT, T_OUT[:3], {"integrator": "rk44", "dt": 1e-4})
    b = press_exact.simulate(DEFAULT, T_OUT[:3], {"integrator": "rk4", "dt": 1e-4})
    assert a.settings["integrator"] == "rk4"
    np.testing.assert_array_equal(a.channels["crank_rate"], b.channels["crank_rate"])


def test_motor_characteristic_is_the_kloss_law():
    """M(s) = 2 M_k/(s/s_k + s_k/s) from the motor data of scene-press.md, at a few slips."""
    w_sync = 2 * math.pi * 1500 / 60
    m_n = 1500 / (w_sync * (1 - 0.058))
    m_k = 2.2 * m_n
    s_k = 0.058 * (2.2 + math.sqrt(2.2 ** 2 - 1))
    for s in (0.01, 0.058, s_k, 0.5, 1.0):
        assert phys.motor_torque(w_sync * (1 - s), 1.0) == pytest.approx(
            2 * m_k / (s / s_k + s_k / s), rel=1e-13)
    # at the rated slip the torque is the rated torque P_n / ω_n
    assert phys.motor_torque(w_sync * (1 - 0.058), 1.0) == pytest.approx(m_n, rel=1e-12)


# ---- the linear-acceleration integrator on a linear oscillator ----------------------------
@nb.njit
def _mass(t, q, p):
    return np.eye(1) * p[1]


@nb.njit
def _force(t, q, qd, p):
    return -p[0] * q


_ACC = accel_from_mass_force(_mass, _force)


def _amplitude(ratio, theta, n=300):
    p = np.array([4 * math.pi ** 2 * 3.0, 3.0])        # ω = 2π, T = 1
    t = np.arange(n + 1) * ratio
    Y, steps, evals, t_fail, code = integrate_wilson(_ACC, no_guard, np.array([1.0, 0.0]), 1, p,
                                                     t, 1, theta, 0, 1e-12, 30)
    return np.max(np.abs(Y[-30:, 0])) if code == 0 else np.inf


def test_linear_acceleration_stability_limit_is_0551_period():
    assert _amplitude(0.98 * LIMIT, 1.0) <= 1.0 + 1e-9
    assert _amplitude(1.02 * LIMIT, 1.0) > 1e3


@pytest.mark.parametrize("ratio", [0.6, 2.0, 10.0])
def test_wilson_theta_137_is_unconditionally_stable(ratio):
    assert _amplitude(ratio, 1.37) <= 1.0 + 1e-9
    assert _amplitude(ratio, 1.4) <= 1.0 + 1e-9


@nb.njit
def _jittered(t, q, qd, p):
    """q'' = −ω² q plus a jitter of height J that flips every w in q: a model whose rounding
    (n-four-bar's second differences over 40 chained closures) is coarser than Newton's
    tolerance, so an iterate whose root falls on a flip alternates for ever."""
    out = np.empty(1)
    out[0] = -p[0] * q[0] + p[1] * (math.floor(q[0] / p[2]) % 2.0)
    return out


def test_a_step_newton_cannot_finish_below_the_models_rounding_is_cut_and_stays_accurate():
    """ω = 2π, h = 1e-3, J = 1e-5 (2.5e-7 of ω²: above the iteration's floor 1e-7 of the
    accelerations, so the full step never converges where it alternates); flips every 2e-12
    in q, the iterates' spacing τ²J/6 = 1.7e-12 at h. The run completes through the cut steps
    (at h/4 a correction of J moves q by 1e-13, the state's convergence test) and stays within
    the clean run's error of cos ωt plus the response to a force of size J, J·t/ω."""
    w2, jit, t = 4 * math.pi ** 2, 1e-5, np.linspace(0.0, 2.0, 201)
    runs = [integrate_wilson(_jittered, no_guard, np.array([1.0, 0.0]), 1,
                             np.array([w2, j, 2e-12]), t, 10, 1.0, 0, 1e-10, 30) for j in (0, jit)]
    (clean, steps0, _, _, code0), (noisy, steps, _, _, code) = runs
    assert code0 == 0 and steps0 == 2000                 # nothing to cut without the jitter
    assert code == 0 and steps > 2000, (code, steps)     # it would stop without the cut
    exact = np.cos(2 * math.pi * t)
    assert np.max(np.abs(noisy[:, 0] - exact)) <= (np.max(np.abs(clean[:, 0] - exact))
                                                   + jit * t[-1] / math.sqrt(w2))
    # the event driver (press-cycle) takes the same step and counts the cut ones too
    Y = np.full((len(t), 2), np.nan)
    code_e, _, _, _, steps_e, _ = integrate_segment(
        first_class(_no_rhs, RHS_INTO), first_class(_jittered, ACC), first_class(no_guard, GUARD),
        first_class(_no_event, EVENT_FN), np.array([1.0, 0.0]), np.array([w2, jit, 2e-12]), 0.0,
        t[-1], t, 1, Y, 1e-3, (np.zeros((1, 1)), np.zeros(1), np.zeros(1)),
        config(M_LA, n_q=1))
    assert code_e == 0 and steps_e == steps, (code_e, steps_e, steps)
    assert np.array_equal(Y[1:, 0], noisy[1:, 0])


@nb.njit
def _no_rhs(t, y, p, dy):
    dy[:] = 0.0


@nb.njit
def _no_event(t, y, p):
    return 1.0


# ---- slow: whole-press checks ------------------------------------------------------------
# small vibration about the start (motor disconnected: u = 0): the linearisation holds
QUIET = PRESS.resolve({"slider_stiffness": 1e9, "gravity": 0.0, "gear_ratio": 0.0,
                       "omega0": 0.0, "rocker_rate0": 0.01})


def test_press_linear_acceleration_threshold_from_linearised_modes():
    w, T = press.linearised_modes(QUIET)
    t_min = T[0]
    for ratio, stable in ((0.54, True), (0.56, False)):
        dt = ratio * t_min
        t = np.arange(301) * dt
        r = press_exact.simulate(QUIET, t, {"integrator": "linacc", "dt": dt})
        assert (r.status == "ok") == stable, (ratio, r.reason)
        if not stable:
            assert r.reason.startswith("unstable")
    t = np.arange(301) * 2.0 * t_min
    r = press_exact.simulate(QUIET, t, {"integrator": "wilson", "theta": 1.4, "dt": 2 * t_min})
    assert r.status == "ok"


def test_press_cycle_lock_event_and_impact_loss():
    cyc = PRESS_CYCLE.resolve({})
    t = PRESS_CYCLE.output_grid(cyc)
    runs = [press_exact.simulate(cyc, t, {"integrator": "rk4", "dt": dt}) for dt in (1e-4, 1e-5)]
    for r in runs:
        assert r.status == "ok"
        eb = r.channels["energy_balance"]
        assert np.max(np.abs(eb - eb[0])) < 1e-5 * (eb[0] + r.extra["press_work"][-1])
    t_lock = runs[1].extra["t_lock"][0]
    assert cyc["lock_after"] < t_lock < cyc["release_after"]
    assert abs(runs[0].extra["t_lock"][0] - t_lock) < 1e-8
    # plastic impact keeping p_φ: loss = ½ ψ'² (A22 − A12²/A11) at the lock state; the rate
    # jump φ'+ − φ'- = (A12/A11) ψ'-; check that they are consistent with each other
    loss = runs[1].extra["lock_energy_loss"][0]
    w_before, w_after = runs[1].extra["crank_rate_at_lock"]
    assert loss > 0.0 and w_after != w_before
    locked = runs[1].extra["locked"] == 1
    psi = runs[1].channels["rocker_angle"][locked]
    assert np.allclose(psi, math.radians(cyc["lock_angle"]), atol=1e-7)


def test_stiff_slider_1e9_energy():
    r = press_exact.simulate(PRESS.resolve({"slider_stiffness": 1e9}), T_OUT,
                             {"integrator": "rk4", "dt": 1e-6})
    eb = r.channels["energy_balance"]
    assert r.status == "ok"
    assert np.max(np.abs(eb - eb[0])) < 1e-6 * r.extra["motor_work"][-1]


def test_hundred_crank_revolutions_energy_drift():
    par = PRESS.resolve({"slider_stiffness": 1e8, "slider_damping": 1e5, "t_end": 6.0})
    t = PRESS.output_grid(par)
    r = press_exact.simulate(par, t, {"integrator": "rk4", "dt": 1e-5})
    c = r.channels
    assert r.status == "ok"
    assert (c["crank_angle"][-1] - c["crank_angle"][0]) / (2 * math.pi) > 100
    eb = c["energy_balance"]
    assert np.max(np.abs(eb - eb[0])) < 1e-6 * r.extra["motor_work"][-1]


def test_loop_violation_observable():
    """|B − A| − l2 from the reported (φ, ψ, x_C): zero on the independent geometry, and the
    size of a slider displacement along the rod when the slider is moved off the closure."""
    for q in _random_states(10)[1]:
        A, B, C = _geometry(q, DEFAULT, 1.0)
        assert phys.loop_violation(DEFAULT, q[0], q[1], C[0]) < 1e-15
        dx = 1e-6
        rod = (B - A) / np.linalg.norm(B - A)
        assert phys.loop_violation(DEFAULT, q[0], q[1], C[0] + dx) == pytest.approx(
            abs(rod[0]) * dx, rel=1e-3)
