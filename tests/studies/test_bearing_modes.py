"""Damped modes of the two-bearing rotor about its steady spin (`xval modes bearing-rotor`,
issue 28 part 1): every solver's linearisation against the closed form written here from the
bearing constants, the ring-down of every time solver against the eigenvalues, the ζ verdicts
and the modes JSON/table. Tolerances are ≤ 10 × the deviations measured (numbers in the
comments)."""
import json

import numpy as np
import pytest

from compare import solvers
from compare.analysis.identify import pencil_poles
from compare.analysis.trajectory import Modes
from compare.cli import main
from compare.physics import bearing_rotor as phys
from compare.results.modes import log_dec
from compare.scenes import bearing, get_scene
from compare.workflows.modes import _run_time, identified_against_eigenvalues

TIME = get_scene("bearing-rotor")
SCENE = TIME.modal()
SOLVERS = tuple(SCENE.leaves)
# the gyroscopic split grows with the spin: 627 rad/s (the balance with a 2000 rad/s motor)
CASES = {"default": {}, "spin 627": {"motor_no_load_speed": "2000"}}


def modes_of(name, params):
    m = solvers.modes(SCENE, solvers.get_solver(name), params)
    assert m.status == "ok", m.reason
    return m


def roots(m):
    """label -> (ω_d rad/s, ζ, whirl) of a Modes."""
    return {lb: (2 * np.pi * f, z, w) for lb, f, z, w in zip(m.labels, m.frequencies_hz,
                                                             m.damping, m.whirl)}


# ------------------------------------------------------------------ the closed form itself
def test_closed_form_cylindrical_mode_is_the_issues_number():
    """ω_n = √(2k_b/m), ζ = 2c_b/(2√(2k_b m)): 575.181 rad/s and 0.0866 (issue 28, from a
    time-domain ring-down fit of all three solvers; given to the digits quoted)."""
    lam, whirl = phys.modal_closed_form(SCENE.resolve({}))["cylindrical forward"]
    assert lam.imag == pytest.approx(575.181, abs=5e-4)
    assert -lam.real / abs(lam) == pytest.approx(0.0866, abs=5e-5)
    assert whirl == "forward"


@pytest.mark.parametrize("case", CASES)
def test_closed_form_conical_pair_obeys_vieta_and_rest(case):
    """The conical pair solves J_t s² + (c_θ − iJ_pΩ)s + k_θ = 0: the forward and backward
    damped frequencies differ by J_pΩ/J_t and their decay rates add to c_θ/J_t (sum of the
    roots); at Ω = 0 both are √(k_b l²/(2J_t)) · √(1 − ζ²), ζ = c_θ/(2√(k_θ J_t))."""
    p = SCENE.resolve(CASES[case])
    cf = phys.modal_closed_form(p)
    spin = phys.steady_spin_rate(p)
    f, b = cf["conical forward"][0], cf["conical backward"][0]
    assert f.imag - b.imag == pytest.approx(p["J_p"] * spin / p["J_t"], rel=1e-12)
    assert -(f.real + b.real) == pytest.approx(p["c_b"] * p["l"] ** 2 / 2 / p["J_t"], rel=1e-12)
    rest = phys.modal_closed_form(SCENE.resolve({"motor_stall_torque": "0"}))
    kt, ct = p["k_b"] * p["l"] ** 2 / 2, p["c_b"] * p["l"] ** 2 / 2
    zeta = ct / (2 * np.sqrt(kt * p["J_t"]))
    for label in ("conical forward", "conical backward"):
        lam = rest[label][0]
        assert lam.imag == pytest.approx(np.sqrt(kt / p["J_t"] * (1 - zeta ** 2)), rel=1e-12)
        assert -lam.real / abs(lam) == pytest.approx(zeta, rel=1e-12)


# ------------------------------------------------------------------ every solver's eigenvalues
@pytest.mark.parametrize("case", CASES)
@pytest.mark.parametrize("name", SOLVERS)
def test_every_solver_matches_the_closed_form(name, case):
    """Every mode's damped frequency, ζ and whirl. Measured against the closed form: ω_d within
    1.8e-11 relative (the axial root's round-off of z_a − l/2 in all three; conical ≤ 7e-13),
    ζ within 4.9e-12 (Exudyn's numerical differentiation)."""
    p = SCENE.resolve(CASES[case])
    cf = phys.modal_closed_form(p)
    got = roots(modes_of(name, p))
    assert set(got) == set(cf) - {"spin"}
    for label, (w, z, whirl) in got.items():
        lam, want = cf[label]
        assert w == pytest.approx(lam.imag, rel=1e-10), label
        assert z == pytest.approx(-lam.real / abs(lam), abs=5e-11), label
        assert whirl == want, label


