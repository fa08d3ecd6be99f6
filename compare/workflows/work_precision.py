"""The work-precision machinery both benches share (time scenes: `bench`, frequency scenes:
`bench_modes`): walking a ladder of accuracy settings, timing a rung, the summary per error
level, observed convergence orders, the figure and the bench folder's files."""
import datetime
from pathlib import Path

import numpy as np

from ..output.report import plot_style, save_figure
from ..output.study import write_study
from ..results import BenchResult

LEVELS = (1e-3, 1e-6, 1e-9)
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


def write_outputs(out_dir, obj, md):
    """report.md (the figure linked at its end) and bench.json; the result with its report."""
    obj["result"] = BenchResult.TYPE
    md = md + ["", "![work-precision](work_precision.png)"]
    return write_study(out_dir, md, obj, "bench.json", report_in_json=False)


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


def bench_dir(out):
    """The bench's folder: `out` itself (--out names the result's folder), made if missing."""
    out_dir = Path(out)
    out_dir.mkdir(parents=True, exist_ok=True)
    return out_dir


def plot(path, rows, scene, ylabel, summary=None):
    """The work-precision figure: error over median wall time per ladder, the summary levels
    and each level's fastest rung starred."""
    plt = plot_style()
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for (s, m) in dict.fromkeys((r["solver"], r["method"]) for r in rows):
        pts = [(r["wall_s"], r["rel_error"]) for r in rows
               if r["solver"] == s and r["method"] == m and r["rel_error"]]
        if pts:
            x, y = zip(*pts)             # ladder order: coarse → fine
            ax.loglog(x, y, "o-", ms=4, label=f"{s} {m}")
    for level in LEVELS:
        ax.axhline(level, color="grey", lw=0.6, ls=":")
        best = (summary or {}).get(f"{level:g}")
        if best:       # the level's fastest solver: a star at its rung, named
            ax.plot(best["wall_s"], best["rel_error"], "*", ms=12, color="black", zorder=5)
            ax.annotate(f"≤ {level:g}: {best['fastest']} {best['method']}",
                        (best["wall_s"], level), textcoords="offset points", xytext=(4, 3),
                        fontsize=7)
    ax.set_xlabel("median wall time [s]")
    ax.set_ylabel(ylabel)
    ax.set_title(f"work-precision: {scene}")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7)
    # log axes spanning less than a decade get minor labels that overlap: major decades only,
    # and plain numbers where the span is short
    from matplotlib.ticker import LogLocator, NullFormatter
    for axis in (ax.xaxis, ax.yaxis):
        axis.set_major_locator(LogLocator(base=10, numticks=8))
        axis.set_minor_formatter(NullFormatter())
    fig.tight_layout()
    save_figure(fig, path)
