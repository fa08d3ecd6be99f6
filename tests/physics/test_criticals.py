"""Critical speeds by excitation order (issue 28): each solver's crossings against the closed
form, the whirl seen from both frames, the Campbell JSON and figure in either frame.

The isotropic Euler–Bernoulli cantilever shaft has no gyroscopic term: seen from the ground
every whirl mode turns at λᵢ²ω₀ (λᵢ the roots of cos λ cosh λ = −1, solved here), forward and
backward alike, at every speed. Unbalance (1× in the fixed frame) therefore meets both at
Ω* = λᵢ² (3.5160, 22.0345), gravity on an anisotropic shaft (2×) at Ω* = λᵢ²/2. In the rotating
frame the solvers report, the forward line reaches 0 there and the backward line crosses 2×
(COMSOL Rotordynamics manual, "Determination of the Critical Speed": in the corotating frame the
forward critical is the forward curve's intersection with the abscissa, the backward one the
backward curve's with ω = 2Ω) — a rule stated outside this code, checked on the solvers' own
rotating-frame frequencies.
"""
import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

from compare import solvers
from compare.analysis.campbell import in_frame
from compare.scenes import get_scene
from compare.scenes.base import UNBALANCE
from compare.workflows.modes import critical_speeds, sweep
from tests.conftest import xval

SHAFT = get_scene("spinning-shaft")
LAMBDA2 = np.array([brentq(lambda x: np.cos(x) * np.cosh(x) + 1, a, b)
                    for a, b in ((1.5, 2.5), (4.0, 5.0), (7.5, 8.2))]) ** 2
# Measured relative deviation from the closed form, all 8 crossings (grid 1.5, 2, 3, 4, 10.5,
# 11.5, 21.5, 22.5: the scene's excitations) and every mode
# mapped to the fixed frame at Ω* = 2 and 25: mstmm 4.4e-13 / 3.0e-13 (the transfer matrix is
# exact: its root finding), fem 4.7e-10 / 2.6e-9 (Hermite elements, Richardson), exudyn 7.43e-7
# / 7.94e-7, mujoco 7.46e-7 / 7.92e-7 (the rigid-segment chain, N = 40/20 extrapolated: its
# λ² as in tests/engines/test_beam_engines.py). Tolerances ≤ 10× those.
TOL = {"mstmm": 4e-12, "fem": 2e-8, "exudyn": 3e-6, "mujoco": 3e-6}
W0 = np.sqrt(582.996 / (2.87 * 1.29 ** 4))         # ω₀ = √(EI/(m L⁴)) of the defaults [rad/s]


# a shaft 1e-13 stiffer one way: gravity then excites 2× (Excitation.present), its frequencies
# move by ~5e-14 relative, far inside every solver's tolerance
ANISOTROPIC = {"EI_yy": str(582.996 * (1 + 1e-13))}


def crossings(solver, excitations, grid, overrides=None):
    """The solver's crossings of the scene's excitations that are listed, on `grid`."""
    sc = replace(SHAFT, campbell=replace(SHAFT.campbell, excitations=excitations))
    s, p = solvers.get_solver(solver), SHAFT.resolve(overrides)
    return critical_speeds(sc, s, p, grid, sweep(sc, s, p, grid))


