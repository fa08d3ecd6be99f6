"""A 2-D map's boundary traced in y: rows added where neighbouring rows' crossings differ,
until the curve is resolved in both axes — against a boundary known in closed form, and on
the rotor against an independent passage test at a row the tracing added."""
import json

import numpy as np
import pytest
from test_maps import _passes

from compare.workflows import maps


def _axis(name, lo, hi):
    return maps.Axis(name, lo, hi, "")


def boundary(y):
    """The closed form: no crossing below y = 0.05; above it a curve with a steep bend."""
    return None if y < 0.05 else 2.0 + np.sin(30.0 * y)


class Plane:
    """A runner whose regime is read off `boundary`: left of the curve "a", right "b"."""

    def __init__(self):
        self.n = 0

    def run(self, tasks):
        self.n += len(tasks)
        out = []
        for _, _, pt in tasks:
            xb = boundary(pt["y"])
            out.append({"label": "a" if xb is None or pt["x"] < xb else "b"})
        return out


def _trace(y_res=1 / 64, width=0.02, max_rows=257):
    xa = _axis("x", 0.0, 4.0)
    xs = np.linspace(0.0, 4.0, 9)
    runner = Plane()
    lines = {float(y): {} for y in np.linspace(0.0, 0.2, 3)}
    maps._fill(runner, "s", {}, lines, [(y, float(x)) for y in lines for x in xs], "x", "y",
               "label")
    maps.bisect_lines(runner, "s", {}, lines, xa, width, "y")
    left = maps.trace_rows(runner, "s", {}, lines, xa, xs, width, "y", y_res * 0.2, max_rows)
    return lines, left, runner


def test_the_traced_boundary_is_the_closed_form_curve_resolved_in_both_axes():
    width, y_width = 0.02, 0.2 / 64
    lines, left, _ = _trace(1 / 64, width)
    assert left == []
    found = {c["y"]: c for c in maps.crossings(lines, None, None)}
    for y in lines:
        xb = boundary(y)
        if xb is None:
            assert y not in found
        else:
            assert abs(found[y]["x"] - xb) <= width, (y, found[y], xb)
    ys = sorted(lines)
    for a, b in zip(ys, ys[1:]):      # neighbours agree to the bracket, or are y_width apart
        same = a in found and b in found and abs(found[a]["x"] - found[b]["x"]) <= width
        assert same or (a not in found and b not in found) or b - a <= y_width * (1 + 1e-9)
    # the curve's start (y = 0.05) is located to y_width: a row within it on either side
    first = min(found)
    assert 0.05 <= first <= 0.05 + y_width
    assert max(y for y in ys if y < first) >= 0.05 - y_width


def test_a_row_budget_leaves_the_gaps_it_could_not_resolve_listed():
    lines, left, _ = _trace(max_rows=6)
    assert left and len(lines) <= 6


@pytest.mark.parametrize("y", [0.0025, 0.00625])
def test_a_row_the_rotor_map_added_holds_its_crossing_by_an_independent_passage_test(y):
    """The default rotor map, custom solvers, traced in eccentricity: the rows between the
    coarse e = 0 and 0.005 and around the peak of M*(e) near 0.00625 — checked by the test's
    own reading of passage with the other custom solver at the bracket's ends."""
    plan = maps.plan_map("rotor-spinup", "torque=1:5", "eccentricity=0:0.02", {"t_end": 10},
                         ["quaternion"], resolution=1e-2, coarse=(9, 5), y_resolution=1 / 32)
    res = maps.run_map(plan)
    assert res["rows"]["quaternion"] > 5
    (c,) = [c for c in res["boundaries"]["quaternion"] if c["y"] == pytest.approx(y)]
    lo, hi = c["bracket"]
    base = {"eccentricity": y}
    assert not _passes(lo, "euler-vector", base) and _passes(hi, "euler-vector", base)


class Shifted(Plane):
    """The cheap level (rtol 1) misplaces the boundary by 0.3 — three grid steps: wrong labels
    next to it, right ones far from it, as a loose tolerance does (one promotion pass is not
    enough; without the repeat this test fails)."""

    def run(self, tasks):
        self.n += len(tasks)
        out = []
        for _, st, pt in tasks:
            xb = boundary(pt["y"])
            xb = None if xb is None else xb + (0.3 if st.get("rtol") == 1 else 0.0)
            out.append({"label": "a" if xb is None or pt["x"] < xb else "b"})
        return out


def test_the_adaptive_grid_ends_with_the_accurate_labels_and_reruns_only_near_the_change():
    grid = [[{"x": float(x), "y": float(y)} for x in np.linspace(0, 4, 41)]
            for y in np.linspace(0.0, 0.2, 21)]
    runner = Shifted()
    labels, sure = maps.adaptive_grid(runner, "s", {"rtol": 1}, {"rtol": 1e-9}, grid)
    truth = [[Plane().run([(None, {}, p)])[0]["label"] for p in row] for row in grid]
    assert labels == truth
    n, rerun = 41 * 21, sum(map(sum, sure))
    assert rerun < 0.2 * n and runner.n == n + rerun


@pytest.mark.parametrize("solver", ["quaternion", "mujoco"])
def test_the_rotor_maps_adaptive_boundary_is_the_all_accurate_one(solver):
    """The same map run accuracy-adaptive and accurate everywhere: identical crossings and
    brackets; and cheap labels sampled hold at the accurate setting (quaternion: a looser
    tolerance; MuJoCo: its CHEAP_DT, 10× its accurate step)."""
    def run(adaptive):
        plan = maps.plan_map("rotor-spinup", "torque=1:5", "eccentricity=0:0.02",
                             {"t_end": 10}, [solver], resolution=2e-2, coarse=(9, 3),
                             y_resolution=0.49, adaptive=adaptive, engines="everywhere")
        return maps.run_map(plan)
    fast, slow = run(True), run(False)
    assert fast["boundaries"] == slow["boundaries"]
    assert fast["levels"][solver]["cheap"] > 0 and slow["levels"][solver]["cheap"] == 0
    cheap = [p for p in fast["points"] if p["settings"] == "cheap"]
    truth = {json.dumps(p["params"], sort_keys=True): p["regime"] for p in slow["points"]}
    for p in cheap:
        assert truth[json.dumps(p["params"], sort_keys=True)] == p["regime"], p
