"""Rotor spin-up: numbers from independent sources — closed forms, conservation laws, a second
formulation, the engines, and the MuJoCo/Exudyn probes in the shared notes."""
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from compare import solvers
from compare.analysis import metrics
from compare.analysis.identify import matrix_pencil, transverse_components
from compare.physics import rotation
from compare.scenes import get_scene

SCENE = get_scene("rotor-spinup")
I_T = 5 * 0.25**2 / 4 + 5 * 0.5**2          # 1.328125 kg·m²
I_P = 5 * 0.25**2 / 2


def run(solver, settings=None, **overrides):
    p = SCENE.resolve({k: str(v) for k, v in overrides.items()})
    s = solvers.get_solver(solver)
    base = solvers.resolve_settings(s.leaf(SCENE.name))
    return solvers.simulate(SCENE, s, p, {**base, **(settings or {})})


# --- rotation math against scipy and against its own definition ---------------------------

@pytest.mark.parametrize("theta", [np.array([0.3, -1.2, 0.7]), np.array([1e-7, 2e-7, -1e-7]),
                                   np.array([1.8, 2.4, 0.0])])
def test_rotation_tensor_and_zhilin(theta):
    L = rotation.rotation_tensor(theta)
    np.testing.assert_allclose(L, Rotation.from_rotvec(theta).as_matrix(), atol=1e-15)
    Z, Zi = rotation.zhilin(theta), rotation.zhilin_inverse(theta)
    np.testing.assert_allclose(Z @ Zi, np.eye(3), atol=1e-14)
    # ω = Z·θ' is the definition: ω× = L' Lᵀ, checked by central differences
    rate, h = np.array([0.4, -0.1, 0.9]), 1e-6
    W = (rotation.rotation_tensor(theta + h * rate) - rotation.rotation_tensor(theta - h * rate)
         ) / (2 * h) @ L.T
    np.testing.assert_allclose(Z @ rate, [W[2, 1], W[0, 2], W[1, 0]], atol=1e-9)
    # the spring is conservative because γ·Z(γ) = γ (paper): check it
    np.testing.assert_allclose(theta @ Z, theta, atol=1e-14)



def test_row_conversions_match_scipy_and_leave_nan_rows_nan():
    """matrices_to_quats against scipy (w ≥ 0), the Euler-vector leaf's rotations against
    scipy's rotation vector then the spin about z; a row with a NaN (or an inf) stays NaN."""
    from custom_models.rotor import euler_vector
    rng = np.random.default_rng(3)
    R = Rotation.random(5, random_state=4).as_matrix()
    R[1, 2, 0], R[3, 0, 1] = np.nan, np.inf
    q = rotation.matrices_to_quats(R)
    good = [0, 2, 4]
    ref = Rotation.from_matrix(R[good]).as_quat(scalar_first=True)
    ref *= np.where(ref[:, :1] < 0, -1.0, 1.0)
    np.testing.assert_allclose(q[good], ref, atol=1e-15)
    assert np.isnan(q[[1, 3]]).all()
    Y = rng.standard_normal((4, 8))
    Y[2, 7] = np.nan                       # a NaN in the work channel alone still blanks the row
    out = euler_vector.rotations(Y)
    for i in (0, 1, 3):
        ref = (Rotation.from_rotvec(Y[i, 3:6]) * Rotation.from_rotvec([0, 0, Y[i, 6]])).as_matrix()
        np.testing.assert_allclose(out[i], ref, atol=1e-14)
    assert np.isnan(out[2]).all()
    assert rotation.all_finite(Y[0]) and not rotation.all_finite(Y[2])

# --- the default scene: independent formulations agree, energy closes ---------------------

@pytest.fixture(scope="module")
def default_runs():
    return {s: run(s) for s in ("euler-vector", "quaternion")}


def test_custom_solvers_conserve_energy(default_runs):
    for tr in default_runs.values():
        assert tr.status == "ok"
        assert metrics.energy_residual(tr) <= 1e-6          # issue acceptance: ≤ 1e-6 J
    assert default_runs["quaternion"].invariants["quaternion_norm"] < 1e-10


def test_custom_solvers_match_the_mujoco_probe(default_runs):
    # notes/mujoco.md: cone-angle spring, gravity −z, 1.5 N·m → |ω(10 s)| = 43.310 rad/s
    for tr in default_runs.values():
        assert tr.final()["omega_norm"] == pytest.approx(43.310, abs=6e-4)
    # the two formulations agree to 6.4e-11 of scale (tests/allowances.json, rotor-spinup
    # 1.5Nm): window 5e-10
    d = metrics.deviation(default_runs["euler-vector"], default_runs["quaternion"],
                          "omega_norm", 0.0)
    assert d.max_rel < 5e-10