@pytest.mark.parametrize("solver", ["mstmm", "fem", "exudyn", "mujoco"])
def test_shaft_unbalance_critical_speeds_are_the_cantilever_roots(solver):
    """Every solver's unbalance crossings, refined on the solver, on steps around them (the
    scene's grid costs 26 points per solver): λᵢ² forward and backward, labelled with order,
    excitation, whirl and frame; beside each the solver's own rotating-frame line (signed by
    its whirl sense, interpolated to the critical) is at 0 (forward) or −2× (backward)."""
    entries = crossings(solver, (UNBALANCE,), np.array([3.0, 4.0, 21.5, 22.5]))
    got = {(e["name"], e["order"], e["excitation"], e["whirl"], e["frame"]): e["value"]
           for e in entries}
    want = {(f"{w} whirl {k}", 1, "unbalance", w, "fixed"): LAMBDA2[k - 1]
            for k in (1, 2) for w in ("forward", "backward")}
    assert got.keys() == want.keys()
    for key, v in want.items():
        assert got[key] == pytest.approx(v, rel=TOL[solver]), key
    s, p = solvers.get_solver(solver), SHAFT.resolve()
    for e in entries:
        assert e["solver_frame"] == "rotating"
        assert e["speed_rad_s"] == pytest.approx(e["value"] * W0, rel=1e-12)
        assert e["speed_rpm"] == pytest.approx(e["speed_rad_s"] * 60 / (2 * np.pi), rel=1e-12)
        if e["name"].endswith("2"):
            continue
        # at the critical the forward mode has no frequency (a leaf may miss it): beside it
        x = e["value"] * np.array([1 - 1e-4, 1 + 1e-4])
        f = []
        for v in x:
            m = solvers.modes(SHAFT, s, {**p, "spin_ratio": float(v)})
            j = m.labels.index(e["name"])
            f.append(m.extra["whirl_sense"][j] * m.frequencies_hz[j])
        spin_hz = e["value"] * W0 / (2 * np.pi)
        rot = 0.0 if e["whirl"] == "forward" else -2 * spin_hz
        assert np.interp(e["value"], x, f) == pytest.approx(
            rot, abs=TOL[solver] * 2 * spin_hz), e["name"]


@pytest.mark.parametrize("solver", ["mstmm", pytest.param("fem", marks=pytest.mark.slow),
                                    pytest.param("exudyn", marks=pytest.mark.slow),
                                    pytest.param("mujoco", marks=pytest.mark.slow)])
def test_shaft_2x_crossings_are_half_the_roots(solver):
    """The scene's excitations as declared: the 2× line (gravity on a shaft stiffer one way)
    meets both whirls at λᵢ²/2, named "<mode> (2×)"; the isotropic shaft (the default) has no
    2× load and lists no 2× crossing. Slow but for mstmm: ~40 modes runs."""
    grid = np.array([1.5, 2.0, 10.5, 11.5])
    assert not [e for e in crossings(solver, SHAFT.campbell.excitations, grid)
                if e["order"] == 2]
    entries = crossings(solver, SHAFT.campbell.excitations, grid, ANISOTROPIC)
    got = {(e["name"], e["excitation"], e["whirl"]): e["value"] for e in entries
           if e["order"] == 2}
    want = {(f"{w} whirl {k} (2×)", "gravity on an anisotropic shaft", w):
            LAMBDA2[k - 1] / 2 for k in (1, 2) for w in ("forward", "backward")}
    assert got == pytest.approx(want, rel=TOL[solver])


@pytest.mark.parametrize("solver", ["mstmm", "fem", "exudyn", "mujoco"])
def test_every_whirl_seen_from_the_ground_turns_at_the_cantilever_frequency(solver):
    """The frame mapping (compare.physics.whirl) on every solver's rotating-frame modes: each
    mode, forward or backward, below or beyond its forward critical (Ω* = 2, 25), is λᵢ²ω₀ in
    the fixed frame, turning with the spin (forward) or against it (backward)."""
    s = solvers.get_solver(solver)
    for ratio in (2.0, 25.0):
        m = solvers.modes(SHAFT, s, SHAFT.resolve({"spin_ratio": str(ratio)}))
        fixed = in_frame(m, ratio * W0 / (2 * np.pi), "rotating", "fixed")
        want = [LAMBDA2[int(lb.split()[-1]) - 1] * W0 / (2 * np.pi) for lb in m.labels]
        np.testing.assert_allclose(fixed.frequencies_hz, want, rtol=TOL[solver])
        sense = dict(zip(m.labels, fixed.extra["whirl_sense"]))
        assert all(v == (1 if lb.startswith("forward") else -1) for lb, v in sense.items())


# `xval calibrate spinning-shaft --seed 7373` set 1: EI_yy = 1.43 EI_xx. The forward whirl 1
# is divergent (a real pair in the rotating frame) between the two planes' bending
# frequencies, λ₁² < Ω* < √(EI_yy/EI_xx)·λ₁² (the two-oscillator quartic of
# tests/engines/test_beam_engines.py): the unbalance line meets it over the whole band and the
# critical speed each solver reports is the band's upper edge, where the mode reappears.
BAND = {"L": "0.8592806692053272", "EI_xx": "379.6951962999924",
        "EI_yy": "541.5535297908771", "m": "2.1195366244353977"}
