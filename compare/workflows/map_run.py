"""A map's runs: `evaluate_chunk` (a worker's chunk of points → labels or values; workers
import it by this module path), `Runner` (batches chunked per solver, remembered by point and
reused from a store) and the point dict `_pt` every refinement builds."""
from __future__ import annotations

import hashlib
import json
from pathlib import Path

from .. import solvers
from ..output.store import store_point
from ..scenes import get_scene
from .executors import execute_many

NONE = "none"                     # an observable's label where its event did not happen
# a chunk's most points: ~0.1 s of a cheap rotor point's work on one core, ~1 % of it spent
# draining the lanes at the chunk's end and on the call
CHUNK = 256


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


def _pt(x_name, x, y_name, y):
    pt = {x_name: float(x)}
    if y_name is not None:
        pt[y_name] = float(y)
    return pt
