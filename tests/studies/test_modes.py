"""Whirl frequencies from every solver against the closed form; mode matching; frequency
identification from time series (issue: natural frequencies from every solver)."""
import numpy as np
import pytest

from compare import solvers
from compare.analysis import metrics
from compare.analysis.identify import fft_peak, matrix_pencil
from compare.analysis.trajectory import Modes
from compare.scenes import get_scene
from compare.workflows.modes import by_name, critical_speeds, sweep, track

SCENE = get_scene("rotor-whirl")
M, R, L, K, G = 5.0, 0.25, 0.5, 2000.0, 9.81
I_T, I_P = M * R**2 / 4 + M * L**2, M * R**2 / 2
LINEARISING = ("euler-vector", "exudyn", "mujoco", "closed-form")


def closed_form(spin, k_eff):
    """Roots of I_t w² ∓ I_p Ω w − k_eff = 0 (backward, forward)."""
    root = np.sqrt((I_P * spin) ** 2 + 4 * I_T * k_eff)
    return (root - I_P * spin) / (2 * I_T), (root + I_P * spin) / (2 * I_T)


@pytest.mark.parametrize("gravity, k_eff", [("0,0,-9.81", K - M * G * L), ("0,0,0", K)])
@pytest.mark.parametrize("spin", [0.0, 20.0, 41.3, 100.0])
def test_every_solver_matches_the_closed_form(spin, gravity, k_eff):
    p = SCENE.resolve({"spin": str(spin), "gravity": gravity})
    b, f = closed_form(spin, k_eff)
    for name in LINEARISING:
        res = solvers.modes(SCENE, solvers.get_solver(name), p)
        assert res.status == "ok", res.reason
        got = dict(zip(res.labels, 2 * np.pi * res.frequencies_hz))
        assert got["backward whirl"] == pytest.approx(b, rel=1e-6), name
        assert got["forward whirl"] == pytest.approx(f, rel=1e-6), name


@pytest.mark.parametrize("gravity, k_eff", [("0,0,-9.81", K - M * G * L), ("0,0,0", K)])
def test_critical_speeds_and_labels(gravity, k_eff):
    p = SCENE.resolve({"gravity": gravity})
    spins = np.linspace(0, 150, 60)
    fwd_crit = np.sqrt(k_eff / (I_T - I_P))       # 41.31 rad/s with k_eff = k
    bwd_crit = np.sqrt(k_eff / (I_T + I_P))
    for name in ("euler-vector", "exudyn", "mujoco"):
        s = solvers.get_solver(name)
        results = sweep(SCENE, s, p, spins)
        lines = track(results)
        fwd, bwd = lines["forward whirl"], lines["backward whirl"]
        assert np.all(np.diff(fwd) > 0) and np.all(np.diff(bwd) < 0)        # fwd ↑, bwd ↓
        entries = critical_speeds(SCENE, s, p, spins, results)
        crit = by_name(entries)
        assert {e["name"]: e["whirl"] for e in entries} == {"forward whirl": "forward",
                                                            "backward whirl": "backward"}
        assert crit["forward whirl"] == pytest.approx(fwd_crit, rel=1e-8), name
        assert crit["backward whirl"] == pytest.approx(bwd_crit, rel=1e-8), name
    if gravity == "0,0,0":      # the spec's figure (scene-rotor.md: "≈ 41.3 rad/s for k_eff = k")
        assert crit["forward whirl"] == pytest.approx(41.3, abs=0.05)


def test_eccentric_pair_is_split_found_and_paired_once():
    # eccentricity e along body y couples y-tilt with the free spin: condensing the spin
    # coordinate, w² are the eigenvalues of k·(I_O⁻¹) restricted to the tilt block
    e = 0.005
    rc = np.array([0, e, L])
    I_o = np.diag([M * R**2 / 4, M * R**2 / 4, M * R**2 / 2]) + M * (rc @ rc * np.eye(3)
                                                                     - np.outer(rc, rc))
    expected = np.sort(np.sqrt(K * np.linalg.eigvalsh(np.linalg.inv(I_o)[:2, :2])))
    assert expected == pytest.approx([38.8039, 38.8203], abs=1e-4)    # notes' numbers
    p = SCENE.resolve({"eccentricity": str(e), "gravity": "0,0,0"})
    found = {}
    for name in ("euler-vector", "exudyn", "mujoco"):
        res = solvers.modes(SCENE, solvers.get_solver(name), p)
        found[name] = res
        assert np.sort(2 * np.pi * res.frequencies_hz) == pytest.approx(expected, rel=1e-6)
    # matching by value with the gap check: each mode paired exactly once, to its twin
    a = Modes("x", "a", np.array(expected) / (2 * np.pi), ["", ""])
    b = Modes("x", "b", np.array(expected[::-1]) / (2 * np.pi), ["", ""])
    pairs = metrics.match_modes(list(a.frequencies_hz), a.labels, list(b.frequencies_hz),
                                b.labels)
    assert pairs == [(0, 1), (1, 0)]