@pytest.mark.parametrize("name", SOLVERS)
def test_spin_root_matches_the_motor_and_friction_slopes(name):
    """The real root of the spin rate, −(M_stall/ω_0 + c_drag)/J_p = −11.25 1/s at the
    defaults. Measured: quaternion 1e-15, Exudyn 1.4e-9, MuJoCo 5.8e-8 relative (the spin
    velocity's round-off in (A22 − I)/h)."""
    p = SCENE.resolve({})
    want = -(p["motor_stall_torque"] / p["motor_no_load_speed"] + p["bearing_drag"]) / p["J_p"]
    (got,) = modes_of(name, p).extra["real_roots_per_s"]
    assert got == pytest.approx(want, rel=5e-7)


def test_undamped_bearings_give_zero_damping_ratios():
    p = SCENE.resolve({"c_b": "0"})
    for name in SOLVERS:
        for label, (_, z, _) in roots(modes_of(name, p)).items():
            assert abs(z) < 1e-10, (name, label)


def test_dropping_the_damping_of_one_solver_fails_the_damping_verdict(monkeypatch):
    """The ζ verdicts have the power to see a 1 % error in c_b reaching one solver."""
    p = SCENE.resolve({})
    leaf = solvers.get_solver("mujoco").leaf(SCENE)
    true = leaf.modes
    monkeypatch.setattr(leaf, "modes", lambda params, settings=None: true(
        {**params, "c_b": 1.01 * params["c_b"]}, settings))
    runs = [modes_of(n, p) for n in SOLVERS]
    zeta = [c for c in SCENE.verdicts(p, runs) if c.channel.endswith("ζ")
            and c.channel != "axial ζ"]
    assert {c.verdict for c in zeta if "mujoco" in (c.a, c.b)} == {"disagree"}
    assert {c.verdict for c in zeta if "mujoco" not in (c.a, c.b)} == {"agree"}


def test_every_pair_agrees_at_the_defaults():
    p = SCENE.resolve({})
    comps = SCENE.verdicts(p, [modes_of(n, p) for n in SOLVERS])
    assert len(comps) == 3 * 5 * 2 and {c.verdict for c in comps} == {"agree"}


# ------------------------------------------------------------------ ring-down
def test_pencil_poles_of_a_complex_orbit():
    """Two whirls of an orbit x + iy, forward (Im λ > 0) and backward, recovered from samples
    of a constructed sum (the poles are what the record was made of)."""
    dt = 5e-5
    t = np.arange(800) * dt
    lam = np.array([-50 + 575.2j, -149.47 - 986.85j])
    x = 1e-6 * np.exp(lam[0] * t) + 3e-7 * np.exp(lam[1] * t)
    for pencil in (None, 20):                       # N/3 columns, and the ring-down's 20
        got = pencil_poles(x[::4], 4 * dt, 2, pencil)
        assert np.sort_complex(got) == pytest.approx(np.sort_complex(lam), rel=1e-11)


def ring_down_of(names):
    p = SCENE.resolve({})
    rows, md = SCENE.identify(p, _run_time, list(names))
    return p, rows, md


@pytest.mark.parametrize("name", ["quaternion", "exudyn", "mujoco"])
def test_ring_down_confirms_the_eigenvalues(name):
    """The free response of the time solver fitted by the matrix pencil against the same
    solver's eigenvalues, judged by the scene's verdicts (error estimates: the rerun at the
    solver's tighter settings); and against the closed form. Measured against the closed
    form: quaternion ω_d 1.6e-11 relative, ζ 1.6e-12; the engines ≤ 1.4e-10, ζ ≤ 1.9e-10."""
    p, rows, _ = ring_down_of([name])
    (row,) = rows
    assert row["status"] == "ok", row.get("reason")
    eig, fit = identified_against_eigenvalues(SCENE, row, [modes_of(name, p)])
    comps = SCENE.verdicts(p, [eig, fit])
    assert len(comps) == 10 and {c.verdict for c in comps} == {"agree"}
    cf = phys.modal_closed_form(p)
    for label, (w, z, whirl) in roots(fit).items():
        lam, want = cf[label]
        assert w == pytest.approx(lam.imag, rel=1e-9), label
        assert z == pytest.approx(-lam.real / abs(lam), abs=2e-9), label
        assert whirl == want, label