BAND_EDGE = np.sqrt(541.5535297908771 / 379.6951962999924) * LAMBDA2[0]     # 4.19907756


def band_edge(solver, overrides=BAND):
    (e,) = [e for e in crossings(solver, (UNBALANCE,), np.array([4.0, 5.0]), overrides)
            if e["name"] == "forward whirl 1"]
    return e


@pytest.mark.parametrize("solver", ["mstmm", "fem", "exudyn", "mujoco"])
def test_a_band_edge_critical_speed_holds_the_closed_form_within_its_bar(solver):
    """The edge located as such (compare/analysis/band_edge.py), not as the jump of a line
    whose label passes to the next mode there: measured 2.2e-9 (mstmm), 5.6e-9 (fem) and
    9.1e-5 (the engines) off √(EI_yy/EI_xx)·λ₁², against bars of 1.6e-8, 1.8e-4 and 6.7e-3.
    As the jump the engines put it at their N = 40 chain's own edge, 6.0e-4 past, with a bar
    of 1.8e-6 from the extrapolated frequency (3 of 6 pairs disagreed)."""
    e = band_edge(solver)
    assert abs(e["value"] - BAND_EDGE) <= e["error"], (e["value"], e["error"])
    # sharp enough to see a plane 1 % stiffer: the edge moves by 0.5 %, 2.1e-2
    assert e["error"] < 0.5 * 5e-3 * BAND_EDGE


def test_a_band_edge_of_a_plane_one_percent_stiffer_disagrees():
    """The seeded bug the edge's bar must show: mujoco's EI_yy 1 % high moves its edge by
    0.5 % (2.1e-2 in Ω*), past both bars; the two solvers of the right model agree."""
    from compare.workflows.modes import critical_speed_comparisons
    stiff = {**BAND, "EI_yy": str(541.5535297908771 * 1.01)}
    entries = {"mstmm": [band_edge("mstmm")], "exudyn": [band_edge("exudyn")],
               "mujoco": [band_edge("mujoco", stiff)]}
    verdicts = {(c.a, c.b): c.verdict
                for c in critical_speed_comparisons(SHAFT, SHAFT.resolve(BAND), entries)}
    assert verdicts == {("mstmm", "exudyn"): "agree", ("mstmm", "mujoco"): "disagree",
                        ("exudyn", "mujoco"): "disagree"}


@pytest.mark.parametrize("solver", ["exudyn", "mujoco"])
def test_engines_extrapolate_a_mode_beside_its_band_edge(solver):
    """Between the N chain's band edge and the N/2 chain's (Ω* = 4.1998, 4.201) only the N
    chain lists the forward whirl 1, and the N/2 chain's next forward whirl took its label:
    paired by label the extrapolate was 18.8 Hz with a bar of 19 (the true frequency 0.064).
    Paired by the labels that count the divergent mode too, and extrapolated in f² through
    the N/2 chain's −(σ/2π)²: within 1e-4 Hz of the quartic's root (measured 6.6e-5, 4.0e-5),
    and within the leaf's bar."""
    s = solvers.get_solver(solver)
    ratio = 541.5535297908771 / 379.6951962999924
    for spin in (4.1998, 4.201):
        p = SHAFT.resolve({**BAND, "spin_ratio": str(spin)})
        m = solvers.modes(SHAFT, s, p)
        j = m.labels.index("forward whirl 1")
        w0 = m.extra["omega0_rad_s"]
        lam4 = LAMBDA2[0] ** 2
        b = lam4 * (1 + ratio) + 2 * spin**2
        c = (lam4 - spin**2) * (ratio * lam4 - spin**2)
        want = np.sqrt((b - np.sqrt(b * b - 4 * c)) / 2) * w0 / (2 * np.pi)
        assert m.frequencies_hz[j] == pytest.approx(want, abs=1e-4), spin
        assert abs(m.frequencies_hz[j] - want) <= m.extra["frequency_error_hz"][j]


