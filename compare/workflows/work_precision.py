"""The work-precision machinery both benches share (time scenes: `bench`, frequency scenes:
`bench_modes`): walking a ladder of accuracy settings, timing a rung, the summary per error
level, observed convergence orders (the figure and the bench folder's files:
compare/output/bench_report.py)."""
import datetime
from pathlib import Path

import numpy as np

from ..output.bench_report import LEVELS  # the summary's error levels, the figure's

COARSE_ERR = 1e-2          # the coarse end of a ladder: this error reached (or a failed run)
FLOOR_ERR = 1e-12          # the fine end: below this the reference cannot tell rungs apart
RUNG_WALL_S = 3.0          # nor walk finer once one run of a rung takes this long
SHORT_RUN_S, SHORT_REPEATS = 0.05, 5     # runs this short are timed 5 × `repeats` times
ORDER_RUNGS = 4            # the observed order is fitted on this many finest rungs


def walk(rungs, start, run, exhaustive=False, patience=2):
    """Run rungs[start], then coarser ones until the error reaches COARSE_ERR or a run fails,
    then finer ones until the floor: the error at or below FLOOR_ERR, no longer falling
    (`patience` rungs in a row each less than 2× better), a run slower than RUNG_WALL_S, or a
    rung refused (bad settings or over the step budget). `run(i)` returns the row (None when
    refused)."""
    if exhaustive:
        return [r for r in map(run, range(len(rungs))) if r is not None]
    rows = {}
    for i in range(start, -1, -1):                       # the start, then coarser
        r = rows[i] = run(i)
        if r is None or r["rel_error"] is None or r["rel_error"] >= COARSE_ERR:
            break
    stall, prev = 0, rows.get(start)
    for i in range(start + 1, len(rungs)):               # finer
        if prev is None or (prev["rel_error"] is not None and prev["rel_error"] <= FLOOR_ERR) \
                or prev["wall_s"] > RUNG_WALL_S or stall >= patience:
            break
        r = rows[i] = run(i)
        if r is None:
            break
        if r["rel_error"] is not None and prev["rel_error"] is not None:
            stall = stall + 1 if r["rel_error"] > 0.5 * prev["rel_error"] else 0
        prev = r
    return [rows[i] for i in sorted(rows) if rows[i] is not None]


def repeat_timed(walls, again, repeats):
    """Append the wall times of `again()` runs to `walls` until the rung has `repeats` of them
    (SHORT_REPEATS × as many when the first took under SHORT_RUN_S: one scheduler hiccup would
    be its whole time; one run only when the first took over RUNG_WALL_S). Returns the last
    result (None when none was needed)."""
    last = None
    while len(walls) < repeats * (SHORT_REPEATS if walls and walls[0] < SHORT_RUN_S else 1) \
            and not (walls and walls[0] > RUNG_WALL_S):
        last = again()
        walls.append(last.wall_s)
    return last


def summarise(rows, solver_names, what, unreached_why=None, describe=None):
    """For each error level: the fastest solver's row and every other solver's time ratio to
    it (each solver at its fastest row within the level), and the summary lines. `what` says
    which error (e.g. "on final omega"); `unreached_why` (solver -> reason) explains a solver
    that reaches no row within a level; `describe(row)` names the fastest rung (default: its
    method)."""
    summary, lines = {}, []
    for level in LEVELS:
        best = {}
        for r in rows:
            if r["rel_error"] is not None and r["rel_error"] <= level:
                if r["solver"] not in best or r["wall_s"] < best[r["solver"]]["wall_s"]:
                    best[r["solver"]] = r
        if not best:
            continue
        fastest = min(best.values(), key=lambda r: r["wall_s"])
        ratios = {s: r["wall_s"] / fastest["wall_s"] for s, r in best.items()}
        unreached = [s for s in solver_names if s not in best]
        summary[f"{level:g}"] = {"fastest": fastest["solver"], "method": fastest["method"],
                                 "wall_s": fastest["wall_s"], "rel_error": fastest["rel_error"],
                                 "settings": fastest["settings"], "time_ratio": ratios,
                                 "unreached": unreached}
        why = unreached_why or {}
        lines.append(f"error ≤ {level:g} {what}: fastest {fastest['solver']} "
                     f"({(describe or (lambda r: r['method']))(fastest)}, "
                     f"{fastest['wall_s']:.3g} s); ratios "
                     + ", ".join(f"{s} {v:.2f}×" for s, v in sorted(ratios.items(),
                                                                   key=lambda x: x[1]))
                     + ("; not reached by " + ", ".join(
                         s + (f" ({why[s]})" if why.get(s) else "") for s in unreached)
                        if unreached else ""))
    return summary, lines


def convergence_orders(rows, low, step, expected):
    """Observed order of each ladder with a step: the least-squares slope of log(error) over
    log(step(row)) on its finest rungs (up to ORDER_RUNGS) above the floor `low` and below
    COARSE_ERR (coarse rungs can be pre-asymptotic), less the floor where the error stops
    falling (a model's own error) — flagged when it falls short of
    `expected(row)` (the method's order, None: unknown) by more than 0.5."""
    out = []
    for (s, m) in dict.fromkeys((r["solver"], r["method"]) for r in rows):
        mine = [r for r in rows if r["solver"] == s and r["method"] == m]
        pts = sorted(((step(r), r["rel_error"]) for r in mine if r["rel_error"]
                      and step(r) is not None and low < r["rel_error"] < COARSE_ERR),
                     reverse=True)
        # coarse → fine: where the error stops falling it sits on a floor of the model (e.g.
        # the paper's finite differences), not of the method; the order is read from
        # error − floor on the rungs well above it
        if any(pts[i][1] > pts[i - 1][1] / 1.5 for i in range(1, len(pts))):
            floor = min(e for _, e in pts)
            pts = [(h, e - floor) for h, e in pts if e > 3 * floor]
        pts = sorted(pts)[:ORDER_RUNGS]
        if len(pts) < 2:
            continue
        x, y = np.log(np.array(pts)).T
        slope = float(np.polyfit(x, y, 1)[0]) if np.ptp(x) > 0 else float("nan")
        order = expected(mine[0])
        out.append({"solver": s, "method": m, "observed": slope, "expected": order,
                    "rungs": len(pts), "dt_range": [pts[0][0], pts[-1][0]],
                    "flag": bool(order is not None and slope < order - 0.5)})
    return out


def order_lines(orders, step_name, unit):
    return [f"order {o['solver']} {o['method']}: observed {o['observed']:.2f} "
            f"(method {o['expected'] if o['expected'] else '?'}, {o['rungs']} rungs, "
            f"{step_name} {o['dt_range'][0]:.3g}–{o['dt_range'][1]:.3g}{unit})"
            + (" — FLAG: below the method's order" if o["flag"] else "") for o in orders]


def new_bench_dir(root, scene_name):
    """The default bench folder (no --out): ROOT/bench/SCENE-YYYYmmdd-HHMMSS, not made here."""
    stamp = datetime.datetime.now().strftime("%Y%m%d-%H%M%S")
    return Path(root) / "bench" / f"{scene_name}-{stamp}"