def test_all_four_solvers_agree_on_the_default_run(rotor_default_run):
    obj, _ = rotor_default_run
    by = {(c["a"], c["b"], c["channel"]): c for c in obj["comparisons"]}
    pairs = {(a, b) for a, b, _ in by}
    assert len(pairs) == 6
    # measured over the six pairs (tests/allowances.json, rotor-spinup 1.5Nm): omega_norm
    # ≤ 3.4e-9, tilt ≤ 1.4e-8 of scale (both custom–MuJoCo); windows ≤ 10 × that
    window = {"omega_norm": 3e-8, "tilt": 1e-7}
    for a, b in pairs:
        for ch, w in window.items():
            assert by[(a, b, ch)]["max_rel"] <= w, (a, b, ch)
    for r in obj["runs"]:
        bound = 1e-6 if r["solver"] in ("euler-vector", "quaternion") else 1e-3
        assert r["energy_residual"] <= bound, r["solver"]


def test_capture_at_low_torque(default_runs):
    tr = default_runs["euler-vector"]
    w = tr.channels["omega_norm"]
    # the probes: |ω| first exceeds 38.8 near t ≈ 4.2 s, then stalls (the free ramp would be
    # M·t/I_p = 96 rad/s at 10 s) with tilt ≈ 0.4 rad at 10 s
    t_pass = metrics.first_crossing(tr.t, w, np.sqrt(2000 / I_T))
    assert 4.0 < t_pass < 4.4
    assert w[-1] < 1.1 * np.sqrt((2000 - 5 * 9.81 * 0.5) / (I_T - I_P))
    assert tr.final()["tilt"] == pytest.approx(0.4, abs=0.02)


def test_passage_at_high_torque():
    tr = run("quaternion", torque=3.2, t_end=5)
    # passage, by the closed form: after the tilt peak the spin leaves the forward-whirl
    # critical speed √(k_eff/(I_t − I_p)) behind for good and ramps on at close to M/I_p
    crit = np.sqrt((2000 - 5 * 9.81 * 0.5) / (I_T - 5 * 0.25**2 / 2))     # 41.058 rad/s
    w = tr.channels["omega_norm"]
    late = tr.t >= 3.5
    assert np.all(w[late] > 1.2 * crit)                               # measured ≥ 1.44×
    ramp = np.polyfit(tr.t[late], w[late], 1)[0]
    assert ramp == pytest.approx(3.2 / (5 * 0.25**2 / 2), rel=0.05)   # measured 1.6 % below
    # the MuJoCo probe of the notes (Cardan spring, the same small-tilt law) peaks at ~3.0 s
    _, t_peak = metrics.peak(tr.t, tr.channels["tilt"])
    assert t_peak == pytest.approx(3.0, abs=0.05)                     # measured 2.99 s
    assert metrics.energy_residual(tr) <= 1e-6


# --- the linear case: closed-form frequency -------------------------------------------------

@pytest.mark.parametrize("solver", ["euler-vector", "quaternion"])
def test_free_oscillation_frequency_is_sqrt_keff_over_It(solver):
    tr = run(solver, torque=0, tilt0=1e-4, eccentricity=0, t_end=2, output_dt=0.001)
    gx, _ = transverse_components(tr.extra["orientation"])
    w, _ = matrix_pencil(gx, 0.001, n_modes=1)
    k_eff = 2000 - 5 * 9.81 * 0.5
    assert w[-1] == pytest.approx(np.sqrt(k_eff / I_T), rel=1e-6)


# --- order of the fixed-step method and failure reporting ----------------------------------

def test_rk4_shows_fourth_order():
    ref = run("euler-vector", {"rtol": 1e-13}, t_end=2)
    errs, dts = [], [4e-3, 2e-3, 1e-3]
    for dt in dts:
        tr = run("euler-vector", {"integrator": "rk4", "dt": dt}, t_end=2, output_dt=0.004)
        errs.append(abs(tr.final()["omega_norm"] - ref.final()["omega_norm"]))
    assert 3.6 < metrics.observed_order(dts, errs) < 4.4


def test_unstable_step_is_reported_not_returned():
    tr = run("euler-vector", {"integrator": "rk4", "dt": 0.05}, k=1e6, t_end=1, output_dt=0.05)
    assert tr.status == "diverged" and 0 < tr.t_fail <= 1
    assert np.isnan(tr.channels["omega_norm"][-1])


def test_falling_past_tilt_pi_is_detected():
    # k = 5 ≪ m·g·l cannot hold the disk up: it falls over towards tilt π, where both the
    # axial/transverse split and the spring direction are undefined (denominator (θ/2)cot(θ/2))
    tr = run("euler-vector", k=5, tilt0=0.1, torque=0, t_end=5)
    assert tr.status == "diverged" and "tilt reached pi" in tr.reason


def test_stable_but_wrong_integration_is_not_reported_ok():
    # k = 1e7: ω_n·dt = 2744·2.5e-4 = 0.69 lies inside RK4's stability interval, but RK4's
    # damping (|R| ≈ 1 − (ωh)⁶/144 per step) eats the 500 J of spring energy within 1 s: the
    # energy balance, not a NaN, is what must flag it; a 16× finer step conserves it
    kw = dict(k=1e7, t_end=1, tilt0=0.01, torque=0)
    coarse = run("quaternion", {"integrator": "rk4", "dt": 2.5e-4}, **kw)
    assert coarse.status == "diverged" and "energy balance" in coarse.reason
    fine = run("quaternion", {"rtol": 1e-11}, **kw)
    assert fine.status == "ok" and metrics.energy_residual(fine) < 1e-6 * 500
