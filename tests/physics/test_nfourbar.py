"""The N four-bar mechanism (scene `n-four-bar`): the reference integration against energy
conservation (the energies from every rod's own motion, not from the one-coordinate form the
reference integrates), the quadrature t(φ) = ∫ dφ/|φ'(φ)| of energy conservation (the
singular passages and every row of the scene's table), the small-amplitude period
2π√(c_T/c_V) about the hanging position, Radau, and the scene's table against a fresh
integration."""
import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

from compare.physics import nfourbar as phys
from compare.scenes import get_scene
from compare.scenes.benchmarks_nfourbar import REF_PHI, REF_T

SCENE = get_scene("n-four-bar")
DEFAULT = SCENE.resolve({})


def t_of(p, phi):
    """The time from the start to φ (the library's motion turns one way: |φ'| ≥ |φ'(0)| > 0
    throughout) by energy conservation, φ'² = φ0'² − 2 (c_V/c_T)(sin φ − sin φ0), φ0' from B_0's
    velocity written here (ẋ_B0 = −L sin φ φ')."""
    c_t, c_v = coefficients(p)
    phi0, w0 = p["phi0"], p["vx0"] / (p["L"] * math.sin(p["phi0"]))
    return quad(lambda f: 1.0 / math.sqrt(w0 * w0 - 2 * c_v / c_t * (math.sin(f) -
                                                                     math.sin(phi0))),
                phi, phi0, epsabs=1e-14, epsrel=1e-13, limit=400)[0]


def coefficients(p):
    """Written here from the rods (not the module's): N + 1 cranks about their pins
    (m L²/3 each, centres at L/2 sin φ) and N couplers translating with the tips (m L² per
    unit φ'², centres at L sin φ)."""
    n, m, L, g = p["N"], p["m"], p["L"], p["g"]
    return (n + 1) * m * L * L / 3 + n * m * L * L, (n + 1) * m * g * L / 2 + n * m * g * L


@pytest.fixture(scope="module")
def reference_10s():
    t = SCENE.output_grid(DEFAULT)
    return t, phys.reference(DEFAULT, t)


def test_reference_conserves_energy_and_agrees_with_radau(reference_10s):
    """DOP853 at 1e-12: the energy balance (every rod's kinetic and potential energy) within
    2e-8 J of the 1214 J peak kinetic energy over 10 s (measured 5.4e-9 J); φ within 1e-9 rad
    of Radau at the same tolerance (measured 2.1e-10 rad)."""
    t, sol = reference_10s
    assert sol.success
    ch = phys.channels(*phys.parallelogram_state(sol.y[0], sol.y[1], DEFAULT["N"]), DEFAULT)
    c_t, c_v = coefficients(DEFAULT)
    e0 = 0.5 * c_t * 1.0 ** 2 + c_v * 1.0          # upright, φ' = −1 rad/s
    assert abs(ch["kinetic_energy"][0] + ch["potential_energy"][0] - e0) < 1e-9
    assert np.max(np.abs(ch["energy_balance"])) < 2e-8
    assert np.max(ch["kinetic_energy"]) > 1000.0
    rad = phys.reference(DEFAULT, t, method="Radau")
    assert np.max(np.abs(rad.y[0] - sol.y[0])) < 1e-9


def test_the_library_start():
    """The library's case: N = 40, every crank vertical (B_0 at (0, L)), B_0 moving at +1 m/s
    in x — the crank turns clockwise, φ' = −1 rad/s."""
    assert (DEFAULT["N"], DEFAULT["phi0"], DEFAULT["vx0"], DEFAULT["t_end"]) == (
        40, math.pi / 2, 1.0, 10.0)
    assert phys.initial_rate(DEFAULT) == pytest.approx(-1.0, rel=1e-15)
    ch = phys.channels(*phys.parallelogram_state(np.array([DEFAULT["phi0"]]),
                                                 np.array([phys.initial_rate(DEFAULT)]), 40),
                       DEFAULT)
    assert (ch["b0_x"][0], ch["b0_y"][0]) == pytest.approx((0.0, 1.0), abs=1e-15)
    vx = -DEFAULT["L"] * math.sin(ch["phi"][0]) * ch["phi_dot"][0]
    assert vx == pytest.approx(1.0, rel=1e-14)


