"""The N four-bar mechanism (scene `n-four-bar`): the reference integration against energy
conservation (the energies from every rod's own motion, not from the one-coordinate form the
reference integrates), the quadrature t(φ) = ∫ dφ/φ'(φ) of energy conservation, the
small-amplitude period 2π√(c_T/c_V) about the hanging position, Radau, and the scene's table
against a fresh integration."""
import math

import numpy as np
import pytest
from scipy.integrate import quad

from compare.physics import nfourbar as phys
from compare.scenes import get_scene
from compare.scenes.benchmarks_nfourbar import REF_PHI, REF_T

SCENE = get_scene("n-four-bar")
DEFAULT = SCENE.resolve({})


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
    1e-8 J of the 1331 J peak kinetic energy over 10 s (measured 9.2e-9 J); φ within 1e-9 rad
    of Radau at the same tolerance (measured 9.6e-11 rad)."""
    t, sol = reference_10s
    assert sol.success
    ch = phys.channels(*phys.parallelogram_state(sol.y[0], sol.y[1], DEFAULT["N"]), DEFAULT)
    c_t, c_v = coefficients(DEFAULT)
    e0 = 0.5 * c_t * (1.0 / math.sin(math.pi / 4)) ** 2 + c_v * math.sin(math.pi / 4)
    assert abs(ch["kinetic_energy"][0] + ch["potential_energy"][0] - e0) < 1e-9
    assert np.max(np.abs(ch["energy_balance"])) < 2e-8
    assert np.max(ch["kinetic_energy"]) > 1000.0
    rad = phys.reference(DEFAULT, t, method="Radau")
    assert np.max(np.abs(rad.y[0] - sol.y[0])) < 1e-9


def test_the_library_start():
    """B_0 at (L cos π/4, L sin π/4) moving at +1 m/s in x: φ' = −√2 rad/s."""
    assert phys.initial_rate(DEFAULT) == pytest.approx(-math.sqrt(2.0), rel=1e-15)
    ch = phys.channels(*phys.parallelogram_state(np.array([DEFAULT["phi0"]]),
                                                 np.array([phys.initial_rate(DEFAULT)]), 50),
                       DEFAULT)
    vx = -DEFAULT["L"] * math.sin(ch["phi"][0]) * ch["phi_dot"][0]
    assert vx == pytest.approx(1.0, rel=1e-14)


def test_singular_crossings_fall_where_the_quadrature_puts_them():
    """Energy conservation gives φ'² = φ0'² − 2 (c_V/c_T)(sin φ − sin φ0); the time from φ0 to
    φ is ∫ dφ/|φ'|. The reference's first passages through φ = 0 (the first singular position),
    −π/2 (hanging) and −π (the second) within 1e-9 s of it."""
    c_t, c_v = coefficients(DEFAULT)
    phi0, w0 = DEFAULT["phi0"], -math.sqrt(2.0)

    def t_of(phi):
        return quad(lambda f: 1.0 / math.sqrt(w0 * w0 - 2 * c_v / c_t * (math.sin(f) -
                                                                         math.sin(phi0))),
                    phi, phi0, epsabs=1e-14, epsrel=1e-13)[0]

    events = []
    for target in (0.0, -math.pi / 2, -math.pi):
        def ev(t, y, target=target):
            return y[0] - target
        ev.terminal = False
        events.append(ev)
    sol = phys.reference(DEFAULT, np.linspace(0, 1.0, 11), events=events)
    for target, te in zip((0.0, -math.pi / 2, -math.pi), sol.t_events):
        assert te[0] == pytest.approx(t_of(target), abs=1e-9)
    assert 0.25 < sol.t_events[0][0] < 0.35 and 0.8 < sol.t_events[2][0] < 0.9


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
