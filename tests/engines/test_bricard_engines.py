"""Exudyn and MuJoCo leaves of `bricard` against the reference integration (DOP853 at 1e-12 in
the one minimal coordinate, compare.physics.bricard), each within a bound from its own
convergence (second order: |y(h) − y*| ≈ 4/3 |y(h) − y(h/2)|); Exudyn's redundant constraint
measured as what it is (its degree-of-freedom count, and the solver stopping on it), and MuJoCo's
soft loop closure as a deviation from the rigid mechanism that grows as the constraint's time
constant squared; both engines' rods are the library's square prisms (closed form)."""
import mujoco
import numpy as np
import pytest

import reference_models.exudyn.bricard as ex  # hard dependencies: a broken import fails
import reference_models.mujoco.bricard as mj
from compare.physics import bricard as phys
from compare.scenes import get_scene

SCENE = get_scene("bricard")
SHORT = SCENE.resolve({"t_end": "2"})
T_OUT = SCENE.output_grid(SHORT)
CH = ("p3_x", "p3_y", "p3_z", "theta1")


@pytest.fixture(scope="module")
def reference():
    Q, QD, _ = phys.reference(SHORT, T_OUT)
    return phys.channels(Q, QD, phys.pack(SHORT))


def run(engine, settings):
    r = engine.simulate(dict(SHORT), T_OUT, settings)
    assert r.status == "ok", r.reason
    return r


def deviation(r, ref, channels=CH):
    return np.array([np.max(np.abs(r.channels[c] - ref[c])) for c in channels])


def converges_to_the_reference(engine, settings, h, ref):
    r1, r2 = run(engine, {**settings, "dt": h}), run(engine, {**settings, "dt": h / 2})
    bound = np.array([np.max(2.0 * np.abs(r1.channels[c] - r2.channels[c])) for c in CH]) + 1e-9
    dev = deviation(r1, ref)
    assert np.all(dev <= bound), (dev, bound)
    assert np.max(bound) < 1e-4                       # an informative bound, not a wide one
    return r1, dev


# the rods' principal moments at the library's m = 1 kg, L = 1 m, a = 0.1 m, by hand: about the
# axis m (a² + a²)/12 = 0.02/12, across it m (L² + a²)/12 = 1.01/12; (axial, across) per rod in
# the space frame at the start, rod k along P_k − P_{k−1}: x, y, z, x, y
AXIAL_I, ACROSS_I = 0.02 / 12.0, 1.01 / 12.0
ROD_AXIS = (0, 1, 2, 0, 1)


def _prisms():
    out = np.full((5, 3), ACROSS_I)
    out[np.arange(5), ROD_AXIS] = AXIAL_I
    return out


def test_both_engines_rods_are_the_librarys_square_prisms():
    """The bodies as each engine holds them after building: mass m, and the principal moments
    of a 0.1 m square prism about the centre along the rods' axes (MuJoCo: its compiled body
    inertia, no rotation of the principal frame; Exudyn: the rigid bodies' inertia at their
    centre, no products)."""
    m = mujoco.MjModel.from_xml_string(mj.xml(SHORT, mj.check_settings({})))
    np.testing.assert_allclose(m.body_mass[1:], 1.0, rtol=1e-15)
    np.testing.assert_allclose(m.body_inertia[1:], _prisms(), rtol=1e-12)
    np.testing.assert_allclose(np.abs(m.body_iquat[1:, 0]), 1.0, rtol=0, atol=1e-15)
    _, mbs, _, _ = ex.build(SHORT, ex.check_settings({}))
    bodies = [mbs.GetObject(i) for i in range(mbs.systemData.NumberOfObjects())]
    bodies = [b for b in bodies if b["objectType"] == "RigidBody"]
    assert len(bodies) == 5
    for k, b in enumerate(bodies):
        assert b["mass"] == 1.0 and np.all(np.asarray(b["centerOfMass"]) == 0.0)
        np.testing.assert_allclose(b["inertia"], [*_prisms()[k], 0, 0, 0], rtol=1e-12, atol=0)


def test_exudyn_counts_one_degree_of_freedom_and_no_redundancy():
    """With the loop's last joint a full revolute joint Exudyn counts the redundant constraint
    (and its default solver stops at the first step); with the closing joint's redundant
    rotation left out, one degree of freedom and none redundant."""
    s = ex.check_settings({})
    _, mbs, _, _ = ex.build(SHORT, s, [1, 1, 1, 0, 1, 1])
    dof = mbs.ComputeSystemDegreeOfFreedom()
    assert (dof["degreeOfFreedom"], dof["redundantConstraints"]) == (1, 1)
    _, mbs, _, _ = ex.build(SHORT, s)
    dof = mbs.ComputeSystemDegreeOfFreedom()
    assert (dof["degreeOfFreedom"], dof["redundantConstraints"]) == (1, 0)


def test_exudyn_stops_on_the_redundant_revolute_joint(monkeypatch):
    monkeypatch.setattr(ex, "CLOSING_AXES", [1, 1, 1, 0, 1, 1])
    r = ex.simulate(dict(SHORT), T_OUT[:3], {})
    assert r.status == "diverged" and "exudyn solver failed" in r.reason


def test_exudyn_converges_to_the_reference(reference):
    """generalized-α at 1e-3 s: 1.9e-6 rad off over 2 s (measured; 4.8e-7 at 5e-4, 1.2e-7 at
    2.5e-4: second order); its halving bounds it; the energy balance 7.1e-6 J (of 4.5 J)."""
    r, dev = converges_to_the_reference(ex, {}, 1e-3, reference)
    assert np.max(np.abs(r.channels["energy_balance"])) < 2e-5


def test_mujoco_converges_to_the_reference(reference):
    """RK4 at 1e-4 s with the loop's time constant 4·dt: 5.0e-10 m off (measured); the loop
    open by 2.0e-10 m at most."""
    r, dev = converges_to_the_reference(mj, {}, 1e-4, reference)
    assert np.max(dev) < 1e-8
    assert r.extra["loop_violation"][0] < 1e-8


def test_mujoco_soft_loop_deviates_as_the_time_constant_squared(reference):
    """The engine's model difference: at a fixed step a 4× longer time constant moves P3 16×
    (measured 16× from tc 1.6e-3 to 6.4e-3 s: 8.0e-9 → 1.3e-7 m), far above the RK4 error
    at that step (5.0e-10 m at tc 4e-4 s)."""
    dev = [np.max(deviation(run(mj, {"dt": 1e-4, "solref_factor": f}), reference))
           for f in (16.0, 64.0)]
    assert 8.0 < dev[1] / dev[0] < 32.0, dev
    assert dev[1] > 1e-8


def test_mujoco_axial_inertia_is_below_its_other_errors(reference, monkeypatch):
    """Thin rods (a = 0): the axial inertia MuJoCo needs (AXIAL·m L²) moves P3 in proportion to
    it: 100× more moves it by 1.0e-8 m (measured), so the default's own share, ~1e-10 m, is
    below the run's deviation from the reference at the library's a (5.0e-10 m)."""
    thin = {**SHORT, "a": 0.0}

    def run_thin():
        r = mj.simulate(thin, T_OUT, {})
        assert r.status == "ok", r.reason
        return r
    base = run_thin()
    monkeypatch.setattr(mj, "AXIAL", mj.AXIAL * 100)
    more = run_thin()
    share = max(np.max(np.abs(more.channels[c] - base.channels[c])) for c in CH) / 99.0
    assert share < np.max(deviation(run(mj, {}), reference))
    assert share < 3e-10
