"""Exudyn rotor leaf (reference_models/exudyn/rotor/) against independent numbers.

Independent references used here: closed-form whirl / oscillation frequencies, the conservation
of T + U − A and of the axial angular momentum, and the MuJoCo probe value of the final spin
(cone-angle spring, 1.5 N·m, 10 s: 43.310 rad/s, quoted to 5 digits).
"""
import math
from decimal import Decimal, getcontext

import numpy as np
import pytest

from compare.scenes.rotor import SPINUP, WHIRL
from reference_models.exudyn import rotor

BASE = SPINUP.resolve()
I_T = 5 * 0.25**2 / 4 + 5 * 0.5**2          # 1.328125
I_P = 5 * 0.25**2 / 2                       # 0.15625
K_EFF = 2000.0 - 5 * 9.81 * 0.5             # 1975.475


def grid(p):
    return np.linspace(0.0, p["t_end"], int(round(p["t_end"] / p["output_dt"])) + 1)


def run(settings=None, **over):
    p = SPINUP.resolve(over)
    t = grid(p)
    return t, rotor.simulate(p, t, settings or {})


def closed_whirl(spin):
    """Backward and forward roots of I_t w² ∓ I_p Ω w − k_eff = 0 (rad/s)."""
    a = I_P * abs(spin)
    root = math.sqrt(a * a + 4 * I_T * K_EFF)
    return (root - a) / (2 * I_T), (root + a) / (2 * I_T)


def rotations(quat):
    w, x, y, z = quat.T
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1)], 1)


def test_contract_shape_and_probe_value():
    """Default scene: channels on the grid, energy balance, and the MuJoCo probe's 43.310."""
    t, r = run()
    assert r.status == "ok" and r.t_fail is None
    assert set(r.channels) == set(SPINUP.channels)
    for v in r.channels.values():
        assert v.shape == t.shape and np.all(np.isfinite(v))
    assert r.extra["orientation"].shape == (len(t), 4)
    c = r.channels
    assert c["omega_norm"][-1] == pytest.approx(43.310, abs=1e-3)      # probe, 5 digits
    assert c["omega_norm"][-1] > 38.8 and 0.3 < c["tilt"][-1] < 0.5   # captured, tilt grows
    eb = c["energy_balance"]
    assert np.max(np.abs(eb - eb[0])) < 1e-5                          # measured 1.9e-6 J
    # balance starts at U(0) = −m g·r_c0 = m g l
    assert eb[0] == pytest.approx(5 * 9.81 * 0.5, rel=1e-12)
    # work is ∫ torque·ω_z: A(t) ≈ torque²·t²/(2 I_p) while the rotor is still upright
    i = int(round(1.0 / BASE["output_dt"]))
    assert c["work"][i] == pytest.approx(1.5**2 * 1.0**2 / (2 * I_P), rel=1e-3)


def test_free_oscillation_frequency():
    """torque 0, e 0, small tilt: planar oscillation at sqrt((k − m g l)/I_t)."""
    t, r = run(torque=0.0, eccentricity=0.0, tilt0=1e-3, t_end=2.0)
    assert r.status == "ok"
    q = r.extra["orientation"]
    alpha = 2 * np.arcsin(q[:, 1])                  # rotation about fixed x
    from scipy.optimize import minimize_scalar

    def resid(w):
        A = np.column_stack([np.cos(w * t), np.sin(w * t)])
        coef, *_ = np.linalg.lstsq(A, alpha, rcond=None)
        return np.sum((A @ coef - alpha) ** 2)

    w_ref = math.sqrt(K_EFF / I_T)                  # 38.5670 rad/s
    w = minimize_scalar(resid, bracket=(w_ref * 0.99, w_ref, w_ref * 1.01), tol=1e-12).x
    assert w == pytest.approx(w_ref, rel=2e-6)
    eb = r.channels["energy_balance"]
    assert np.max(np.abs(eb - eb[0])) < 1e-9


@pytest.mark.parametrize("spin", [0.0, 20.0, 41.3, 100.0])
def test_whirl_closed_form(spin):
    res = rotor.modes(WHIRL.resolve(dict(eccentricity=0.0, spin=spin)), {})
    w = np.array(res.frequencies_hz) * 2 * math.pi
    b, f = closed_whirl(spin)
    assert res.labels == ["backward whirl", "forward whirl"]
    assert w[0] == pytest.approx(b, rel=1e-6)
    assert w[1] == pytest.approx(f, rel=1e-6)


