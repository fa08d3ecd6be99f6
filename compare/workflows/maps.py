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

This module runs a planned map (`run_map`, `map_to_folder`, `throughput`) and re-exports its
parts: the plan (map_plan.py: axes, estimate, `plan_map`'s checks), the runs (map_run.py:
`evaluate_chunk`, `Runner`), the refinement (map_trace.py: bisection, the adaptive grid, row
tracing, crossings and their error estimates) and the verdicts (map_verdicts.py).
"""
from __future__ import annotations

import datetime
import math
import os
import time
from pathlib import Path

import numpy as np

from .. import solvers
from ..errors import BadInput
from ..output import progress
from ..results import MapResult
from ..scenes import get_scene
from .digest import STORE_VERSION, job_code
from .executors import Interrupted, worker_pool

# the map's parts, re-exported: callers and tests import them from here
from .map_plan import (  # noqa: F401
    COST_PER_RUN,
    COST_PER_SAMPLE,
    MAX_JOBS,
    MAX_ROWS,
    Y_RESOLUTION,
    Axis,
    estimate,
    is_engine,
    parse_axis,
    plan_map,
)
from .map_run import CHUNK, NONE, Runner, _digest, _pt, evaluate_chunk  # noqa: F401
from .map_trace import (  # noqa: F401
    _fill,
    adaptive_grid,
    bisect_lines,
    crossing_errors,
    crossings,
    level_crossings,
    refine_engine,
    refine_observable,
    trace_rows,
)
from .map_verdicts import MAP_VERDICTS, compare_boundaries, readings, verdict_status  # noqa: F401


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
    result = compute_map(plan, settings_for, executor, scheduler, workers, store, log, salt)
    result["folder"] = str(out_dir)
    return write_map_outputs(out_dir, result, record)


def compute_map(plan, settings_for=None, executor="local", scheduler=None, workers=None,
                store=None, log=None, salt=None) -> dict:
    """Run a planned map with the campaign's executors (process pool or Dask): the map's JSON,
    held in memory (`store`: where its points are kept for a rerun to reuse, if anywhere)."""
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
    result["result"] = MapResult.TYPE
    return result


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
