"""Mode shapes in 3D (`mode_shape_3d` hooks of the MSTMM scenes, compare/mode_shapes.py).

Expected numbers are independent of the code under test: the cantilever's closed-form flap and
torsion shapes written here, and rigid-body motion (u + θ × r) of the whole helicopter."""
import json
from pathlib import Path

import numpy as np
import pytest
from rerun.chunk import RrdReader

from compare.output.mode_shapes import FRAMES, TIMELINE, mode_entity, panels
from compare.output.recording import load_rows
from compare.scenes.mstmm import HELICOPTER_HOVER, ROTATING_BEAM, SPINNING_SHAFT
from compare.workflows.modes import run_modes
from custom_models.fem import blade as fem_blade
from custom_models.mstmm import blade as mstmm_blade
from reference_models.mujoco import beam_modes as mujoco_blade
from reference_models.mujoco import shaft_modes as mujoco_shaft

BETA_L = 1.8751040687119611          # first root of cos λ cosh λ = −1


def cantilever_flap_1(x, L):
    """First bending mode of a clamped-free beam: cosh − cos − σ(sinh − sin)."""
    b = BETA_L * x / L
    sigma = (np.cosh(BETA_L) + np.cos(BETA_L)) / (np.sinh(BETA_L) + np.sin(BETA_L))
    return np.cosh(b) - np.cos(b) - sigma * (np.sinh(b) - np.sin(b))


def at_rest():
    return ROTATING_BEAM.resolve({"speed": "0", "n_modes": "5"})


@pytest.mark.parametrize("solver, leaf, tol", [
    # measured (of the tip deflection): mstmm 5e-15 (transfer matrices, exact), fem 2e-11
    # (Hermite mesh, Richardson), mujoco 5.3e-5 (the rigid-segment chain's discretisation)
    ("mstmm", mstmm_blade, 1e-12), ("fem", fem_blade, 1e-9), ("mujoco", mujoco_blade, 2e-4)],
    ids=["mstmm", "fem", "mujoco"])
def test_flap_1_drawn_on_the_axis_is_the_closed_form(solver, leaf, tol):
    p = at_rest()
    res = leaf.modes(p, {})
    i = res.labels.index("flap 1")
    pts, d = ROTATING_BEAM.mode_shape_3d(p, solver, res.shapes[i])[0]     # the blade axis
    x = pts[:, 0] - p["hub_radius"]
    assert np.allclose(pts[:, 1:], 0.0) and np.isclose(x[-1], p["L"])
    w = np.real(d[:, 2] / d[-1, 2])                 # flap: out of the rotor plane
    assert np.max(np.abs(w - cantilever_flap_1(x, p["L"]) / cantilever_flap_1(p["L"], p["L"]))
                  ) < tol
    assert np.max(np.abs(d[:, :2])) < 1e-9 * np.max(np.abs(d))     # no lag, no extension


def test_torsion_1_turns_the_chord_lines():
    """Torsion 1 at rest: twist ∝ sin(πx/2L); the chord's edges move ±twist·chord/2 out of the
    rotor plane, the axis stays."""
    p = at_rest()
    res = mstmm_blade.modes(p, {})
    strips = ROTATING_BEAM.mode_shape_3d(p, "mstmm", res.shapes[res.labels.index("torsion 1")])
    (_, d_axis), chords = strips[0], strips[1:]
    assert np.max(np.abs(d_axis)) < 1e-9
    x = np.array([c[0][0, 0] for c in chords])
    assert all(np.isclose(np.ptp(c[0][:, 1]), p["chord"]) for c in chords)
    edge = np.array([c[1][1, 2] for c in chords])          # +chord/2 edge, out of plane
    assert np.allclose([c[1][0, 2] for c in chords], -edge)
    assert np.allclose(edge / edge[-1], np.sin(np.pi * x / (2 * p["L"])), atol=1e-9)


