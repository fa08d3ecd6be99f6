"""Roots of a characteristic function g(ω) (a scaled determinant) over a grid: every sign
change is bracketed and refined; a dip of |g| that does not change sign (two roots closer
than the grid, or a double root) is zoomed into until it resolves into sign changes or
touches zero; after each root the function is deflated, g/(ω − r), and the bracket searched
again, so clusters of three or more roots inside one grid step are not counted once.
"""
import numpy as np
from scipy.optimize import brentq

ZOOM_POINTS = 9
MAX_DEPTH = 12
# a dip that never changes sign is a double root when |g| at the finest zoom is below this
# fraction of |g| where the dip was first seen (a double root falls as (ω − r)²: ~1e-10 over
# the zoom; a mere minimum of |g| stays O(1))
DOUBLE_ROOT_LEVEL = 1e-6
# Roots are always located to at least this relative tolerance: deflation g/(ω − r), the
# known-root tests and the zoom's stopping width all assume r is exact. A looser `rtol` only
# looked cheaper: measured on the helicopter (tail clamped), rtol 1e-6 found the 9.655 Hz root
# twice and rtol 1e-4 missed the 6.346 Hz cyclic pair (the zoom stopped at 10 % width).
SEARCH_RTOL = 1e-10


def hadamard_det(A: np.ndarray) -> float:
    """det A / Π‖a_j‖: same sign and zeros as det A, bounded by 1 (no overflow at high ω)."""
    norms = np.linalg.norm(A, axis=0)
    norms[norms == 0] = 1.0
    sign, logdet = np.linalg.slogdet(A / norms)
    return float(sign * np.exp(logdet))


def find_roots(g, grid: np.ndarray, rtol: float = 1e-12) -> list:
    """All roots of g on [grid[0], grid[-1]], ascending, multiplicity counted for double
    roots (|g| touching zero without a sign change). `rtol` can tighten the refinement below
    SEARCH_RTOL, never loosen it."""
    rtol = min(rtol, SEARCH_RTOL)
    vals = np.array([g(w) for w in grid])
    return sorted(_roots_on(g, np.asarray(grid, float), vals, rtol, 0))


def hidden_roots(g, grid: np.ndarray, known: list, rtol: float, passes: int = 3) -> list:
    """Roots a first pass over `grid` could not see beside `known` ones: g deflated by them,
    g/Π(ω − r)/r, searched again on the grid (sign changes and dips), until a pass adds none.
    A known root's zero falls steeply through its cell and the next, and a pair of roots closer
    than a cell beside it makes neither a sign change nor a dip of |g| there: the clamped
    aircraft at rest (`xval calibrate helicopter-clamped --seed 6161` set 3) lost its second
    cyclic flap pair, 3.39149/3.39158 Hz, one cell above lag collective 1 at 3.39050 (fem and
    both engines list it). Deflated, the pair is a dip of its own."""
    new: list = []
    for _ in range(passes):
        roots = np.array(known + new, float)

        def h(x, roots=roots):
            d = np.prod((x - roots) / roots)
            return g(x) / d if d != 0 else np.inf
        w = np.asarray(grid, float)
        if len(roots):
            w = w[np.min(np.abs(w[:, None] - roots[None, :]), axis=1) > 1e-9 * w]
        more = [r for r in find_roots(h, w, rtol)
                if not len(roots) or np.min(np.abs(roots - r)) > 1e-7 * r]
        if not more:
            break
        new += more
    return new


def _roots_on(g, w, v, rtol, depth, ref_level=None):
    roots = []
    n = len(w)
    for i in range(n - 1):
        if v[i] == 0.0:
            roots.append(w[i])
            continue
        if v[i] * v[i + 1] < 0:
            r = brentq(g, w[i], w[i + 1], xtol=rtol * abs(w[i + 1]), rtol=1e-15, maxiter=200)
            roots.append(r)
            roots += _cluster(g, w[i], w[i + 1], [r], rtol, depth)
    for i in range(1, n - 1):
        # a dip of |g| with no sign change beside it: zoom
        if (abs(v[i]) < abs(v[i - 1]) and abs(v[i]) < abs(v[i + 1]) and v[i - 1] * v[i] > 0
                and v[i] * v[i + 1] > 0 and _may_touch(w[i - 1:i + 2], v[i - 1:i + 2])):
            ref = ref_level or max(abs(v[i - 1]), abs(v[i + 1]))
            roots += _zoom(g, w[i - 1], w[i + 1], rtol, depth + 1, ref)
    return roots


