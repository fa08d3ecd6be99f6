"""`xval map`: a scene's regimes (or a scalar observable) over one or two parameters, the
boundaries located by every solver on its own and compared with error bars.

Regimes: a coarse grid, then bisection of every grid edge along x whose ends differ in regime
until its bracket is at most `resolution` × the x range (all open brackets of a round are one
batch of runs). A 2-D map bisects along x on each row, then traces the boundary in y: between
two neighbouring rows whose crossings differ (in number, or in place by more than the x
bracket) a row is added half-way, run on the coarse x grid and bisected, until neighbouring
rows agree or are `y_resolution` × the y range apart — the boundary is resolved as a curve in
both axes, and only computed crossings are drawn. The custom solvers map the whole plane; an
engine starts from the custom solvers' brackets on the coarse rows (its own runs at their
ends, widened outwards until they straddle its own crossing, then its own bisection) and runs
elsewhere only with `engines="everywhere"`: the rows added between are the custom solvers'.
A scalar observable is refined where it changes fastest (or bisected where it crosses `level`).

Every crossing's bracketing runs are rerun at the solver's tighter settings (those of its own
error estimate): where a regime flips there, the crossing is located again at the tighter
settings and the shift is the crossing's error estimate. Two solvers' crossings agree when
their distance is within the resolution plus both error estimates plus both half-brackets.
"""
from __future__ import annotations

import datetime
import hashlib
import json
import math
import os
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import solvers
from ..analysis.verdict import Verdict
from ..errors import BadInput
from ..output import progress
from ..output.store import store_point
from ..results import MapResult
from ..scenes import get_scene
from . import plan as planner
from .digest import STORE_VERSION, job_code
from .executors import Interrupted, execute_many, worker_pool

NONE = "none"                     # an observable's label where its event did not happen
MAX_JOBS = 100_000                # runs a map may plan before it is refused (--max-jobs)
# a chunk's most points: ~0.1 s of a cheap rotor point's work on one core, ~1 % of it spent
# draining the lanes at the chunk's end and on the call
CHUNK = 256
MAX_ROWS = 257                    # rows a 2-D map's boundary tracing may reach per solver
# the rows' default spacing where the boundary bends, of the y range: the x bracket (1e-3 by
# default) taken for y too hit MAX_ROWS on the rotor map (197 rows, 144 gaps left, 180 s)
Y_RESOLUTION = 1 / 64
# the estimate before anything runs: seconds per output sample and per run, by solver engine,
# measured on rotor-spinup over 10 s at 1001 samples (quaternion 3.3 ms, euler-vector 5 ms,
# MuJoCo 86 ms, Exudyn 316 ms per run) plus a fixed cost per run; rough for other scenes
COST_PER_SAMPLE = {"numba": 5e-6, "numpy": 1e-6, "scipy": 5e-5, "mujoco": 9e-5,
                   "exudyn": 3.2e-4}
COST_PER_RUN = {"mujoco": 0.02, "exudyn": 0.05}


@dataclass(frozen=True)
class Axis:
    name: str
    lo: float
    hi: float
    unit: str

    @property
    def span(self):
        return self.hi - self.lo

    def as_dict(self):
        return {"name": self.name, "lo": self.lo, "hi": self.hi, "unit": self.unit}


def parse_axis(text, sc, flag):
    """NAME=LO:HI → Axis, the name a numeric scalar parameter of the scene, LO < HI inside its
    admissible range."""
    name, sep, rng = (text or "").partition("=")
    lo_t, sep2, hi_t = rng.partition(":")
    if not sep or not sep2:
        raise BadInput(f"{flag} {text!r}: expected NAME=LO:HI")
    p = sc.param(name.strip())
    if not p.is_numeric:
        raise BadInput(f"{flag} {name}: not a numeric parameter of scene {sc.name}")
    lo, hi = p.parse(lo_t), p.parse(hi_t)
    if not lo < hi:
        raise BadInput(f"{flag} {text!r}: LO must be below HI")
    return Axis(p.name, float(lo), float(hi), p.unit)


# --- running points ----------------------------------------------------------------------

def _digest(point):
    return hashlib.sha256(json.dumps(point, sort_keys=True, default=str).encode()).hexdigest()


def evaluate_chunk(scene_name, solver_name, base, points, settings, what):
    """Runs in a worker: each point's label or value. `points` are {name: value} dicts laid
    over the `base` overrides; `what` is None (the regime) or an observable's name.

    A regime goes through the leaf's batch where it has one (`solvers.regimes`: the
    whole chunk in one call, the label decided inside it, no per-point Trajectory or file); a
    point it leaves out (a failed run) and every other solver or observable run one by one
    through `simulate`, models loaded and compiled once per worker, warmed up once per chunk.
    Measured (`xval bench rotor-spinup --points 10000`, 2 cores, runs minutes apart):
    quaternion 534 → 655, euler-vector 360 → 534 points/s, the kernel's integration
    ~97 % of a point's cost. Its loop is plain, one per worker: a prange kernel over both cores
    in a single worker gave 614 and 491. The engines (CPU per point of this chunk path over 40
    points of the bench grid, 2 busy cores): MuJoCo 93 → 45–49 ms (one rollout per point),
    Exudyn 384 → 111–122 ms (8 rotors per kinematic tree)."""
    sc, s = get_scene(scene_name), solvers.get_solver(solver_name)
    params = sc.resolve_many(base, points)
    return sc.either(time=_simulated_chunk, modes=_modes_chunk)(sc, s, params, settings, what)