def test_whirl_negative_spin_labels():
    """Forward whirl follows the spin's sense: for Ω < 0 it is still the higher line."""
    res = rotor.modes(WHIRL.resolve(dict(eccentricity=0.0, spin=-30.0)), {})
    w = np.array(res.frequencies_hz) * 2 * math.pi
    b, f = closed_whirl(-30.0)
    assert res.labels == ["backward whirl", "forward whirl"]
    assert w == pytest.approx([b, f], rel=1e-6)


def test_eccentric_split_at_rest():
    """e along y, no gravity, Ω = 0: the spin coordinate condenses into the y-tilt inertia."""
    m, R, l, e, k = 5.0, 0.25, 0.5, 0.005, 2000.0
    i_xx = m * R * R / 4 + m * (l * l + e * e)
    i_yy = m * R * R / 4 + m * l * l
    i_zz = m * R * R / 2 + m * e * e
    i_yz = -m * e * l
    w_ref = sorted([math.sqrt(k / i_xx), math.sqrt(k / (i_yy - i_yz**2 / i_zz))])
    res = rotor.modes(WHIRL.resolve(dict(gravity=np.zeros(3), spin=0.0, eccentricity=0.005)), {})
    w = np.array(res.frequencies_hz) * 2 * math.pi
    assert w == pytest.approx(w_ref, rel=1e-8)
    assert w == pytest.approx([38.8039, 38.8203], abs=1e-4)        # values in the Exudyn notes


def test_whirl_sweep_matches_closed_form():
    spins = np.linspace(0.0, 150.0, 200)
    bw, fw = rotor.whirl_sweep(WHIRL.resolve({"eccentricity": 0.0}), spins)
    ref = np.array([closed_whirl(s) for s in spins])
    assert np.max(np.abs(bw / ref[:, 0] - 1)) < 1e-6
    assert np.max(np.abs(fw / ref[:, 1] - 1)) < 1e-6


def damped_whirl_50_digits(c_int, c_ext, spin):
    """The two roots of I_t λ² + (c_e + c_i − i I_p Ω) λ + (k_eff − i c_i Ω) = 0 (the damped
    whirl) by the quadratic formula in 50 digits, ascending in |Im λ| (rad/s)."""
    getcontext().prec = 50
    it, ip, k = Decimal(I_T), Decimal(I_P), Decimal(K_EFF)
    br, bi = Decimal(c_ext) + Decimal(c_int), -ip * Decimal(spin)
    cr, ci = k, -Decimal(c_int) * Decimal(spin)
    dr, di = br * br - bi * bi - 4 * it * cr, 2 * br * bi - 4 * it * ci      # b² − 4ac
    r = (dr * dr + di * di).sqrt()
    sr, si = ((r + dr) / 2).sqrt(), ((r - dr) / 2).sqrt().copy_sign(di)
    roots = [complex((-br + s * sr) / (2 * it), (-bi + s * si) / (2 * it)) for s in (1, -1)]
    return sorted(roots, key=lambda z: abs(z.imag))


@pytest.mark.parametrize("c_int, c_ext", [(0.5, 0.05), (0.1, 0.0)])
def test_damped_whirl_bars_hold_the_exact_roots_over_the_sweep(c_int, c_ext):
    """With internal damping the finite differences leave ~1e-8 × c_int Ω in the spin
    coordinate's row; solved with it, the whirl roots were 41–47 ulp off the exact quadratic
    against bars of 31 (`xval modes rotor-whirl --set spin=140 --set c_int=0.5 --set
    c_ext=0.05`: the Campbell sweep's forward whirl at 15.15 rad/s disagreed with the closed
    form, 8.8e-15 apart). The spin coordinate is ignorable there, and the tilt block's roots
    meet the exact ones within their bars at every speed of the sweep."""
    for spin in np.linspace(0.0, 150.0, 100):
        m = rotor.modes(WHIRL.resolve(dict(eccentricity=0.0, spin=spin, c_int=c_int,
                                           c_ext=c_ext)), {})
        exact = np.array([abs(z.imag) for z in damped_whirl_50_digits(c_int, c_ext, spin)])
        got = np.sort(np.array(m.frequencies_hz)) * 2 * math.pi
        bar = np.array(m.extra["frequency_error_hz"])[np.argsort(m.frequencies_hz)] * 2 * math.pi
        assert (np.abs(got - np.sort(exact)) <= bar).all(), (spin, np.abs(got - exact) / bar)


