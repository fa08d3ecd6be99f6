"""The benchmark bicycle against the numbers Meijaard, Papadopoulos, Ruina and Schwab (2007)
publish: the matrices M, C1, K0, K2 at the benchmark design (printed to 14 digits in the paper),
the roots at v = 0 and 5 m/s and the weave and capsize speeds (Table 2), and — at every speed
0–10 m/s — the roots against the characteristic polynomial det(M λ² + v C1 λ + g K0 + v² K2)
solved apart (numpy.roots on its coefficients, formed here from 2×2 determinants)."""
import json

import numpy as np
import pytest

from compare import solvers
from compare.physics import bicycle
from compare.scenes import get_scene

SCENE = get_scene("bicycle")
P = SCENE.resolve()

# the paper's published values (section 4 and Table 2)
M_PAPER = [[80.81722, 2.31941332208709], [2.31941332208709, 0.29784188199686]]
C1_PAPER = [[0.0, 33.86641391492494], [-0.85035641456978, 1.68540397397560]]
K0_PAPER = [[-80.95, -2.59951685249872], [-2.59951685249872, -0.80329488458618]]
K2_PAPER = [[0.0, 76.59734589573222], [0.0, 2.65431523794604]]
ROOTS_V0 = [5.53094371765393, 3.13164324790656, -3.13164324790656, -5.53094371765393]
WEAVE_V5 = complex(-0.77534188219585, 4.46486771378823)
CAPSIZE_V5 = -0.32286642900409
CASTOR_V5 = -14.07838969279822
V_WEAVE = 4.292382536341
V_CAPSIZE = 6.024262015388


def test_matrices_match_the_paper():
    # the paper prints 14–15 significant digits
    for got, paper in zip(bicycle.matrices(P), (M_PAPER, C1_PAPER, K0_PAPER, K2_PAPER)):
        np.testing.assert_allclose(got, paper, rtol=1e-13, atol=1e-13)


def test_roots_at_rest_and_at_5_m_s_match_table_2():
    lam0 = bicycle.eigenvalues(P, 0.0)
    np.testing.assert_allclose(lam0.imag, 0.0, atol=1e-12)
    np.testing.assert_allclose(lam0.real, ROOTS_V0, rtol=1e-12)
    lam5 = bicycle.eigenvalues(P, 5.0)
    expect = [CAPSIZE_V5, WEAVE_V5, WEAVE_V5.conjugate(), CASTOR_V5]
    np.testing.assert_allclose(lam5, expect, rtol=1e-12)
    assert bicycle.root_labels(lam5) == ["capsize", "weave", "weave", "castor"]


def _char_poly_roots(p, v):
    """Roots of det(A λ² + B λ + C) for the 2×2 matrices, from its quartic's coefficients."""
    M, C1, K0, K2 = bicycle.matrices(p)
    A, B, C = M, v * C1, p["g"] * K0 + v * v * K2
    polys = [[np.poly1d([A[i, j], B[i, j], C[i, j]]) for j in range(2)] for i in range(2)]
    det = polys[0][0] * polys[1][1] - polys[0][1] * polys[1][0]
    return np.roots(det.coeffs)


@pytest.mark.parametrize("v", np.arange(0.0, 10.01, 0.5))
def test_roots_from_0_to_10_m_s_are_the_characteristic_polynomials(v):
    lam = bicycle.eigenvalues(P, v)
    ref = _char_poly_roots(P, v)
    # match each root to its nearest (the quartic's roots carry ~1e-12 relative rounding)
    for x in lam:
        assert np.min(np.abs(ref - x)) <= 1e-9 * max(1.0, abs(x)), (v, x, ref)


def test_weave_and_capsize_speeds_by_root_finding():
    v_w, v_c = bicycle.weave_capsize_speeds(P)
    assert abs(v_w - V_WEAVE) < 1e-8
    assert abs(v_c - V_CAPSIZE) < 1e-8
    # self-stable in between, unstable just outside
    assert bicycle.growth_rate(P, 0.5 * (v_w + v_c)) < 0
    assert bicycle.growth_rate(P, v_w - 1e-3) > 0 < bicycle.growth_rate(P, v_c + 1e-3)