def _modes_chunk(sc, s, params, settings, what):
    """A frequency scene's observable: one eigen-analysis a point."""
    return [_classify(sc, p, solvers.modes(sc, s, p), what) for p in params]


def _simulated_chunk(sc, s, params, settings, what):
    """A time scene's chunk: the regime batch where the leaf has one, else a run a point."""
    batch = solvers.regimes(sc, s, params, settings) if what is None else None
    labels, wall = batch or ([None] * len(params), 0.0)
    out, warm = [], True
    for p, label in zip(params, labels):
        if label is not None:
            out.append({"status": "ok", "wall_s": wall, "label": label, "value": None})
            continue
        tr = solvers.simulate(sc, s, p, settings, warm_up=warm)
        warm = False
        out.append(_classify(sc, p, tr, what))
    return out


def _classify(sc, params, tr, what):
    row = {"status": tr.status, "wall_s": tr.wall_s}
    if tr.status != "ok":
        row.update(label=tr.status, value=None, reason=tr.reason)
    elif what is None:
        row.update(label=sc.regime(params, tr), value=None)
    else:
        v = sc.map_observables[what][0](params, tr)
        row.update(label=NONE if v is None else "value", value=v)
    return row


class Runner:
    """Runs batches of (solver, settings, point) through the executor, chunked per solver so
    a worker reuses its loaded and compiled models; results are remembered by point (a point
    asked again, or already stored by a campaign under `store`, is not run again)."""

    def __init__(self, sc, base, what, executor=None, workers=2, store=None, log=None,
                 salt=None):
        self.sc, self.base, self.what, self.salt = sc, base, what, salt
        self.executor, self.workers = executor, workers
        self.store = Path(store) if store else None
        self.memo, self.log = {}, log or (lambda m: None)
        self.tight = {}                  # point key → "regime holds/flips at <settings>"
        self.runs, self.wall = {}, {}
        self.counter = None              # a compare.output.progress counter of the runs

    def _keys(self, tasks):
        """Each task's digest of {scene, base, solver, settings, point, what, salt}: the JSON
        `_digest` hashes, built from the parts shared by a batch serialised once (sorted keys,
        json's default separators: the same text, so the same digests as stored points have;
        serialising the whole dict per point was ~6 % of a 10,000-point map's wall time)."""
        def text(v):
            return json.dumps(v, sort_keys=True, default=str)
        head = {}
        out = []
        for solver, settings, pt in tasks:
            k = (solver, id(settings))
            if k not in head:
                head[k] = (settings, '{"base": ' + text(self.base) + ', "point": ',
                           ', "salt": ' + text(self.salt) + ', "scene": ' + text(self.sc.name)
                           + ', "settings": ' + text(settings) + ', "solver": ' + text(solver)
                           + ', "what": ' + text(self.what) + "}")
            _, a, b = head[k]
            out.append(hashlib.sha256((a + text(pt) + b).encode()).hexdigest())
        return out

    def _key(self, solver, settings, pt):
        return self._keys([(solver, settings, pt)])[0]

    def run(self, tasks):
        """tasks: [(solver, settings, point)] → the rows, in order."""
        todo, keys = {}, self._keys(tasks)
        for k, (solver, settings, pt) in zip(keys, tasks):
            if k in self.memo or k in todo:
                continue
            stored = self.store and self.store / f"{k}.json"
            if stored and stored.exists():
                self.memo[k] = {**json.loads(stored.read_text()), "reused": True}
                continue
            todo[k] = (solver, settings, pt)
        if self.counter is not None:         # the plan's estimate, raised where it falls short
            c = self.counter
            c.advance(0, total=max(c.total or 0, c.done + len(todo)))
        groups, texts = {}, {}
        for k, (solver, settings, pt) in todo.items():
            if id(settings) not in texts:          # one settings object serves a whole batch
                texts[id(settings)] = json.dumps(settings, sort_keys=True)
            groups.setdefault((solver, texts[id(settings)]), []).append((k, pt))
        calls, chunks = {}, {}
        for (solver, settings_text), items in groups.items():
            settings = json.loads(settings_text)
            # every chunk strided over the batch: a point's cost follows its place on the grid
            # (the rotor's low-eccentricity rows take 1.7× the steps), contiguous chunks left
            # one worker idle for ~12 % of a 10,000-point bench. At most CHUNK points a chunk,
            # so that a worker on a slower core takes fewer: two chunks a worker left the
            # other idle for 0.5–1.4 s of a 3–4 s bench (worker spans logged, same run)
            n = min(len(items), max(2 * self.workers, -(-len(items) // CHUNK)))
            for i in range(n):
                chunk = items[i::n]
                key = (solver, settings_text, i)
                chunks[key] = (solver, chunk)
                calls[key] = (evaluate_chunk, (self.sc.name, solver, self.base,
                                               [p for _, p in chunk], settings, self.what))
        for o in execute_many(calls, self.executor):
            if o.error is not None:
                raise o.error
            solver, chunk = chunks[o.key]
            # one core's time in the solver per point (compile time apart, as `simulate` has it)
            self.wall[solver] = self.wall.get(solver, 0.0) + sum(r["wall_s"] for r in o.value)
            self.runs[solver] = self.runs.get(solver, 0) + len(o.value)
            if self.counter is not None:
                self.counter.advance(len(o.value))
            for (k, _), row in zip(chunk, o.value):
                self.memo[k] = row
                if self.store:
                    store_point(self.store, k, row)
        return [self.memo[k] for k in keys]


# --- refinement ----------------------------------------------------------------------------

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


def _pt(x_name, x, y_name, y):
    pt = {x_name: float(x)}
    if y_name is not None:
        pt[y_name] = float(y)
    return pt


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


# --- error estimates and verdicts -------------------------------------------------------------

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


def readings(points, x_name, y_name, level=None):
    """Every run of the map as {solver: {row: [(x, label, status, reason)] sorted by x}}: what
    each solver read where, so a crossing without a counterpart can be judged against the other
    solver's own runs around it."""
    out = {}
    for p in points:
        if "regime" in p:
            label = p["regime"]
        else:
            v = p["value"]
            label = NONE if v is None else ("value" if level is None else
                                            "above" if v >= level else "below")
        row = p["params"].get(y_name) if y_name else None
        out.setdefault(p["solver"], {}).setdefault(row, []).append(
            (p["params"][x_name], label, p["status"], p.get("reason")))
    for rows in out.values():
        for r in rows.values():
            r.sort(key=lambda t: t[0])
    return out


def _failed(r):
    return f"{r[2]} at x = {r[0]:.6g}" + (f" ({r[3]})" if r[3] else "")


def _unmatched(c, a, b, seen):
    """A crossing of `a` with no crossing of the same regimes in `b` on its row: disagree
    (b's own runs around it read no such crossing), incomplete (a run on either side failed,
    or b ran nothing), or None (outside the region b mapped: not compared); with the line that
    says why."""
    what = f"{a}'s crossing {c['from']}→{c['to']} at x = {c['x']:.6g}{_row(c)}"
    if seen is None:                      # nothing known of the runs: b's rows are mapped
        return Verdict.DISAGREE, f"{what} has no counterpart in {b}"
    mine = [r for r in seen.get(a, {}).get(c["y"], []) if r[0] in c["bracket"] and r[2] != "ok"]
    if mine:
        return Verdict.INCOMPLETE, f"{what}: a failed run of {a}, no regime ({_failed(mine[0])})"
    if not seen.get(b):
        return Verdict.INCOMPLETE, f"{what}: {b} ran no points"
    rb = seen[b].get(c["y"], [])
    if not rb or not rb[0][0] <= c["x"] <= rb[-1][0]:
        return None, f"{what}: outside the region {b} mapped (not compared)"
    left = [r for r in rb if r[0] <= c["x"]][-1]
    right = next(r for r in rb if r[0] >= c["x"])
    bad = [r for r in (left, right) if r[2] != "ok"]
    if bad:
        return Verdict.INCOMPLETE, f"{what}: {b}'s run failed there ({_failed(bad[0])})"
    same = {r[1] for r in rb} == {left[1]}
    return Verdict.DISAGREE, (f"{what} has no counterpart in {b}: {b} reads {left[1]} at "
                   f"{left[0]:.6g} and {right[1]} at {right[0]:.6g}"
                   + (f" (and at all its {len(rb)} runs on the row, {rb[0][0]:.6g} to "
                      f"{rb[-1][0]:.6g})" if same else ""))


def _no_crossings(a, b, seen):
    """Neither solver finds a crossing: their regimes at the points both ran decide (None:
    nothing known of the runs)."""
    if seen is None:
        return None, "no crossing on a common row"
    for s in (a, b):
        if not seen.get(s):
            return Verdict.INCOMPLETE, f"{s} ran no points"
    ra = {(y, r[0]): r for y, rs in seen[a].items() for r in rs}
    common = [(ra[k], r) for y, rs in seen[b].items() for r in rs if (k := (y, r[0])) in ra]
    if not common:
        return (Verdict.INCOMPLETE,
                f"neither finds a crossing, and {a} and {b} ran no common point")
    for p, q in common:
        for s, r in ((a, p), (b, q)):
            if r[2] != "ok":
                return Verdict.INCOMPLETE, f"{s}'s run failed ({_failed(r)})"
    diff = [(p, q) for p, q in common if p[1] != q[1]]
    if diff:
        p, q = diff[0]
        return Verdict.DISAGREE, (f"neither finds a crossing, but at x = {p[0]:.6g} {a} reads "
                                  f"{p[1]} and {b} reads {q[1]} ({len(diff)} of {len(common)} "
                                  "common points differ)")
    labels = ", ".join(sorted({p[1] for p, _ in common}))
    return Verdict.AGREE, (f"neither finds a crossing; both read {labels} at all "
                           f"{len(common)} common points")


def compare_boundaries(boundaries, width, seen=None):
    """Per solver pair: each crossing of the first matched to the nearest of the second on the
    same row with the same regimes; `agree` when every matched distance is within
    width + both error estimates + both half-brackets; `unconfirmed` where a crossing within
    that vanishes at its solver's tighter setting (it has no error bar). A crossing of either
    with no counterpart is judged against the other's own runs around it (`seen`, from
    `readings`): `disagree` where they read no such crossing, `incomplete` where a run there
    failed or the other ran nothing; where neither finds a crossing, their regimes at the
    points both ran decide. Never silently dropped: every such crossing is in `why` and in
    `unmatched`. Worst first: disagree, incomplete, unconfirmed, agree; `no data` only where
    nothing could be compared (crossings outside the region the other mapped)."""
    names = list(boundaries)
    out = []
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            pairs, lines, unmatched, matched = [], [], [], 0
            for one, other in ((a, b), (b, a)):
                for ca in boundaries[one]:
                    cands = [cb for cb in boundaries[other] if cb["y"] == ca["y"]
                             and cb["from"] == ca["from"] and cb["to"] == ca["to"]]
                    if not cands:
                        got, line = _unmatched(ca, one, other, seen)
                        if got is not None:
                            pairs.append(got)
                        lines.append(line)
                        unmatched.append({"solver": one, "x": ca["x"], "y": ca["y"],
                                          "outcome": got or "outside"})
                        continue
                    if one == b:          # matched from a's side already
                        continue
                    matched += 1
                    cb = min(cands, key=lambda c: abs(c["x"] - ca["x"]))
                    d = abs(cb["x"] - ca["x"])
                    bound = (width + (ca.get("error") or 0) + (cb.get("error") or 0)
                             + 0.5 * (np.ptp(ca["bracket"]) + np.ptp(cb["bracket"])))
                    got = Verdict.AGREE if d <= bound * (1 + 1e-9) else Verdict.DISAGREE
                    if got == Verdict.AGREE and (ca.get("unconfirmed")
                                                 or cb.get("unconfirmed")):
                        got = Verdict.UNCONFIRMED
                        gone = ca if ca.get("unconfirmed") else cb
                        lines.append(f"{ca['from']}→{ca['to']}{_row(ca)}: unconfirmed — "
                                     f"{a if gone is ca else b}'s " + gone.get(
                                         "unconfirmed_why",
                                         "crossing vanishes at its tighter setting"))
                    pairs.append(got)
                    if got == Verdict.DISAGREE:
                        lines.append(f"{ca['from']}→{ca['to']}{_row(ca)}: {a} at "
                                     f"{ca['x']:.6g} {_bracket(ca)}, {b} at {cb['x']:.6g} "
                                     f"{_bracket(cb)}: {d:.3g} apart > {bound:.3g} "
                                     "(resolution + error estimates + half-brackets)")
            if not boundaries[a] and not boundaries[b]:
                got, line = _no_crossings(a, b, seen)
                if got is not None:
                    pairs.append(got)
                lines.append(line)
            verdict = Verdict.worst(pairs, default=Verdict.NO_DATA)
            why = lines or ([f"all {matched} crossings within resolution + error "
                             "estimates + half-brackets"] if pairs else ["nothing compared"])
            out.append({"a": a, "b": b, "verdict": verdict, "matched": matched, "why": why,
                        "unmatched": unmatched})
    return out


# what a map's pair can be, worst first (the status counts each)
MAP_VERDICTS = (Verdict.DISAGREE, Verdict.INCOMPLETE, Verdict.UNCONFIRMED, Verdict.NO_DATA,
                Verdict.AGREE)


def verdict_status(verdicts):
    """The map's status for a CI: counts per verdict, and the worst verdict over its pairs
    (`no comparison` for a map of one solver)."""
    n = Verdict.tally(x["verdict"] for x in verdicts)
    worst = Verdict.worst((x["verdict"] for x in verdicts), default="no comparison")
    return {"status": worst, "pairs": len(verdicts), **{v: n[v] for v in MAP_VERDICTS}}


def _row(c):
    return "" if c["y"] is None else f" (row {c['y']:.6g})"


def _bracket(c):
    e = c.get("error")
    return f"[{c['bracket'][0]:.6g}, {c['bracket'][1]:.6g}]" + (f" ± {e:.2g}" if e else "")


# --- the map -------------------------------------------------------------------------------

def estimate(sc, x_axis, y_axis, chosen, resolution, coarse, engines, params,
             y_resolution=None):
    """(runs, seconds) before anything runs: the coarse grid, ~log2 bisection rounds per row
    for a few crossings, the rows a boundary's tracing adds (~log2 halvings per gap), the
    engines' share, each run at its engine's measured cost."""
    nx, ny = coarse
    rows = ny if y_axis else 1
    rounds = max(1, math.ceil(math.log2(max(2.0, 1.0 / (resolution * (nx - 1))))))
    traced = ((ny - 1) * max(1, math.ceil(math.log2(max(2.0, 1.0 / (
        (y_resolution or resolution) * (ny - 1)))))) if y_axis else 0)
    per_custom = (nx + 2 * rounds + 4) * (rows + traced)
    per_engine = (nx * rows + 2 * rows * rounds) if engines == "everywhere" else 8 * rows
    samples = sc.samples_per_run(params)
    runs, secs = 0, 0.0
    for s in chosen:
        n = per_engine if is_engine(s) else per_custom
        runs += n
        secs += n * (COST_PER_SAMPLE.get(s.engine, 1e-4) * samples
                     + COST_PER_RUN.get(s.engine, 1e-3))
    return runs, secs


def plan_map(scene_name, x, y=None, overrides=None, solver_names=None, resolution=1e-3,
             coarse=None, observable=None, level=None, engines="boundary", max_jobs=None,
             y_resolution=None, max_rows=MAX_ROWS, adaptive=True):
    """Everything checked before a run (one line, BadInput): scene, axes, parameters,
    solvers, the work against the budget."""
    sc = get_scene(scene_name)
    if not sc.mappable:
        raise BadInput(f"scene {sc.name!r} is a frequency scene with no map observable: maps "
                       f"are of time scenes' regimes and of observables")
    if level is not None and observable is None:      # a level of which observable?
        raise BadInput(f"--level needs --observable NAME (of {sc.name}: "
                       f"{', '.join(sc.map_observables) or 'none'})")
    if observable is None and sc.regime is None and sc.map_observables:
        observable = next(iter(sc.map_observables))
    if observable is None and sc.regime is None:
        raise BadInput(f"scene {sc.name!r} declares no regime or map observable")
    if observable is not None and observable not in sc.map_observables:
        raise BadInput(f"--observable {observable}: not a map observable of {sc.name} "
                       f"(known: {', '.join(sc.map_observables) or 'none'})")
    if not (isinstance(resolution, (int, float)) and 0 < resolution < 0.5):
        raise BadInput(f"--resolution must be in (0, 0.5), got {resolution!r}")
    y_resolution = max(resolution, Y_RESOLUTION) if y_resolution is None else y_resolution
    if not (isinstance(y_resolution, (int, float)) and 0 < y_resolution < 0.5):
        raise BadInput(f"--y-resolution must be in (0, 0.5), got {y_resolution!r}")
    if engines not in ("boundary", "everywhere"):
        raise BadInput(f"--engines must be boundary or everywhere, got {engines!r}")
    x_axis = parse_axis(x, sc, "--x")
    y_axis = parse_axis(y, sc, "--y") if y else None
    if y_axis and y_axis.name == x_axis.name:
        raise BadInput("--y names the same parameter as --x")
    overrides = dict(overrides or {})
    for a in (x_axis, y_axis):
        if a and a.name in overrides:
            raise BadInput(f"--set {a.name}: it is an axis of the map")
    coarse = tuple(coarse) if isinstance(coarse, (list, tuple)) else (
        (coarse,) if coarse else ())
    if not all(isinstance(n, int) and not isinstance(n, bool) for n in coarse) \
            or len(coarse) > 2:
        raise BadInput(f"coarse grid: NX or (NX, NY) whole numbers, got {coarse!r}")
    coarse = (coarse + ((17,) if not coarse else ()) + (9 if y_axis else 1,))[:2]
    if not y_axis:
        coarse = (coarse[0], 1)
    if coarse[0] < 2 or (y_axis and coarse[1] < 2):
        raise BadInput("coarse grid: at least 2 points along each axis")
    # every solver's settings checked at the low corner; a run holds one solver's output
    pl = planner.plan(sc, {**overrides, x_axis.name: x_axis.lo,
                           **({y_axis.name: y_axis.lo} if y_axis else {})}, solver_names,
                      limits=planner.Limits(together=False))
    params, chosen = pl.params, list(pl.solvers)
    for corner in (x_axis.hi,):
        sc.resolve({**overrides, x_axis.name: corner})
    runs, secs = estimate(sc, x_axis, y_axis, chosen, resolution, coarse, engines, params,
                          y_resolution)
    limit = MAX_JOBS if max_jobs is None else max_jobs
    if runs > limit:
        raise BadInput(f"map of {sc.name}: ~{runs} runs (~{secs:.3g} s on one core) exceed the "
                       f"budget of {limit} runs: lower the resolution or the coarse grid, or "
                       f"pass --max-jobs")
    return {"scene": sc, "x": x_axis, "y": y_axis, "overrides": overrides, "chosen": chosen,
            "resolution": resolution, "coarse": coarse, "observable": observable,
            "level": level, "engines": engines, "estimate": {"runs": runs, "seconds": secs},
            "settings": pl.settings, "y_resolution": y_resolution, "max_rows": max_rows,
            "adaptive": bool(adaptive)}


def is_engine(s):
    return s.engine in ("exudyn", "mujoco")


def run_map(plan, settings_for=None, executor=None, workers=2, store=None, log=None,
            salt=None):
    """The map of a `plan_map` plan: points, each solver's crossings with error estimates,
    the pairwise verdicts, the work done. `settings_for(solver)` gives each solver's settings
    (default: its accurate defaults)."""
    log = log or (lambda m: None)
    sc, xa, ya = plan["scene"], plan["x"], plan["y"]
    what, level = plan["observable"], plan["level"]
    y_name = ya.name if ya else None
    nx, ny = plan["coarse"]
    width = plan["resolution"] * xa.span
    xs = np.linspace(xa.lo, xa.hi, nx)
    ys = np.linspace(ya.lo, ya.hi, ny) if ya else [None]
    coarse_step = xs[1] - xs[0]
    runner = Runner(sc, plan["overrides"], what, executor, workers, store, log, salt)
    runner.counter = progress.task(f"map {sc.name}", plan["estimate"]["runs"], "runs")
    settings = {s.name: (settings_for(s) if settings_for else plan["settings"][s.name])
                for s in plan["chosen"]}
    customs = [s for s in plan["chosen"] if not is_engine(s)]
    engines = [s for s in plan["chosen"] if is_engine(s)]
    everywhere = customs + (engines if plan["engines"] == "everywhere" else [])
    t0 = time.perf_counter()
    lines, found, unresolved = {}, {}, {}
    cheap_at = {}               # (solver, y, x) -> the cheap settings that point's label is from
    for s in everywhere:
        log(f"map {sc.name}: {s.name} on the {nx} × {len(ys)} coarse grid …")
        lines[s.name] = {None if y is None else float(y): {} for y in ys}
        cheap = (s.info(sc).cheaper(settings[s.name])
                 if what is None and plan.get("adaptive", True) else None)
        if what is None:
            grid = [[_pt(xa.name, float(x), y_name, y) for x in xs] for y in ys]
            labels, sure = adaptive_grid(runner, s.name, cheap, settings[s.name], grid)
            for y, row, ok in zip(ys, labels, sure):
                key = None if y is None else float(y)
                lines[s.name][key] = dict(zip(map(float, xs), row))
                for x, good in zip(xs, ok):
                    if not good:
                        cheap_at[(s.name, key, float(x))] = cheap
        else:
            grid = [(float(x), y) for y in ys for x in xs]
            rows = runner.run([(s.name, settings[s.name], _pt(xa.name, x, y_name, y))
                               for x, y in grid])
            for (x, y), r in zip(grid, rows):
                lines[s.name][None if y is None else float(y)][x] = r["value"]
        log(f"map {sc.name}: {s.name} refining …")
        if what is None:
            bisect_lines(runner, s.name, settings[s.name], lines[s.name], xa, width, y_name)
            if ya is not None:
                left = trace_rows(runner, s.name, settings[s.name], lines[s.name], xa, xs,
                                  width, y_name, plan["y_resolution"] * ya.span,
                                  plan["max_rows"])
                if left:
                    unresolved[s.name] = left
                    log(f"map {sc.name}: {s.name}: {len(left)} row gaps left unresolved "
                        f"(more than {plan['max_rows']} rows)")
        else:
            refine_observable(runner, s.name, settings[s.name], lines[s.name], xa, width,
                              level, y_name)
    ref = next(iter(customs), None)
    for s in engines:
        if s in everywhere:
            continue
        if ref is None:
            raise BadInput("--engines boundary needs a custom solver to find the boundary "
                           "first (or pass --engines everywhere)")
        log(f"map {sc.name}: {s.name} from {ref.name}'s brackets …")
        coarse_rows = {None if y is None else float(y) for y in ys}
        ref_found = [c for c in (crossings(lines[ref.name], xa, ya) if what is None
                                 else level_crossings(lines[ref.name], level))
                     if c["y"] in coarse_rows]
        if what is None:
            lines[s.name] = refine_engine(runner, s.name, settings[s.name], ref_found, xa,
                                          width, coarse_step, y_name)
        else:
            lines[s.name] = _observable_at(runner, s.name, settings[s.name], ref_found, xa,
                                           y_name)
    for s in plan["chosen"]:
        found[s.name] = (crossings(lines[s.name], xa, ya) if what is None
                         else level_crossings(lines[s.name], level))
        if what is None and found[s.name]:
            tight, _, _ = solvers.tighter_settings(s.info(sc), settings[s.name])
            tight = tight and s.info(sc).refined(tight)     # every knob tighter, not dt alone
            crossing_errors(runner, s.name, settings[s.name], tight, lines[s.name],
                            found[s.name], xa, width, y_name)
    wall = time.perf_counter() - t0
    slopes = {}                          # an observable's slope over each line's first step
    if what is not None:
        for name, ls in lines.items():
            for y, pts in ls.items():
                xs = [x for x in sorted(pts) if pts[x] is not None][:2]
                if len(xs) == 2:
                    slopes.setdefault(name, []).append(
                        {"y": y, "at": xs[0], "slope": (pts[xs[1]] - pts[xs[0]])
                         / (xs[1] - xs[0])})
    uniform = (int(round(1 / plan["resolution"])) + 1) * len(ys)
    points = []
    for s, ls in lines.items():
        for y, pts in ls.items():
            for x, v in sorted(pts.items()):
                pt = _pt(xa.name, x, y_name, y)
                st = cheap_at.get((s, y, x), settings[s])
                row = runner.memo[runner._key(s, st, pt)]
                tight = runner.tight.get(runner._key(s, st, pt))
                points.append({"solver": s, "params": pt,
                               ("regime" if what is None else "value"): v,
                               "status": row["status"], "reason": row.get("reason"),
                               "settings": "cheap" if (s, y, x) in cheap_at else "accurate",
                               # the point's own check: its regime rerun at tighter settings
                               # (points bracketing a crossing); None where not rerun
                               "error_estimate": tight})
    verdicts = compare_boundaries(found, width, readings(points, xa.name, y_name, level))
    for p in points:                     # contract.md: every point has both (one is None)
        p.setdefault("regime", None)
        p.setdefault("value", None)
    per_solver = {s: runner.runs[s] / runner.wall[s] for s in runner.runs if runner.wall.get(s)}
    runner.counter.close()
    return {"scene": sc.name, "x": xa.as_dict(), "y": ya.as_dict() if ya else None,
            "set": plan["overrides"], "observable": what, "level": level,
            "resolution": plan["resolution"], "bracket_width": width,
            "y_resolution": plan["y_resolution"] if ya else None,
            # rows per solver: the coarse grid's and those the boundary's tracing added
            "rows": {s: len(ls) for s, ls in lines.items()},
            # per solver: points whose label stands at the cheap level (its settings) and runs
            # at the accurate one (the coarse grid's points next to a change, every bisection)
            "levels": {s: {"cheap": sum(1 for k in cheap_at if k[0] == s),
                           "cheap_settings": next((v for k, v in cheap_at.items()
                                                   if k[0] == s), None),
                           "accurate": sum(1 for p in points if p["solver"] == s)
                           - sum(1 for k in cheap_at if k[0] == s)} for s in lines},
            "unresolved_rows": unresolved,
            "coarse": list(plan["coarse"]), "engines": plan["engines"],
            "settings": settings, "estimate": plan["estimate"],
            "points": points, "boundaries": found,
            "verdicts": verdicts, "comparisons": verdicts,     # contract.md's name
            "status": verdict_status(verdicts),
            "value_deviation": _value_deviation(lines) if what is not None else [],
            "slope_at_lo": slopes,
            "runs": dict(runner.runs), "uniform_grid_runs": uniform,
            "run_wall_s": dict(runner.wall), "wall_s": wall,
            # per solver: points per second of its own run time (contract.md's points_per_s)
            "points_per_core_second": per_solver, "points_per_s": per_solver,
            "points_per_second": sum(runner.runs.values()) / wall if wall > 0 else None,
            "reused": sum(1 for r in runner.memo.values() if r.get("reused"))}


def _value_deviation(lines):
    """An observable's largest difference between two solvers over the points both ran."""
    names, out = list(lines), []
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            d = [abs(lines[a][y][x] - lines[b][y][x]) for y in lines[a] if y in lines[b]
                 for x in lines[a][y] if x in lines[b][y]
                 and lines[a][y][x] is not None and lines[b][y][x] is not None]
            if d:
                out.append({"a": a, "b": b, "points": len(d), "max_abs": max(d)})
    return out


def _observable_at(runner, solver, settings, ref_found, xa, y_name):
    """An engine's observable at the reference's level-crossing brackets."""
    lines = {}
    for c in ref_found:
        rows = runner.run([(solver, settings, _pt(xa.name, x, y_name, c["y"]))
                           for x in c["bracket"]])
        for x, r in zip(c["bracket"], rows):
            lines.setdefault(c["y"], {})[x] = r["value"]
    return lines


def map_dir(root, scene_name):
    """The default map folder (no --out): ROOT/maps/<scene>-<stamp>-<pid>, not made here."""
    stamp = datetime.datetime.now().strftime("%Y%m%d-%H%M%S")
    return Path(root) / "maps" / f"{scene_name}-{stamp}-{os.getpid()}"


def map_to_folder(plan, out, settings_for=None, executor="local", scheduler=None, workers=None,
                  store=None, record=True, log=None, out_dir=None, salt=None):
    """Run a planned map with the campaign's executors (process pool or Dask) into the folder
    `out` (or `out_dir`): map.json, map.png, report.md, map.rrd."""
    from ..output.map_plot import write_map_outputs
    out_dir = Path(out_dir or out)
    out_dir.mkdir(parents=True, exist_ok=True)
    workers = workers or 2
    if store is not None and salt is None:       # stored points are valid while these hold
        sc = plan["scene"]
        salt = {"store": STORE_VERSION, "code": job_code(sc, plan["chosen"]),
                "versions": {s.name: solvers.versions(s) for s in plan["chosen"]}}
    try:
        with worker_pool(executor, scheduler, workers, in_process_if_unguarded=True) as pool:
            result = run_map(plan, settings_for, pool, workers, store, log, salt)
    except KeyboardInterrupt:
        n = len(list(Path(store).glob("*.json"))) if store else 0
        raise Interrupted(f"{n} map points are stored in {store} and will be reused"
                          if store else "map stopped") from None
    result["folder"], result["result"] = str(out_dir), MapResult.TYPE
    return write_map_outputs(out_dir, result, record)


def throughput(scene_name, solver_names, overrides, n_points, workers=2, log=None):
    """Points per second of each solver over `n_points` of the scene's first default map
    (a grid over its axes), through the map's own batch path: the worker pool warmed up first
    (models loaded and compiled in every worker), then the points timed, one solver at a
    time (`xval bench SCENE --points N`) — at the accurate setting everywhere, and (regimes,
    error-controlled solvers) accuracy-adaptive as a map runs them (`adaptive_grid`): the
    points rerun, and the labels that differ from the all-accurate grid (the boundary's shift:
    0 where none do)."""
    sc = get_scene(scene_name)
    if not sc.maps:
        raise BadInput(f"--points: scene {sc.name!r} declares no map to take points from")
    spec = sc.maps[0]
    base = {**spec.set, **(overrides or {})}
    plan = plan_map(sc.name, spec.x, spec.y, base, solver_names, coarse=(2, 2) if spec.y
                    else (2, 1), observable=spec.observable, max_jobs=None)
    xa, ya = plan["x"], plan["y"]
    nx = max(2, int(round(math.sqrt(n_points)))) if ya else n_points
    ny = max(1, int(math.ceil(n_points / nx))) if ya else 1
    ys = np.linspace(ya.lo, ya.hi, ny) if ya else [None]
    grid = [[_pt(xa.name, x, ya.name if ya else None, y) for x in np.linspace(xa.lo, xa.hi, nx)]
            for y in ys]
    left = n_points                       # the last row cut to n_points in all
    for row in grid:
        del row[max(left, 0):]
        left -= len(row)
    grid = [row for row in grid if row]
    pts = [p for row in grid for p in row]
    rows, say = [], log or (lambda m: None)

    def timed(st, adaptive=None):
        runner = Runner(sc, base, spec.observable, pool, workers)
        runner.run([(s.name, x, p) for x in (st, adaptive) if x for p in pts[:2 * workers]])
        runner = Runner(sc, base, spec.observable, pool, workers)     # warm-up above
        t0 = time.perf_counter()
        if adaptive:
            labels, sure = adaptive_grid(runner, s.name, adaptive, st, grid)
            got = ([x for r in labels for x in r], sum(map(sum, sure)))
        else:
            got = ([r["label"] for r in runner.run([(s.name, st, p) for p in pts])], len(pts))
        return got, time.perf_counter() - t0, sum(runner.wall.values())

    with worker_pool("local", None, workers) as pool:
        for s in plan["chosen"]:
            st = plan["settings"][s.name]
            (labels, _), wall, core = timed(st)
            row = {"solver": s.name, "points": len(pts), "wall_s": wall,
                   "points_per_second": len(pts) / wall,
                   "points_per_core_second": len(pts) / core, "settings": st,
                   "accurate_points_per_second": len(pts) / wall}
            cheap = s.info(sc).cheaper(st) if spec.observable is None else None
            if cheap:
                (fast, accurate), wall, core = timed(st, cheap)
                row.update(wall_s=wall, points_per_second=len(pts) / wall,
                           points_per_core_second=len(pts) / core, cheap_settings=cheap,
                           rerun_fraction=accurate / len(pts),
                           labels_differ=sum(a != b for a, b in zip(fast, labels)))
            rows.append(row)
            say(f"{s.name}: {len(pts)} points in {row['wall_s']:.3g} s, "
                f"{row['points_per_second']:.0f} points/s"
                + (f" (accurate everywhere {row['accurate_points_per_second']:.0f}; "
                   f"{row['rerun_fraction']:.1%} rerun accurate, "
                   f"{row['labels_differ']} labels differ)" if cheap else ""))
    return {"scene": sc.name, "map": spec.name, "x": xa.as_dict(),
            "y": ya.as_dict() if ya else None, "set": base, "workers": workers, "rows": rows}