def test_singular_crossings_fall_where_the_quadrature_puts_them():
    """The time from the upright start to φ is ∫ dφ/|φ'| (energy conservation, `t_of`). The
    reference's passages through φ = 0 (the first singular position), −π/2 (hanging), −π (the
    second) and −2π (the first again, one revolution on) within 1e-9 s of it."""
    targets = (0.0, -math.pi / 2, -math.pi, -2 * math.pi)
    events = []
    for target in targets:
        def ev(t, y, target=target):
            return y[0] - target
        ev.terminal = False
        events.append(ev)
    sol = phys.reference(DEFAULT, np.linspace(0, 3.0, 31), events=events)
    for target, te in zip(targets, sol.t_events):
        assert len(te) == 1
        assert te[0] == pytest.approx(t_of(DEFAULT, target), abs=1e-9)
    assert 0.70 < sol.t_events[0][0] < 0.74 and 1.22 < sol.t_events[2][0] < 1.26


def test_the_table_rows_are_the_quadratures_inversion():
    """Every row of the scene's table against the quadrature alone: φ(t_k) is the root of
    t_of(φ) = t_k (no ODE integrated), within 1e-9 rad at every whole second; the first
    singular passage (φ = 0) falls between the first two rows."""
    t0 = t_of(DEFAULT, 0.0)
    assert 0.70 < t0 < 0.74 and REF_PHI[0] > 0.0 > REF_PHI[1]
    w_min = abs(DEFAULT["vx0"]) / DEFAULT["L"]          # |φ'| ≥ 1 rad/s: brackets the root
    for tk, phik in zip(REF_T[1:], REF_PHI[1:]):
        lo, hi = DEFAULT["phi0"] - 10.0 * tk, DEFAULT["phi0"] - w_min * tk + 1e-9
        phi = brentq(lambda f, tk=tk: t_of(DEFAULT, f) - tk, lo, hi, xtol=1e-14, rtol=1e-15)
        assert phik == pytest.approx(phi, abs=1e-9), tk


def test_small_amplitude_period():
    """About the hanging position φ = −π/2 the motion is c_T φ'' = −c_V (φ + π/2): period
    2π√(c_T/c_V) (N = 3, amplitude 1e-3 rad: the pendulum's correction A²/16 ~ 6e-8)."""
    p = {**DEFAULT, "N": 3, "phi0": -math.pi / 2 + 1e-3, "vx0": 0.0}
    c_t, c_v = coefficients(p)
    period = 2 * math.pi * math.sqrt(c_t / c_v)

    def turning(t, y):
        return y[1]
    sol = phys.reference(p, np.linspace(0, 3 * period, 31), events=turning)
    te = sol.t_events[0]
    te = te[te > 1e-6]
    assert np.diff(te)[:4] == pytest.approx([period / 2] * 4, rel=1e-6)


def test_the_tabulated_reference_is_a_fresh_integration(reference_10s):
    t, sol = reference_10s
    idx = [int(np.argmin(np.abs(t - tk))) for tk in REF_T]
    np.testing.assert_allclose(sol.y[0][idx], REF_PHI, rtol=0, atol=1e-10)