def test_engine_whirl_is_drawn_with_the_sense_of_mstmm():
    """The spinning shaft's forward whirl 1 at Ω* = 2: the rigid-segment chain's complex row
    and mstmm's real (U, V) row draw the same orbit, turning the same way, once aligned."""
    from custom_models.mstmm import shaft as mstmm_shaft

    class Run:                      # what panels() reads of a solver's result
        def __init__(self, solver, res):
            self.solver, self.status = solver, "ok"
            self.frequencies_hz, self.labels, self.shapes = (res.frequencies_hz, res.labels,
                                                             res.shapes)

    p = SPINNING_SHAFT.resolve({"spin_ratio": "2", "n_modes": "2"})
    runs = [Run("mstmm", mstmm_shaft.modes(p, {})), Run("mujoco", mujoco_shaft.modes(p, {}))]
    pn = panels(SPINNING_SHAFT, p, runs)[0]
    assert pn.label == "forward whirl 1"
    tips = {s: ds[0][-1][:2] for s, (_, ds) in pn.solvers.items()}      # (u, v) at the tip
    for s, (u, v) in tips.items():
        # circular whirl (isotropic shaft) at the tip, counter-clockwise in the rotating frame
        # for the lower branch (Im(u·conj v) > 0, beam_chain_common.whirl_sense)
        assert abs(abs(u) - abs(v)) < 1e-3 * abs(u), s
        assert np.imag(u * np.conj(v)) > 0, s
    # measured 5e-5 of the tip displacement (the chain's segments)
    assert np.allclose(tips["mujoco"], tips["mstmm"], atol=2e-4 * abs(tips["mstmm"][0]))


def test_helicopter_rigid_rotation_moves_every_strip_rigidly():
    """A small rigid rotation θ (about a horizontal axis) of the whole aircraft written in the
    shape-row layout (blade frames, hub about its centre, fuselage about its centre of mass):
    every point the hook draws moves by θ × r."""
    from compare.physics.mstmm import helicopter_layout
    p = HELICOPTER_HOVER.resolve({})
    lay = helicopter_layout(p)
    theta = np.array([0.3, -0.7, 0.0])
    xs = np.linspace(0.0, p["blade_L"], 7)
    rows = []
    for k in range(4):
        a = k * np.pi / 2
        er, el, ez = (np.array([np.cos(a), np.sin(a), 0]), np.array([-np.sin(a), np.cos(a), 0]),
                      np.array([0, 0, 1.0]))
        for x in xs:
            u = np.cross(theta, lay["roots"][k] + x * er)
            rows.append([u @ er, u @ el, u @ ez, (theta @ er) * p["blade_chord"] / 2])
    cm = lay["fuselage"]["cm"]
    row = np.concatenate([np.ravel(rows), np.zeros(3), theta, np.cross(theta, cm), theta])
    for pts, d in HELICOPTER_HOVER.mode_shape_3d(p, "mstmm", row):
        assert np.allclose(d, np.cross(theta, pts), atol=1e-12)


def test_run_modes_writes_figure_and_recording(tmp_path):
    res = run_modes("rotating-beam", ["mstmm", "fem"], {"speed": "40"}, log=lambda m: None,
                    campbell_sweep=False)
    res.save(tmp_path)
    obj, results = res.to_json(), list(res.runs.values())
    png, rrd = obj["mode_shapes_figure"], obj["mode_shapes_recording"]
    assert open(png, "rb").read(8) == b"\x89PNG\r\n\x1a\n"
    assert "![mode shapes](mode_shapes.png)" in open(obj["report"]).read()
    result = Path(obj["report"]).with_name("result.json")
    assert json.loads(result.read_text())["mode_shapes_recording"] == rrd
    pn = panels(ROTATING_BEAM, ROTATING_BEAM.resolve({"speed": "40"}), results)
    assert len(pn) == 5
    for k, panel in enumerate(pn):
        for solver in ("mstmm", "fem"):
            t, strips = load_rows(rrd, f"{mode_entity(k, panel)}/{solver}",
                                  "LineStrips3D:strips", timeline=TIMELINE)
            assert len(t) == FRAMES and np.allclose(t, np.arange(FRAMES) / FRAMES)
            # a quarter period in: the undeformed axis plus the drawn peak displacement
            pts, ds = panel.solvers[solver]
            q = np.array(strips[FRAMES // 4][0])
            assert np.allclose(q, pts[0] + ds[0].real, atol=1e-5)
        static = RrdReader(rrd).stream().filter(content=f"{mode_entity(k, panel)}/undeformed",
                                                is_static=True, components="LineStrips3D:strips")
        assert len(list(static)) == 1                        # the faint reference, static
