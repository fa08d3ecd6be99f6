"""Bricard's mechanism (scene `bricard`): the reference integration against conservation of
energy, the mechanism's symmetries and a second integrator, the scene's tabulated reference
against a fresh integration, and the custom `lagrange-partial` solver against the reference
within its own error bar; a 1 % mass error in the solver is a disagreement."""
import numpy as np
import pytest

from compare import solvers
from compare.physics import bricard as phys
from compare.scenes import get_scene
from compare.scenes.benchmarks_bricard import REF_P3, REF_T

SCENE = get_scene("bricard")
DEFAULT = SCENE.resolve({})
P = phys.pack(DEFAULT)
SHORT = SCENE.resolve({"t_end": "2"})      # past the first turning point (≈ 2.45 s is half)


def test_the_loop_has_one_degree_of_freedom_where_gruebler_counts_zero():
    """Six revolute joints, six loop equations: rank five at the start (one zero singular value
    of the joint twists), and the mechanism's own motion in it: joints 0, 2, 4 turn alike and
    so do joints 1, 3, 5 (the trihedral Bricard linkage's symmetry)."""
    X, _, _ = phys.forward(np.zeros(6), P)
    sv = np.linalg.svd(X.T, compute_uv=False)
    assert sv[-1] < 1e-14 * sv[0] and sv[-2] > 0.1 * sv[0]
    q, ok = phys.close(1.0, np.zeros(5), P, 1e-15, 50)
    assert ok and np.max(np.abs(phys.closure(q, P))) < 1e-14
    np.testing.assert_allclose(q[[2, 4]], q[0], atol=1e-12)
    np.testing.assert_allclose(q[[3, 5]], q[1], atol=1e-12)


@pytest.fixture(scope="module")
def reference_short():
    t = SCENE.output_grid(SHORT)
    return t, phys.reference(SHORT, t)


def test_reference_conserves_energy_and_agrees_with_radau(reference_short):
    """DOP853 at 1e-12: the energy balance within 1e-10 J of a 4.55 J peak kinetic energy
    (measured 2e-11 J to 2 s, 5.1e-11 J to 10 s), the angles within 1e-10 rad of Radau at the
    same tolerance (measured 9e-12 over 10 s)."""
    t, (Q, QD, sol) = reference_short
    assert sol.success
    ch = phys.channels(Q, QD, P)
    assert np.max(np.abs(ch["energy_balance"])) < 1e-10
    assert np.max(ch["kinetic_energy"]) > 1.0            # the loop does move
    Qr, _, _ = phys.reference(SHORT, t, method="Radau")
    assert np.max(np.abs(Qr - Q)) < 1e-10


def test_the_tabulated_reference_is_a_fresh_integration(reference_short):
    """The scene's table of P3 against the integration here (to 2 s; the next test: to 10 s)."""
    t, (Q, QD, _) = reference_short
    ch = phys.channels(Q, QD, P)
    for k, tk in enumerate(REF_T[REF_T <= 2.0]):
        i = int(np.argmin(np.abs(t - tk)))
        got = [ch[c][i] for c in ("p3_x", "p3_y", "p3_z")]
        np.testing.assert_allclose(got, REF_P3[k], rtol=0, atol=1e-10)


def test_the_whole_table_and_the_period():
    """To 10 s: the table, and the mechanism's exact symmetry: released at rest at θ1 = 0, it
    swings to rest at θ1 = π — joints 0, 2, 4 at π, joints 1, 3, 5 back at 0: the start's mirror
    image in the plane x = 0 (P3 at (−L, −L, L)), every rod at its starting height — and back,
    a libration whose turning
    points (θ1' = 0) are 0 and π exactly and fall at whole multiples of the half period
    (measured: to 9.4e-13 rad and 1e-12 s; half period 2.493154304 s)."""
    t = SCENE.output_grid(DEFAULT)

    def turning(t_, y):
        return y[1]
    Q, QD, sol = phys.reference(DEFAULT, t, events=turning)
    ch = phys.channels(Q, QD, P)
    idx = [int(np.argmin(np.abs(t - tk))) for tk in REF_T]
    got = np.array([[ch[c][i] for c in ("p3_x", "p3_y", "p3_z")] for i in idx])
    np.testing.assert_allclose(got, REF_P3, rtol=0, atol=1e-10)
    assert np.max(np.abs(ch["energy_balance"])) < 1e-10
    te, ye = sol.t_events[0][1:], sol.y_events[0][1:]       # the release itself is the first
    assert len(te) == 4
    np.testing.assert_allclose(ye[:, 0], [np.pi, 0.0, np.pi, 0.0], rtol=0, atol=1e-9)
    np.testing.assert_allclose(te, te[0] * np.arange(1, 5), rtol=0, atol=1e-9)
    # the loop at θ1 = π, closed from the reference's state at the output time nearest to it
    q, ok = phys.close(np.pi, Q[int(np.argmin(np.abs(t - te[0]))), 1:], P, 1e-15, 50)
    assert ok
    np.testing.assert_allclose(np.cos(q), [-1, 1, -1, 1, -1, 1], rtol=0, atol=1e-12)
    np.testing.assert_allclose(phys.point3(q, P), [-1.0, -1.0, 1.0], rtol=0, atol=1e-12)


def _run(params, solver="lagrange-partial"):
    s = solvers.get_solver(solver)
    return solvers.simulate(SCENE, s, params, solvers.settings_for(s, SCENE.name),
                            estimate_error=True)


@pytest.fixture(scope="module")
def custom_short():
    return _run(SHORT)


def _reference_verdict(tr, ref_ch, channels):
    """Every sample of `channels` within the run's error bar (+ the scene's allowance) of the
    reference's."""
    bad = {}
    for c in channels:
        dev = np.abs(tr.channels[c] - ref_ch[c])
        bar = np.abs(tr.errors[c]) + SCENE.tolerances[c] * max(np.max(np.abs(ref_ch[c])), 1.0)
        if not np.all(dev <= bar):
            bad[c] = float(np.max(dev - bar))
    return bad


def test_custom_solver_meets_the_reference_within_its_error_bar(custom_short, reference_short):
    tr = custom_short
    assert tr.status == "ok", tr.reason
    _, (Q, QD, _) = reference_short
    ref_ch = phys.channels(Q, QD, P)
    assert not _reference_verdict(tr, ref_ch, [str(c) for c in phys.CHANNELS])
    # informative: the bar is far below the motion's own scale (P3 moves by ~2 m)
    assert max(np.max(np.abs(tr.errors[c])) for c in ("p3_x", "p3_y", "p3_z")) < 1e-4
    # the scene's own finding says the same against its table
    f = next(f for f in SCENE.findings(SHORT, [tr]) if f.name.endswith("partial"))
    assert " agree " in f.text, f.text


def test_a_one_percent_mass_error_is_a_disagreement(reference_short):
    """The same five rods 1 % heavier move the same way (gravity and inertia scale alike), so
    the error shows in the energies: the kinetic energy 1 % off, far outside the bar."""
    tr = _run({**SHORT, "m": SHORT["m"] * 1.01})
    assert tr.status == "ok", tr.reason
    _, (Q, QD, _) = reference_short
    bad = _reference_verdict(tr, phys.channels(Q, QD, P), ["kinetic_energy"])
    assert "kinetic_energy" in bad