def test_matching_refuses_ambiguous_pairs():
    # one mode of b sits between two close modes of a: it must not be claimed twice, and the
    # ambiguous one is left unpaired rather than guessed
    pairs = metrics.match_modes([1.00, 1.02, 5.0], ["", "", ""], [1.011, 5.0001], ["", ""])
    assert pairs == [(2, 1)]
    assert metrics.match_modes([1.0, 2.0], ["flap 1", "lag 1"], [2.0, 1.0],
                               ["lag 1", "flap 1"]) == [(0, 1), (1, 0)]


def test_matching_pairs_a_family_by_frequency_not_by_its_number():
    # helicopter-hover, `xval calibrate --seed 2026` set 6: Exudyn names a coupled fuselage–
    # rotor root "fuselage 2", so its list's second flap cyclic is the 15.66 Hz one; by number
    # mstmm's 4.45 Hz flap cyclic 2 met it (0.72 apart). Within the family by frequency, it is
    # left unpaired, and the 15.66 Hz modes meet their twins
    mstmm = ([4.4366, 4.4547, 15.6564, 15.6759],
             ["flap cyclic 1", "flap cyclic 2", "flap cyclic 3", "flap cyclic 4"])
    exudyn = ([4.4297, 15.6583, 15.6738], ["flap cyclic 1", "flap cyclic 2", "flap cyclic 3"])
    why = {}
    assert metrics.match_modes(*mstmm, *exudyn, why) == [(0, 0), (2, 1), (3, 2)]
    assert "fewer 'flap cyclic' modes" in why[("a", 1)]


def test_matching_leaves_two_far_apart_modes_unpaired():
    # the last two left over are no pair for being alone: 15.68 Hz against 0.36 Hz
    why = {}
    assert metrics.match_modes([15.6773], ["flap differential 2"], [0.3643], ["fuselage 1"],
                               why) == []
    assert "not within a factor 2" in why[("a", 0)]
    # a root one names lag and the other fuselage, within both lists, meets its twin
    assert metrics.match_modes([11.9616, 13.2], ["lag collective 1", "flap 3"], [11.9652, 13.21],
                               ["fuselage 3", "flap 3"]) == [(0, 0), (1, 1)]


def test_matching_leaves_a_mode_whose_twin_is_past_the_others_list_unpaired():
    # rotating-beam, `xval calibrate --seed 5150` set 8 (L 3.58 m, chord 0.71 m): the
    # rigid-segment engines' lag 1 (rotary inertia ∝ (chord/L)², −0.7 %) falls below flap 4 and
    # is their fifth mode, mstmm's fifth is flap 4 and its lag 1 sixth; the two fifths met as
    # the last pair, 0.34 Hz apart against a 0.019 Hz bound
    mstmm = ([1.364091, 8.548609, 16.176658, 23.936354, 46.9057],
             ["flap 1", "flap 2", "torsion 1", "flap 3", "flap 4"])
    exudyn = ([1.364082, 8.548217, 16.176658, 23.933796, 46.569578],
              ["flap 1", "flap 2", "torsion 1", "flap 3", "lag 1"])
    why = {}
    assert metrics.match_modes(*mstmm, *exudyn, why) == [(i, i) for i in range(4)]
    assert "past the other's list" in why[("a", 4)]
    assert "not among the other's" in why[("b", 4)]
    # helicopter-clamped, `--seed 5150` set 5 (33.6 rad/s): the engines' 13 modes end at their
    # flap cyclic 7 (15.789 Hz) and list one flap differential, mstmm's end at its flap
    # differential 2 (15.816 Hz): the two last met, and that differential "disagreement" then
    # kept the frame explanation from 16 engine–paper differences (its condition: the pair
    # agrees on the differential modes)
    heli_mstmm = ([5.954285, 15.816491], ["flap differential 1", "flap differential 2"])
    heli_engine = ([5.954332, 15.623211, 15.788886],
                   ["flap differential 1", "flap cyclic 6", "flap cyclic 7"])
    why = {}
    assert metrics.match_modes(*heli_mstmm, *heli_engine, why) == [(0, 0)]
    assert "past the other's list" in why[("a", 1)]
    # the same fifth modes inside both lists (each solver's sixth given) still pair by family
    mstmm6 = (mstmm[0] + [47.2], mstmm[1] + ["lag 1"])
    exudyn6 = (exudyn[0] + [46.89], exudyn[1] + ["flap 4"])
    assert metrics.match_modes(*mstmm6, *exudyn6) == [(i, i) for i in range(4)] + [(4, 5),
                                                                                    (5, 4)]


