"""Bricard's mechanism (scene `bricard`): the rods' inertia against a square prism's closed form,
the reference integration against conservation of energy, the mechanism's symmetries and a
second integrator, the scene's tabulated reference against a fresh integration, thin rods
(a = 0) against an independent thin-rod table, and the custom `lagrange-partial` solver against
the reference within its own error bar; a 1 % mass error in the solver is a disagreement."""
import numpy as np
import pytest

from compare import solvers
from compare.physics import bricard as phys
from compare.scenes import get_scene
from compare.scenes.benchmarks_bricard import REF_P3, REF_T

SCENE = get_scene("bricard")
DEFAULT = SCENE.resolve({})
P = phys.pack(DEFAULT)
SHORT = SCENE.resolve({"t_end": "2"})      # past the first turning point (≈ 2.5 s is half)
# P3 at t = 0, 1, …, 10 s for thin rods (a = 0), integrated (DOP853 at 1e-12, Radau agreeing
# to 9e-12 m) while the rods' inertia had no term in a: an independent number for a = 0
THIN_P3 = np.array([
    [1.0, 0.50866476023, -0.969892003789, -0.966341177901, 0.532399282557, 0.999999983091,
     0.484302768902, -0.973152766593, -0.962483804495, 0.555490531461, 0.999999729402],
    [-1.0, -1.649827063211, -1.219455140948, -1.230661550978, -1.641032210097,
     -1.000183881295, -1.658252373736, -1.208437127983, -1.242046001418, -1.631884102292,
     -1.00073538991],
    [1.0, 0.139035330748, 0.756464579607, 0.742736073473, 0.153506642712, 0.999816101798,
     0.125099532499, 0.769839853856, 0.728660865181, 0.168477138343, 0.999264339691]]).T


def test_each_rods_inertia_is_a_square_prisms():
    """m = 2 kg, L = 1.5 m, a = 0.2 m, by hand: about the rod's axis m (a² + a²)/12 =
    2·0.08/12 = 0.0133333…, across it m (L² + a²)/12 = 2·2.29/12 = 0.3816666… (twice); the axial
    one's direction is the rod's (P_k − P_{k−1} turned by the rod's pose), at a bent
    configuration; a = 0: the thin rod (nothing axial, m L²/12 = 0.375 across)."""
    p = phys.pack({"m": 2.0, "L": 1.5, "g": 9.81, "a": 0.2})
    q, ok = phys.close(0.7, np.zeros(5), p, 1e-15, 50)
    assert ok
    _, Rs, _ = phys.forward(q, p)
    for k, I in enumerate(phys.inertia(q, p)):
        d = Rs[k + 1] @ (phys.POINTS[k + 1] - phys.POINTS[k])
        np.testing.assert_allclose(I, I.T, rtol=0, atol=1e-15)
        np.testing.assert_allclose(np.linalg.eigvalsh(I), [0.0133333333333333, 0.381666666666667,
                                                           0.381666666666667], rtol=1e-13)
        np.testing.assert_allclose(I @ d, 0.0133333333333333 * d, rtol=0, atol=1e-14)
    thin = phys.inertia(q, phys.pack({"m": 2.0, "L": 1.5, "g": 9.81, "a": 0.0}))
    np.testing.assert_allclose(np.linalg.eigvalsh(thin[2]), [0.0, 0.375, 0.375], rtol=0,
                               atol=1e-14)


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
    (measured 2.8e-11 J to 2 s, 6.8e-11 J to 10 s), the angles within 1e-10 rad of Radau at the
    same tolerance (measured 1.1e-11 over 10 s)."""
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
    (measured: to 7.7e-13 rad and 7.5e-13 s; half period 2.495855757 s)."""
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


def test_thin_rods_reproduce_the_thin_rod_table():
    """a = 0: the thin rods' P3 at t = 0, 1, …, 10 s (measured: to 5e-13 m); the library's
    a = 0.1 m moves it by up to 0.016 m, 1.6e8× the tolerance here."""
    thin = {**DEFAULT, "a": 0.0}
    t = SCENE.output_grid(thin)
    Q, QD, sol = phys.reference(thin, t)
    assert sol.success
    ch = phys.channels(Q, QD, phys.pack(thin))
    idx = [int(np.argmin(np.abs(t - tk))) for tk in REF_T]
    got = np.array([[ch[c][i] for c in ("p3_x", "p3_y", "p3_z")] for i in idx])
    np.testing.assert_allclose(got, THIN_P3, rtol=0, atol=1e-10)
    assert np.max(np.abs(THIN_P3 - REF_P3)) > 1e-2


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
