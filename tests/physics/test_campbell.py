"""Campbell diagrams a reviewer can follow (issue 23, item 4): adaptive sampling, lines tracked
by mode shape, veering told apart from crossing.

The two-mode system K(s) = [[1 + s, ε], [ε, 3.2 − s]] (unit mass) has the closed form
λ± = 2.1 ± √((s − 1.1)² + ε²): with ε = 0 the diagonal lines 1 + s and 3.2 − s cross at
s = 1.1 and the shapes (the unit vectors) keep; with ε > 0 the lines veer, their least gap is
2ε at s = 1.1, and the shapes are handed over (the lower mode is e₁ far left, e₂ far right).
"""
import numpy as np
import pytest

from compare import solvers
from compare.analysis.campbell import sample, track_lines
from compare.analysis.trajectory import Modes
from compare.scenes import get_scene

BASE = np.array([0.0, 0.7, 1.4, 2.1])     # 1.1 is no bisection point of these steps
MIN_STEP = 0.7 / 64


def two_modes(eps):
    def at(s):
        w, v = np.linalg.eigh([[1 + s, eps], [eps, 3.2 - s]])
        return [Modes("two-mode", "eigh", w, ["", ""], shapes=v.T.copy())]
    return at


def diagram(eps):
    values, per_point = sample(two_modes(eps), BASE, 20, MIN_STEP)
    return track_lines(values, [p[0] for p in per_point])


def test_crossing_keeps_the_shapes_and_the_diagonal_lines():
    d = diagram(0.0)
    assert len(d.values) > len(BASE)                     # refined around the crossing
    assert [e.kind for e in d.events] == ["crossing"]
    e = d.events[0]
    assert e.lo < 1.1 < e.hi and e.hi - e.lo <= 2 * MIN_STEP
    assert e.at == pytest.approx(1.1, abs=1e-12)          # both lines are straight
    lines = sorted(d.lines.values(), key=lambda f: f[0])
    assert lines[0] == pytest.approx(1 + d.values, abs=1e-12)
    assert lines[1] == pytest.approx(3.2 - d.values, abs=1e-12)
    assert all(np.nanmin(m) == pytest.approx(1.0, abs=1e-12) for m in d.mac.values())


@pytest.mark.parametrize("eps", [0.05, 0.01])
def test_veering_keeps_the_frequency_order_and_is_marked(eps):
    d = diagram(eps)
    assert [e.kind for e in d.events] == ["veering"]
    e = d.events[0]
    # the least sampled gap: at least the closed form's 2ε, at most its value one bisection
    # step (2·MIN_STEP) away from s = 1.1
    assert 2 * eps <= e.gap_hz <= 2 * np.hypot(2 * MIN_STEP, eps)
    assert abs(e.at - 1.1) <= 2 * MIN_STEP
    root = np.hypot(d.values - 1.1, eps)
    lines = sorted(d.lines.values(), key=lambda f: f[0])
    assert lines[0] == pytest.approx(2.1 - root, abs=1e-12)     # the lines never cross
    assert lines[1] == pytest.approx(2.1 + root, abs=1e-12)
    assert d.min_mac_unmarked() >= 0.9


def test_a_veering_narrower_than_the_finest_step_reads_as_a_crossing():
    """The resolution the docstring states: gap 2ε = 2e-4 against steps of 0.011."""
    assert [e.kind for e in diagram(1e-4).events] == ["crossing"]


def test_hover_lines_keep_their_shapes():
    """The hovering helicopter (mstmm) on the scene's sampling: more points than the 11 of the
    grid, within the scene's budget; along every line, the MAC of consecutive samples —
    recomputed here from the solver's shapes — is ≥ 0.9 except over a marked veering."""
    sc = get_scene("helicopter-hover")
    s, p, cb = solvers.get_solver("mstmm"), sc.resolve(), sc.campbell
    grid = cb.values(p)
    values, per_point = sample(lambda v: [solvers.modes(sc, s, {**p, "speed": v})], grid,
                               cb.refine, (grid[1] - grid[0]) / 2 ** cb.depth)
    results = [pt[0] for pt in per_point]
    assert len(grid) < len(values) <= len(grid) + cb.refine
    d = track_lines(values, results)
    marked = [(e.lines, e.lo, e.hi) for e in d.events if e.kind != "crossing"]
    checked = 0
    for key, f in d.lines.items():
        for k in np.nonzero(np.isfinite(f[:-1]) & np.isfinite(f[1:]))[0]:
            a = results[k].shapes[list(results[k].frequencies_hz).index(f[k])]
            b = results[k + 1].shapes[list(results[k + 1].frequencies_hz).index(f[k + 1])]
            m = abs(np.vdot(a, b)) ** 2 / (np.vdot(a, a).real * np.vdot(b, b).real)
            if not any(key in ks and lo <= values[k] and values[k + 1] <= hi
                       for ks, lo, hi in marked):
                assert m >= 0.9, (key, values[k])
            checked += 1
    assert checked > 100