def test_identification_on_a_known_signal():
    dt, w0, z0 = 1e-3, 38.567, 0.002
    t = np.arange(0, 2, dt)
    x = np.exp(-z0 * w0 * t) * np.cos(w0 * np.sqrt(1 - z0**2) * t + 0.3) + 0.2 * np.cos(3 * w0 * t)
    w, zeta = matrix_pencil(x, dt, n_modes=2)
    assert w[0] == pytest.approx(w0 * np.sqrt(1 - z0**2), rel=1e-9)
    assert zeta[0] == pytest.approx(z0, rel=1e-6)
    assert w[1] == pytest.approx(3 * w0, rel=1e-9)
    # the FFT estimate converges as the record lengthens
    errs = [abs(fft_peak(np.cos(w0 * t[:n]), dt) - w0) for n in (250, 500, 1000, 2000)]
    assert errs[-1] < errs[0] and errs[-1] / w0 < 5e-3


@pytest.mark.parametrize("solver", ["exudyn", "mujoco"])
def test_engines_free_response_gives_the_closed_form_frequency(solver):
    from compare.workflows.modes import _run_time
    p = SCENE.resolve()
    rows, _ = SCENE.identify(p, _run_time, [solver])
    k_eff = K - M * G * L
    assert rows[0]["status"] == "ok"
    assert rows[0]["matrix_pencil"][-1] == pytest.approx(np.sqrt(k_eff / I_T), rel=1e-4)


def test_reported_critical_speeds_are_crossings_of_the_solver_itself():
    """A critical speed is where the named mode's frequency equals the excitation. Every one
    reported for the hovering helicopter (mstmm) satisfies that definition when the solver is
    run again at that speed, to 1e-8 of the frequency; a crossing the solver cannot confirm is
    not reported (the 'fuselage' lines pass between differently named modes below 10 rad/s,
    where a parabola extrapolated a root to 4.98 rad/s from points at 4.54): it is listed as
    unconfirmed with why, and the solver run again at the lines' estimate indeed has no mode
    of that name."""
    sc = get_scene("helicopter-hover")
    s = solvers.get_solver("mstmm")
    p = sc.resolve()
    values = sc.campbell.values(p)
    unconfirmed = []
    crit = by_name(critical_speeds(sc, s, p, values, sweep(sc, s, p, values),
                                   unconfirmed=unconfirmed))
    assert crit
    assert sorted(u["name"] for u in unconfirmed) == ["fuselage 1", "fuselage 2"]
    for u in unconfirmed:
        assert u["name"] not in crit and u["step"][0] < u["lines_estimate"] < u["step"][1]
        assert f"no mode {u['name']!r}" in u["reason"]
        assert u["name"] not in solvers.modes(sc, s, {**p, "speed": u["lines_estimate"]}).labels
    for name, v in crit.items():
        m = solvers.modes(sc, s, {**p, "speed": v})
        f = m.frequencies_hz[m.labels.index(name)]
        assert f == pytest.approx(sc.campbell.excitation_hz(p, v), rel=1e-8), name