def test_large_tilt_chart_changes_conserve_energy_and_axial_momentum():
    """Start tilted 1.2 rad and spinning: the run changes Cardan charts and still conserves
    T + U (torque 0) and K_z (no axial moment: spring ⊥ e_z, gravity ∥ e_z)."""
    t, r = run({"integrator": "rk67", "dt": 5e-4}, torque=0.0, tilt0=1.2, spin0=60.0, t_end=1.0)
    assert r.status == "ok"
    assert r.settings["chart_changes"] >= 1
    eb = r.channels["energy_balance"]
    assert np.max(np.abs(eb - eb[0])) < 1e-5 * np.max(r.channels["kinetic"])
    Rm = rotations(r.extra["orientation"])
    w = r.extra["angular_velocity"]
    m, Rr = BASE["m"], BASE["R"]
    rc = Rm @ np.array([0.0, BASE["eccentricity"], BASE["l"]])
    I_disk = np.diag([m * Rr**2 / 4, m * Rr**2 / 4, m * Rr**2 / 2])
    I_c = np.einsum("nij,jk,nlk->nil", Rm, I_disk, Rm)
    I_o = I_c + m * (np.einsum("ni,ni->n", rc, rc)[:, None, None] * np.eye(3)
                     - np.einsum("ni,nj->nij", rc, rc))
    Kz = np.einsum("nj,nj->n", I_o[:, 2, :], w)
    assert np.max(np.abs(Kz - Kz[0])) < 1e-7 * np.max(np.abs(Kz))


def test_tilt_pi_is_reported_singular():
    p = SPINUP.resolve({"t_end": 0.5})
    p["tilt0"] = math.pi - 5e-4      # past the scene's admissible range: the leaf's own guard
    t = grid(p)
    r = rotor.simulate(p, t, {})
    assert r.status == "diverged"
    assert "tilt pi" in r.reason
    assert r.t_fail is not None and r.t_fail <= 0.5
    assert np.all(np.isnan(r.channels["omega_norm"][t > r.t_fail + 1e-12]))


def test_unstable_step_is_reported_not_returned():
    # through the adapter: its one energy rule sees the blow-up of explicit Euler at 10 ms
    from compare import solvers
    p = SPINUP.resolve({"tilt0": 0.01, "t_end": 2.0})
    r = solvers.simulate(SPINUP, solvers.get_solver("exudyn"), p,
                         {"integrator": "explicit-euler", "dt": 1e-2})
    t = r.t
    assert r.status == "diverged" and r.t_fail is not None
    om = r.channels["omega_norm"]
    assert np.all(np.isnan(om[t > r.t_fail]))
    assert np.all(np.isfinite(om[t < r.t_fail - 0.02]))


def test_pass_through_at_3_2():
    """3.2 N·m, 5 s: the rotor passes the critical band (probes: ~90.7 rad/s at 5 s)."""
    t, r = run(torque=3.2, t_end=5.0)
    c = r.channels
    assert r.status == "ok"
    assert 88.0 < c["omega_norm"][-1] < 93.0
    eb = c["energy_balance"]
    assert np.max(np.abs(eb - eb[0])) < 3e-6                          # measured 4.7e-7 J


def test_bad_settings():
    p = SPINUP.resolve({"t_end": 0.1})
    with pytest.raises(ValueError):
        rotor.simulate(p, grid(p), {"integrator": "nope"})
    with pytest.raises(ValueError):
        rotor.simulate(p, grid(p), {"integrator": "rk4", "dt": -1.0})
    with pytest.raises(ValueError):
        rotor.simulate(p, grid(p), {"integrator": "rk4", "dt": 0.2})    # > the horizon


def test_integrators_converge_to_same_spin():
    """Fixed-step RK4 and adaptive DOPRI5 land on the probe value as well."""
    for s in ({"integrator": "rk4", "dt": 5e-4}, {"integrator": "dopri5", "rtol": 1e-10}):
        t, r = run(s)
        assert r.status == "ok"
        assert r.channels["omega_norm"][-1] == pytest.approx(43.310, abs=1e-3)
        eb = r.channels["energy_balance"]
        assert np.max(np.abs(eb - eb[0])) < 1e-4


def test_step_longer_than_the_output_step_is_interpolated():
    """dt = 2 × output_dt runs on its own step grid, channels interpolated linearly: against the
    independent quaternion solver (rtol 1e-12) the final value (a step end) is off by the RK67
    error 2.8e-6 rad/s and the in-between samples by 3.1e-5 (measured); windows 10×."""
    from custom_models.rotor import quaternion as rotor_quaternion

    p = SPINUP.resolve({"t_end": 2})
    t = grid(p)
    ref = rotor_quaternion.simulate(p, t, {"rtol": 1e-12}).channels["omega_norm"]
    r = rotor.simulate(p, t, {"integrator": "rk67", "dt": 2 * p["output_dt"]})
    w = r.channels["omega_norm"]
    assert r.status == "ok" and np.all(np.isfinite(w))
    assert abs(w[-1] - ref[-1]) < 3e-5
    assert np.max(np.abs(w - ref)) < 3e-4