@pytest.mark.parametrize("solver", ["exudyn", "mujoco"])
def test_engines_extrapolate_the_forward_whirl_through_its_rotating_frame_zero(solver):
    """Just past a forward critical the chains of N and N/2 segments sit on opposite sides of
    the rotating-frame zero; extrapolated with its sign the forward whirl is λ² − Ω* (here
    −1e-3 and −1.5e-2). Measured deviation 2.5e-7 and 1.64e-5 (in ω*; the chain's λ² error);
    extrapolating magnitudes gave +2.96e-4 and −3.4e-3 (as a frequency!)."""
    s = solvers.get_solver(solver)
    for k, past in ((1, 1e-3), (2, 1.5e-2)):
        ratio = LAMBDA2[k - 1] + past
        m = solvers.modes(SHAFT, s, SHAFT.resolve({"spin_ratio": str(float(ratio))}))
        j = m.labels.index(f"forward whirl {k}")
        signed = m.extra["whirl_sense"][j] * m.frequencies_hz[j] * 2 * np.pi / W0
        assert signed == pytest.approx(-past, abs=5e-5), (k, signed)


def test_campbell_json_in_both_frames_and_the_figure_in_the_frame_asked(tmp_path):
    """rotor-whirl (the closed-form leaf; lines in the fixed frame): the JSON keeps
    `critical_speeds` as {solver: {name: value}}, the Campbell's entries carry order, whirl and
    frame, and the lines are given in both frames: in the rotor's frame the forward whirl is
    f − Ω/2π in magnitude, the backward f + Ω/2π (J_t λ² ∓ J_p Ω λ − k_eff = 0 written here)."""
    rc, out, err = xval("modes", "rotor-whirl", "--solver", "closed-form", "--set",
                        "n_spin=16", "--campbell-frame", "rotating", "--out", str(tmp_path),
                        "--json")
    assert rc == 0, err
    obj = json.loads(out)
    cb = obj["campbell"]
    m, R, L, k = 5.0, 0.25, 0.5, 2000.0 - 5.0 * 9.81 * 0.5
    jt, jp = m * R**2 / 4 + m * L**2, m * R**2 / 2
    crit = {"forward whirl": np.sqrt(k / (jt - jp)), "backward whirl": np.sqrt(k / (jt + jp))}
    assert obj["critical_speeds"]["closed-form"] == pytest.approx(crit, rel=1e-9)
    assert [(e["name"], e["order"], e["excitation"], e["whirl"], e["frame"])
            for e in cb["critical_speeds"]["closed-form"]] == [
        ("backward whirl", 1, "unbalance", "backward", "fixed"),
        ("forward whirl", 1, "unbalance", "forward", "fixed")]
    assert cb["frame"] == "fixed" and cb["figure_frame"] == "rotating"
    spin = np.array(cb["values"])
    lines = cb["lines_hz_by_frame"]
    assert lines["fixed"] == cb["lines_hz"]
    root = np.sqrt((jp * spin) ** 2 + 4 * jt * k)
    fwd, bwd = (root + jp * spin) / (2 * jt), (root - jp * spin) / (2 * jt)
    np.testing.assert_allclose(lines["rotating"]["closed-form"]["forward whirl"],
                               np.abs(fwd - spin) / (2 * np.pi), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(lines["rotating"]["closed-form"]["backward whirl"],
                               (bwd + spin) / (2 * np.pi), rtol=1e-12)
    assert (Path(obj["report"]).parent / "campbell.png").exists()


def test_a_frame_the_scene_cannot_draw_is_bad_input(tmp_path):
    """Blade modes do not whirl: a fixed-frame fan plot is refused in one line, exit 2, before
    anything runs."""
    rc, _, err = xval("modes", "rotating-beam", "--campbell-frame", "fixed", "--out",
                      str(tmp_path / "o"))
    assert rc == 2
    line = err.strip()
    assert "\n" not in line and "--campbell-frame fixed" in line and "rotating" in line
    assert not (tmp_path / "o").exists()
