"""A map's refinement: bisection of every line's crossings (`bisect_lines`), the accuracy-
adaptive coarse grid (`adaptive_grid`), a 2-D boundary traced in y by rows added between
neighbours that differ (`trace_rows`), an engine's crossings from the custom solvers' brackets
(`refine_engine`), a scalar observable's refinement and level crossings, and each crossing's
error estimate from its bracket rerun at tighter settings (`crossing_errors`)."""
from __future__ import annotations

import numpy as np

from .map_run import NONE, _pt


def _line_crossings(xs, labels):
    """Indices i where labels[i] != labels[i + 1] along a sorted line."""
    return [i for i in range(len(xs) - 1) if labels[i] != labels[i + 1]]


def bisect_lines(runner, solver, settings, lines, x_axis, width, y_name=None):
    """Bisect every crossing on every line until its bracket is ≤ width. `lines`: {y: {x:
    label}} (y None for a 1-D map), changed in place. Every open bracket of a round is one
    batch."""
    while True:
        mids = []
        for y, pts in lines.items():
            xs = sorted(pts)
            for i in _line_crossings(xs, [pts[x] for x in xs]):
                if xs[i + 1] - xs[i] > width * (1 + 1e-9):
                    mids.append((y, 0.5 * (xs[i] + xs[i + 1])))
        if not mids:
            return
        _fill(runner, solver, settings, lines, mids, x_axis.name, y_name, "label")


def adaptive_grid(runner, solver, cheap, accurate, grid):
    """Labels of a grid of points (rows of point dicts, neighbours along and across rows),
    accuracy spent only where a regime changes: every point first at `cheap` (None: all at
    `accurate`), then each point with a neighbour of another label rerun at `accurate`,
    again until every point next to a change is an accurate one — so every bracket a map
    bisects has accurate ends, and a cheap label stands only where all its neighbours read
    the same. Returns (labels, accurate?) as lists of rows."""
    first = cheap or accurate
    flat = runner.run([(solver, first, pt) for row in grid for pt in row])
    it = iter(flat)
    labels = [[next(it)["label"] for _ in row] for row in grid]
    sure = [[cheap is None] * len(row) for row in grid]
    while True:
        todo = set()
        for i, row in enumerate(labels):
            for j, lab in enumerate(row):
                for a, b in ((i, j + 1), (i + 1, j)):
                    if a < len(labels) and b < len(labels[a]) and labels[a][b] != lab:
                        todo |= {(i, j), (a, b)}
        todo = sorted((i, j) for i, j in todo if not sure[i][j])
        if not todo:
            return labels, sure
        for (i, j), r in zip(todo, runner.run([(solver, accurate, grid[i][j])
                                               for i, j in todo])):
            labels[i][j], sure[i][j] = r["label"], True


def _rows_differ(a: dict, b: dict, width: float) -> bool:
    """Two rows' crossings differ: in number or direction, or in place by more than `width`."""
    ca, cb = ([(0.5 * (xs[i] + xs[i + 1]), pts[xs[i]], pts[xs[i + 1]])
               for i in _line_crossings(xs, [pts[x] for x in xs])]
              for pts in (a, b) for xs in [sorted(pts)])
    return len(ca) != len(cb) or any(p[1:] != q[1:] or abs(p[0] - q[0]) > width
                                     for p, q in zip(ca, cb))


def trace_rows(runner, solver, settings, lines, x_axis, xs, width, y_name, y_width,
               max_rows):
    """Rows added half-way between neighbours whose crossings differ, each run on the coarse
    x grid `xs` and bisected, until no neighbours differ or they are ≤ `y_width` apart (all
    rows of a round one batch). Returns the (y, y) gaps left unresolved by `max_rows`."""
    while True:
        ys = sorted(lines)
        gaps = [(a, b) for a, b in zip(ys, ys[1:])
                if _rows_differ(lines[a], lines[b], width)]
        new = [0.5 * (a + b) for a, b in gaps if b - a > y_width * (1 + 1e-9)]
        if not new:
            return []
        if len(lines) + len(new) > max_rows:
            return [(a, b) for a, b in gaps if b - a > y_width * (1 + 1e-9)]
        grid = [(y, float(x)) for y in new for x in xs]
        for y in new:
            lines[y] = {}
        _fill(runner, solver, settings, lines, grid, x_axis.name, y_name, "label")
        bisect_lines(runner, solver, settings, {y: lines[y] for y in new}, x_axis, width,
                     y_name)


def _fill(runner, solver, settings, lines, mids, x_name, y_name, key):
    """Run the points (y, x) of one refinement round as one batch; store their label/value."""
    rows = runner.run([(solver, settings, _pt(x_name, x, y_name, y)) for y, x in mids])
    for (y, x), row in zip(mids, rows):
        lines[y][x] = row[key]


def crossings(lines, x_axis, y_axis):
    """Every crossing of every line as {"x", "y", "bracket", "from", "to"}."""
    out = []
    for y, pts in sorted(lines.items(), key=lambda kv: (kv[0] is not None, kv[0])):
        xs = sorted(pts)
        for i in _line_crossings(xs, [pts[x] for x in xs]):
            out.append({"x": 0.5 * (xs[i] + xs[i + 1]), "y": y, "bracket": [xs[i], xs[i + 1]],
                        "from": pts[xs[i]], "to": pts[xs[i + 1]]})
    return out