def test_the_leaf_lists_every_root_and_the_weave_mode():
    m = solvers.modes(SCENE, solvers.get_solver("meijaard"), SCENE.resolve({"speed": "5"}))
    assert m.status == "ok", m.reason
    eig = np.asarray(m.extra["eigenvalues"])
    assert eig.shape == (4, 2)
    np.testing.assert_allclose(eig[:, 0] + 1j * eig[:, 1],
                               [CAPSIZE_V5, WEAVE_V5, WEAVE_V5.conjugate(), CASTOR_V5],
                               rtol=1e-12)
    assert m.labels == ["weave"]
    np.testing.assert_allclose(m.frequencies_hz, [WEAVE_V5.imag / (2 * np.pi)], rtol=1e-12)
    np.testing.assert_allclose(m.damping, [-WEAVE_V5.real / abs(WEAVE_V5)], rtol=1e-12)
    assert m.extra["max_re_per_s"] == pytest.approx(CAPSIZE_V5, rel=1e-12)
    # the round-off bounds cover the difference from the paper's 14 digits
    assert np.all(np.asarray(m.extra["eigenvalue_error_per_s"]) < 1e-11)


def test_modes_json_gives_every_root_as_re_im(tmp_path):
    from tests.conftest import xval
    rc, out, err = xval("modes", "bicycle", "--solver", "meijaard", "--set", "speed=0", "--json",
                        "--out", str(tmp_path / "m"))
    assert rc == 0, err
    run = json.loads(out)["runs"][0]
    roots = sorted(x for x, _ in run["eigenvalues"])
    np.testing.assert_allclose(roots, sorted(ROOTS_V0), rtol=1e-12)
    assert all(im == 0.0 for _, im in run["eigenvalues"])
    assert run["frequencies_hz"] == []          # four real roots: nothing oscillates at rest


def test_growth_rate_map_brackets_the_published_weave_and_capsize_speeds(tmp_path):
    import xval
    r = xval.map("bicycle", "speed=0:10", solvers=["meijaard"], observable="growth_rate",
                 level=0.0, resolution=1e-4, record=False, out=tmp_path, workers=1)
    found = r.to_json()["boundaries"]["meijaard"]
    assert [(b["from"], b["to"]) for b in found] == [("above", "below"), ("below", "above")]
    for b, v in zip(found, (V_WEAVE, V_CAPSIZE)):
        lo, hi = b["bracket"]
        assert lo <= v <= hi and hi - lo <= 1e-3


def test_listed_in_the_benchmarks_group_and_campaign(capsys):
    from compare.commands import list as list_command
    from compare.workflows.campaign_plan import load_campaign
    list_command.main(None)
    group = [ln for ln in capsys.readouterr().out.splitlines() if ln.startswith("group")]
    assert any("benchmarks" in ln and "bicycle" in ln for ln in group)
    camp = load_campaign("benchmarks")
    assert {c.get("set", {}).get("speed", 5.0) for c in camp["cases"]
            if c["scene"] == "bicycle"} \
        == {0.0, 5.0}
    (m,) = [m for m in camp["maps"] if m["scene"] == "bicycle"]
    assert m["observable"] == "growth_rate" and m["level"] == 0.0


def test_a_design_without_a_positive_definite_mass_matrix_is_bad_input(tmp_path):
    from tests.conftest import xval
    rc, _, err = xval("modes", "bicycle", "--set", "I_Hxz=-100", "--out", str(tmp_path / "o"))
    # the fork's I_xz of −100 kg·m² is no rigid body's either (the triangle inequality of its
    # principal moments), which the scene checks first
    assert rc == 2 and ("positive definite" in err or "triangle inequality" in err)
    assert len(err.strip().splitlines()) == 1
    assert not (tmp_path / "o").exists()