def test_allowances_are_within_10x_of_measured():
    """The modal allowances of bearing.py against the deviations left beyond both error
    estimates at the cases they were measured in; each must cover them (verdict agree) and be
    no wider than 10 × the largest."""
    tol = SCENE.tolerances
    left = {"eig f": 0.0, "eig ζ": 0.0, "ring f": 0.0, "ring ζ": 0.0}
    for ov in ({}, {"motor_no_load_speed": "2000"}, {"c_b": "0"}, {"k_b": "1e7"}):
        p = SCENE.resolve(ov)
        runs = [modes_of(n, p) for n in SOLVERS]
        rows, _ = SCENE.identify(p, _run_time, None)
        comps = SCENE.verdicts(p, runs) + [
            c for row in rows
            for c in SCENE.verdicts(p, list(identified_against_eigenvalues(SCENE, row, runs)))]
        assert {c.verdict for c in comps} == {"agree"}, ov
        for c in comps:
            key = ("ring" if "ring-down" in c.b else "eig") + (" ζ" if c.channel.endswith("ζ")
                                                              else " f")
            left[key] = max(left[key], max(0.0, c.deviation - (c.error_estimate or 0.0))
                            / c.scale)
    ring = next(iter(tol["frequency_by_solver"].values()))
    ring_z = next(iter(tol["damping_by_solver"].values()))
    for allowance, measured in ((tol["frequency"], left["eig f"]), (tol["damping"],
                                left["eig ζ"]), (ring, left["ring f"]), (ring_z, left["ring ζ"])):
        assert measured <= allowance <= 10 * measured


# ------------------------------------------------------------------ scene, CLI, JSON
def test_initial_conditions_start_every_time_solver_alike():
    """spin0, offset0, tilt0 (the ring-down's release) read the same in every time solver at
    t = 0: spin rate, and journal a at sag + offset + (l/2)(0, −sin θ, cos θ − 1)."""
    p = TIME.resolve({"spin0": "70", "offset0": "1e-6,2e-6,0", "tilt0": "1e-4",
                      "t_end": "1e-4", "output_dt": "1e-4"})
    sag = phys.static_sag(p)
    for name in SOLVERS:
        s = solvers.get_solver(name)
        tr = solvers.simulate(TIME, s, p, solvers.settings_for(s, TIME))
        assert tr.status == "ok", tr.reason
        assert tr.channels["spin_rate"][0] == pytest.approx(70.0, rel=1e-14)
        assert tr.channels["journal_a_x"][0] == pytest.approx(sag[0] + 1e-6, abs=1e-15)
        assert tr.channels["journal_a_y"][0] == pytest.approx(
            sag[1] + 2e-6 - 0.3 * np.sin(1e-4), abs=1e-15)


def test_held_parameters_are_refused_and_time_scenes_without_linearisation_too(capsys):
    assert main(["modes", "bearing-rotor", "--set", "defect_height=1e-5"]) == 2
    err = capsys.readouterr().err
    assert "defect_height: held at 0.0" in err and len(err.strip().splitlines()) == 1
    assert main(["modes", "press"]) == 2
    assert "time-domain scene" in capsys.readouterr().err


def test_modes_json_lists_the_damped_modes(tmp_path, capsys, monkeypatch):
    """`xval modes bearing-rotor --json` (contract.md, "Rotordynamic results"): per run ω_d,
    rpm, ζ, log dec δ = 2πζ/√(1 − ζ²), whirl; the ring-down rows with the same, and their
    verdicts against the eigenvalues among the comparisons."""
    monkeypatch.setattr(bearing, "RING_T", 0.01)            # a short record: this is the format
    assert main(["modes", "bearing-rotor", "--solver", "quaternion", "--json",
                 "--out", str(tmp_path)]) == 0
    obj = json.loads(capsys.readouterr().out)
    (run,) = obj["runs"]
    i = run["labels"].index("cylindrical forward")
    assert run["omega_d"][i] == pytest.approx(575.181, abs=5e-4)
    assert run["rpm"][i] == pytest.approx(575.181 * 60 / (2 * np.pi), abs=5e-3)
    assert run["zeta"][i] == pytest.approx(0.0866, abs=5e-5)
    z = run["zeta"][i]
    assert run["log_dec"][i] == pytest.approx(2 * np.pi * z / np.sqrt(1 - z * z), rel=1e-14)
    assert run["whirl"][i] == "forward"
    (ring,) = obj["identified_from_free_response"]
    assert ring["whirl"][ring["labels"].index("conical backward")] == "backward"
    assert any(c["b"] == "quaternion ring-down" and c["channel"] == "cylindrical forward ζ"
               for c in obj["comparisons"])
    assert "| log dec |" in open(obj["report"]).read()


def test_log_dec_of_critical_damping_is_infinite():
    assert log_dec([0.0, 1.0])[0] == 0.0 and np.isinf(log_dec([1.0])[0])


def test_modes_of_a_time_scene_keep_their_kind():
    """The modal view is a frequency scene; the scene itself stays a time scene."""
    assert TIME.is_time and not TIME.is_modes and SCENE.is_modes and SCENE.name == TIME.name
    assert isinstance(modes_of("quaternion", SCENE.resolve({})), Modes)