def refine_engine(runner, solver, settings, ref_crossings, x_axis, width, coarse_step,
                  y_name):
    """An engine's own crossings, started from the custom solvers' brackets: its runs at the
    bracket's ends; while both ends read the same regime the bracket is widened outwards
    (doubling, up to a coarse step each side); then its own bisection. Returns its lines."""
    lines = {}
    for c in ref_crossings:
        lo, hi = c["bracket"]
        y = c["y"]
        pts = lines.setdefault(y, {})
        grow = hi - lo
        while True:
            lo, hi = max(x_axis.lo, lo), min(x_axis.hi, hi)
            a, b = runner.run([(solver, settings, _pt(x_axis.name, x, y_name, y))
                               for x in (lo, hi)])
            pts[lo], pts[hi] = a["label"], b["label"]
            if a["label"] != b["label"] or grow > coarse_step \
                    or (lo <= x_axis.lo and hi >= x_axis.hi):
                break
            lo, hi, grow = lo - grow, hi + grow, 2 * grow
    bisect_lines(runner, solver, settings, lines, x_axis, width, y_name)
    return lines


def refine_observable(runner, solver, settings, lines, x_axis, width, level, y_name,
                      max_rounds=12):
    """A scalar observable on each line: bisect where it crosses `level` (or where the event
    starts or stops happening); without a level, where it changes fastest — intervals whose
    change exceeds twice the line's median change (a straight line is not refined) — until
    they are ≤ width."""
    for _ in range(max_rounds):
        mids = []
        for y, pts in lines.items():
            xs = sorted(pts)
            vals = [pts[x] for x in xs]
            steps = [abs(b - a) for a, b in zip(vals, vals[1:])
                     if a is not None and b is not None]
            fast = 2 * float(np.median(steps)) if steps else 0.0
            for i in range(len(xs) - 1):
                if xs[i + 1] - xs[i] <= width * (1 + 1e-9):
                    continue
                a, b = vals[i], vals[i + 1]
                if (a is None) != (b is None):
                    split = True
                elif a is None:
                    split = False
                elif level is not None:
                    split = (a - level) * (b - level) < 0
                else:
                    split = fast > 0 and abs(b - a) > fast
                if split:
                    mids.append((y, 0.5 * (xs[i] + xs[i + 1])))
        if not mids:
            return
        _fill(runner, solver, settings, lines, mids, x_axis.name, y_name, "value")


def level_crossings(lines, level):
    """Where a scalar line crosses `level` or its event appears / disappears."""
    out = []
    for y, pts in sorted(lines.items(), key=lambda kv: (kv[0] is not None, kv[0])):
        xs = sorted(pts)
        for i in range(len(xs) - 1):
            a, b = pts[xs[i]], pts[xs[i + 1]]
            la = NONE if a is None else ("above" if level is not None and a >= level else
                                         ("below" if level is not None else "value"))
            lb = NONE if b is None else ("above" if level is not None and b >= level else
                                         ("below" if level is not None else "value"))
            if la != lb:
                out.append({"x": 0.5 * (xs[i] + xs[i + 1]), "y": y,
                            "bracket": [xs[i], xs[i + 1]], "from": la, "to": lb})
    return out


def crossing_errors(runner, solver, settings, tight, lines, found, x_axis, width, y_name):
    """Rerun each crossing's two bracketing points at the tighter settings; where a regime
    flips, locate the crossing again at those settings: its shift is the error estimate."""
    if tight is None:
        for c in found:
            c.update(error=None, holds=None, error_by="no tighter setting")
        return
    rows = runner.run([(solver, tight, _pt(x_axis.name, x, y_name, c["y"]))
                       for c in found for x in c["bracket"]])
    for i, c in enumerate(found):
        a, b = rows[2 * i]["label"], rows[2 * i + 1]["label"]
        c["holds"] = a == c["from"] and b == c["to"]
        c["error_by"] = f"bracket rerun at {_settings_text(tight)}"
        for x, was, now in zip(c["bracket"], (c["from"], c["to"]), (a, b)):
            key = runner._key(solver, settings, _pt(x_axis.name, x, y_name, c["y"]))
            runner.tight[key] = (f"regime {'holds' if was == now else 'flips to ' + now} at "
                                 f"{_settings_text(tight)}")
        if c["holds"]:
            c["error"] = 0.0
            continue
        # locate it again at the tighter settings from a bracket a coarse step wide
        line = {c["y"]: {}}
        lo, hi = c["bracket"]
        span = max(hi - lo, width) * 4
        xs = np.linspace(max(x_axis.lo, c["x"] - span), min(x_axis.hi, c["x"] + span), 5)
        for x, r in zip(xs, runner.run([(solver, tight, _pt(x_axis.name, x, y_name, c["y"]))
                                        for x in xs])):
            line[c["y"]][float(x)] = r["label"]
        bisect_lines(runner, solver, tight, line, x_axis, width, y_name)
        again = [d for d in crossings(line, x_axis, None)
                 if d["from"] == c["from"] and d["to"] == c["to"]]
        shift = min((abs(d["x"] - c["x"]) for d in again), default=None)
        if shift is not None and shift <= 2 * width:
            c["error"] = shift       # within two brackets: the location's own error
            continue
        # the tighter setting answers otherwise — the crossing gone, or moved past two brackets
        # (a wider window would agree with anything): the verdict says `unconfirmed`
        why = ("crossing vanishes at its tighter setting" if shift is None else
               f"crossing moves {shift:.3g} at its tighter setting, beyond two brackets "
               f"({2 * width:.3g})")
        c.update(error=None, unconfirmed=True, unconfirmed_why=why,
                 error_by=f"{c['error_by']}: the {why}")


def _settings_text(st):
    return ", ".join(f"{k}={v}" for k, v in st.items() if k in ("rtol", "dt", "integrator"))