def test_the_energies_see_a_coupler_turning():
    """The channels read the rods as they stand: a coupler turned by ψ (the chain off the
    parallelogram) adds its own ½ (m L²/12) ψ'² and moves its centre's height by L/2 sin ψ,
    and the spread channel shows a crank off the others."""
    n = 2
    PHI, PHID, PSI, PSID = phys.parallelogram_state(np.array([0.3]), np.array([0.0]), n)
    base = phys.channels(PHI, PHID, PSI, PSID, DEFAULT)
    PSI[0, 1], PSID[0, 1] = 0.2, 2.0
    PHI[0, 2] += 0.1
    moved = phys.channels(PHI, PHID, PSI, PSID, DEFAULT)
    m, L, g = DEFAULT["m"], DEFAULT["L"], DEFAULT["g"]
    assert moved["kinetic_energy"][0] - base["kinetic_energy"][0] == pytest.approx(
        0.5 * m * (L / 2 * 2.0) ** 2 + 0.5 * m * L * L / 12 * 4.0, rel=1e-14)
    assert moved["potential_energy"][0] - base["potential_energy"][0] == pytest.approx(
        m * g * L / 2 * math.sin(0.2) + m * g * L / 2 * (math.sin(0.4) - math.sin(0.3)),
        rel=1e-12)
    assert moved["parallelogram"][0] == pytest.approx(0.1, rel=1e-12)


def test_the_reference_finding_judges_against_the_table(reference_10s):
    """The scene's finding on runs made here from the reference itself: it agrees within a
    1e-9 rad bar; φ 1e-6 rad off with a 1e-7 rad bar disagrees; no error bar is inconclusive,
    never agree; a chain off the parallelogram is reported with its size."""
    from compare.analysis.trajectory import Trajectory
    from compare.analysis.verdict import Verdict
    t, sol = reference_10s
    ch = phys.channels(*phys.parallelogram_state(sol.y[0], sol.y[1], DEFAULT["N"]), DEFAULT)

    def run(name, shift=0.0, bar=None, spread=0.0):
        c = {**ch, "phi": ch["phi"] + shift, "parallelogram": ch["parallelogram"] + spread}
        errors = {} if bar is None else {"phi": np.full(len(t), bar)}
        return Trajectory("n-four-bar", name, t, c, errors=errors)
    found = {f.name: f for f in SCENE.findings(DEFAULT, [
        run("a", 0.0, 1e-9), run("b", 1e-6, 1e-7), run("c", 0.0, None, 0.3)])}
    assert f" {Verdict.AGREE} " in found["reference_a"].text
    assert f" {Verdict.DISAGREE} " in found["reference_b"].text
    assert f" {Verdict.INCONCLUSIVE} " in found["reference_c"].text
    assert found["parallelogram_c"].value == pytest.approx(0.3)


def test_the_benchmark_reference_is_b0_of_the_table(reference_10s):
    """IFToMM A02's monitored result, B_0's displacement: the scene's benchmark reference at
    the whole seconds of the run's grid is B_0 of a fresh integration (the channels every
    solver reports) within the table's 1e-10, B_0 = (0, L) at the upright start, NaN between
    the rows; not known off the library's parameters."""
    t, sol = reference_10s
    bm = SCENE.benchmark
    assert bm.problem == "A02" and bm.columns == ("b0_x", "b0_y")
    ref = bm.reference(DEFAULT, t)
    ch = phys.channels(*phys.parallelogram_state(sol.y[0], sol.y[1], DEFAULT["N"]), DEFAULT)
    rows = [int(np.argmin(np.abs(t - tk))) for tk in REF_T]
    for c in bm.columns:
        held = np.isfinite(ref[c])
        assert np.array_equal(np.nonzero(held)[0], rows), c
        np.testing.assert_allclose(ref[c][rows], ch[c][rows], rtol=0, atol=1e-10)
    assert (ref["b0_x"][0], ref["b0_y"][0]) == pytest.approx((0.0, DEFAULT["L"]), abs=1e-12)
    assert bm.reference({**DEFAULT, "N": 41}, t) is None
    assert bm.reference({**DEFAULT, "phi0": math.pi / 4}, t) is None
    assert bm.uncertainty >= 1.8e-10 * DEFAULT["L"]     # the table's own error (quadrature)