def _may_touch(w, v):
    """Can two roots hide in a dip of |g| seen at three samples? Yes if the parabola through
    them reaches zero or comes close, or if the middle sample is far below both neighbours (a
    dip narrower than the grid, which the parabola does not follow)."""
    if abs(v[1]) < 0.2 * min(abs(v[0]), abs(v[2])):
        return True
    # the parabola a x² + b x + v[1] through the three samples (x = w − w[1]), in closed form
    x0, x2 = w[0] - w[1], w[2] - w[1]
    s0, s2 = (v[0] - v[1]) / x0, (v[2] - v[1]) / x2
    a = (s0 - s2) / (x0 - x2)
    b = s0 - a * x0
    if a == 0:
        return False
    vmin = v[1] - b ** 2 / (4 * a)
    return np.sign(vmin) != np.sign(v[1]) or abs(vmin) < 0.5 * abs(v[1])


def _zoom(g, a, b, rtol, depth, ref):
    """Sample a dip more finely; `ref` is |g| beside the dip where it was first seen."""
    w = np.linspace(a, b, ZOOM_POINTS)
    v = np.array([g(x) for x in w])
    if (b - a) < 1e3 * rtol * b or depth > MAX_DEPTH:
        # at the resolution and still no sign change: a double root if |g| fell like (ω − r)²
        # from the first sighting (ratio (width/grid step)² ≪ DOUBLE_ROOT_LEVEL), else none
        i = int(np.argmin(np.abs(v)))
        return [w[i], w[i]] if abs(v[i]) < DOUBLE_ROOT_LEVEL * ref else []
    return _roots_on(g, w, v, rtol, depth, ref)


def _cluster(g, a, b, found, rtol, depth):
    """More roots in [a, b] besides `found`: search the deflated function."""
    if depth > MAX_DEPTH:
        return []

    def h(x):
        d = np.prod([x - r for r in found])
        return g(x) / d if d != 0 else np.inf
    w = np.linspace(a, b, ZOOM_POINTS)
    # keep the samples off the known roots (the deflated function is 0/0 there)
    for r in found:
        w = w[np.abs(w - r) > 1e-6 * (b - a)]
    v = np.array([h(x) for x in w])
    extra = []
    for i in range(len(w) - 1):
        if v[i] * v[i + 1] < 0:
            r = brentq(h, w[i], w[i + 1], xtol=rtol * abs(w[i + 1]), rtol=1e-15, maxiter=200)
            if all(abs(r - f) > 10 * rtol * abs(r) for f in found + extra):
                extra.append(r)
    for i in range(1, len(w) - 1):
        if (abs(v[i]) < abs(v[i - 1]) and abs(v[i]) < abs(v[i + 1]) and v[i - 1] * v[i] > 0
                and v[i] * v[i + 1] > 0 and _may_touch(w[i - 1:i + 2], v[i - 1:i + 2])):
            for r in _zoom(h, w[i - 1], w[i + 1], rtol, depth + 1,
                           max(abs(v[i - 1]), abs(v[i + 1]))):
                extra.append(r)
    if extra:
        extra += _cluster(g, a, b, found + extra, rtol, depth + 1)
    return extra


def root_error_hz(f_hz, rtol: float) -> np.ndarray:
    """The error estimate of roots located to `rtol` (brentq's xtol = rtol·|ω|, never looser
    than SEARCH_RTOL) plus their round-off: the transfer matrices are exact, so this is all."""
    f = np.abs(np.asarray(f_hz, float))
    return (min(rtol, SEARCH_RTOL) + 4 * np.finfo(float).eps) * f