def test_frequency_verdicts_weigh_the_solvers_error_estimates():
    """|Δ| = 1e-5 Hz on 10 Hz: beyond a 1e-7 relative allowance (1e-6 Hz), within it plus
    error estimates of 6e-6 Hz each; without an estimate on one side, the allowance alone."""
    def m(name, f, err=None):
        return Modes("x", name, np.array([f]), ["flap 1"],
                     extra={} if err is None else {"frequency_error_hz": [err]})
    TOL = {"frequency": 1e-7}
    c, = metrics.frequency_comparisons([m("a", 10.0, 6e-6), m("b", 10.00001, 6e-6)], TOL)
    assert c.verdict == "agree" and c.error_estimate == pytest.approx(1.2e-5)
    assert c.ratio == pytest.approx(1e-5 / (1.2e-5 + 1.00001e-6), rel=1e-4)
    assert c.shown == "agree (marginal)"
    c, = metrics.frequency_comparisons([m("a", 10.0, 4e-6), m("b", 10.00001, 4e-6)], TOL)
    assert c.verdict == "disagree"
    c, = metrics.frequency_comparisons([m("a", 10.0, 6e-6), m("b", 10.00001)], TOL)
    assert c.verdict == "disagree" and c.error_estimate is None


def test_rotor_whirl_estimates_contain_the_closed_form_error():
    """The euler-vector linearisation's finite-difference estimate contains its distance to
    the closed form (exact at zero eccentricity), and stays within 1e-12 relative of it."""
    sc = get_scene("rotor-whirl")
    for spin in (0.0, 50.0, 140.0):
        p = sc.resolve({"spin": spin})
        exact = solvers.modes(sc, solvers.get_solver("closed-form"), p).frequencies_hz
        ev = solvers.modes(sc, solvers.get_solver("euler-vector"), p)
        err = metrics.frequency_errors(ev)
        assert np.all(np.abs(ev.frequencies_hz - exact) <= err)
        assert np.all(err <= 1e-12 * exact)


def test_unpaired_modes_are_listed_with_why(tmp_path, monkeypatch):
    """helicopter-clamped, mstmm and fem, 18 modes: every mode is either compared or listed as
    unpaired, never dropped. The listed ones are exactly the modes inside a repeated root
    (another mode of the same solver within 1e-9 relative — found here from the frequencies)
    whose label the other solver does not use. Which basis of a repeated root a solver returns
    is round-off (custom_models/mstmm/labels.py): the blade torsion pair at 19.868 Hz came out
    'torsion differential' in mstmm and 'torsion collective' in fem on an Intel AVX-512 machine
    (4 of 40 modes per solver unpaired at 40 modes, with the pair at 57.27 Hz) and 'torsion
    collective' in both on an AMD AVX2 one (all 18 paired). So the labels inside a repeated root
    are given the first machine's words here, on every machine (mstmm 'differential', fem
    'collective'): a relabelling of the same frequencies and spanned space, which the pairing
    must list, not drop."""
    from compare import solvers
    from compare.workflows.modes import run_modes
    modes = solvers.modes

    def first_machines_basis(sc, s, params):
        m = modes(sc, s, params)
        was, word = (("collective", "differential") if m.solver == "mstmm" else
                     ("differential", "collective"))
        f = m.frequencies_hz
        m.labels = [lb.replace(was, word)
                    if any(j != i and abs(f[j] / f[i] - 1) < 1e-9 for j in range(len(f)))
                    else lb for i, lb in enumerate(m.labels)]
        return m
    monkeypatch.setattr(solvers, "modes", first_machines_basis)
    r = run_modes("helicopter-clamped", ["mstmm", "fem"], {"n_modes": 18},
                  log=lambda m: None, campbell_sweep=False, identify=False)
    r.save(tmp_path)
    obj, res, comps = r.to_json(), list(r.runs.values()), r.comparisons
    m = {r.solver: r for r in res}

    def expected(mine, other):
        f = mine.frequencies_hz
        return {lb for i, lb in enumerate(mine.labels) if lb not in other.labels
                and any(j != i and abs(f[j] / f[i] - 1) < 1e-9 for j in range(len(f)))}
    listed = obj["unpaired_modes"]
    for s, o in (("mstmm", "fem"), ("fem", "mstmm")):
        mine = {u["mode"] for u in listed if u["solver"] == s}
        assert mine == expected(m[s], m[o]) and len(mine) == 2, (s, mine)
        assert len(comps) + len(mine) == len(m[s].frequencies_hz) == 18
    assert all("not among the other's" in u["reason"] and "under half" in u["reason"]
               for u in listed)
    assert obj["summary"].endswith("; 4 modes unpaired")
    report = open(obj["report"]).read()
    assert "Modes left unpaired" in report and "torsion collective 1" in report
