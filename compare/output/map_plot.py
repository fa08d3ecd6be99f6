"""A map's files: map.png (regions by regime or observable, each solver's boundary in the
plots' colours, the runs as dots), the Markdown section, and map.rrd (points per solver, each
boundary as line strips)."""
import numpy as np

from ..analysis.verdict import Verdict
from ..atomic import atomic_path, write_json, write_text
from .recording import APPLICATION_ID, PALETTE
from .report import header_lines, params_title, plot_style, save_figure

REGIME_COLOURS = ("#d9d9d9", "#a6cee3", "#fdbf6f", "#b2df8a", "#fb9a99", "#cab2d6")


def _labels(result):
    key = "regime" if result["observable"] is None else "value"
    return key, sorted({str(p[key]) for p in result["points"]})


def _colour(i):
    return PALETTE[i % len(PALETTE)]


def _hex(c):
    return c if isinstance(c, str) else "#" + "".join(f"{int(v):02x}" for v in c[:3])


def status_line(result) -> str:
    """The map's verdicts in one line: how many solver pairs agree, every other verdict
    counted (a `--strict` run fails on any of them)."""
    st = result.get("status") or {}
    others = [f"{st[k]} {k}" for k in Verdict.by_rank() if k != Verdict.AGREE and st.get(k)]
    return (f"map {result['scene']}: {st.get(Verdict.AGREE, 0)} of {st.get('pairs', 0)} solver "
            "pairs agree" + (f"; {', '.join(others)}" if others else "")
            + f" (status: {st.get('status', '—')})")


def _segments(crossings, points, y):
    """Lines only between computed rows: the k-th crossings of two neighbouring rows of the
    solver (rows it ran, crossing or not) when both have as many; nothing across a row
    without a crossing or with a different count — only what was computed is drawn."""
    rows = sorted({p["params"][y["name"]] for p in points})
    by_row = {}
    for c in crossings:
        by_row.setdefault(c["y"], []).append(c["x"])
    out = []
    for a, b in zip(rows, rows[1:]):
        xa, xb = sorted(by_row.get(a, [])), sorted(by_row.get(b, []))
        if xa and len(xa) == len(xb):
            out += [([p, q], [a, b]) for p, q in zip(xa, xb)]
    return out


def plot_map(path, result):
    plt = plot_style()
    x, y = result["x"], result["y"]
    solvers = list(result["runs"]) or list(result["boundaries"])
    fig, ax = plt.subplots(figsize=(7.5, 4.8))
    key, labels = _labels(result)
    first = solvers[0] if solvers else None
    pts = [p for p in result["points"] if p["solver"] == first]
    px = np.array([p["params"][x["name"]] for p in pts])
    py = (np.array([p["params"][y["name"]] for p in pts]) if y
          else np.zeros(len(pts)))
    if key == "regime":              # regions: each run of the first solver as its regime
        for i, lab in enumerate(labels):
            m = np.array([str(p["regime"]) == lab for p in pts])
            if m.any():
                ax.scatter(px[m], py[m], s=60, marker="s", color=REGIME_COLOURS[
                    i % len(REGIME_COLOURS)], label=f"{lab} ({first})", zorder=1)
    else:
        vals = np.array([np.nan if p["value"] is None else p["value"] for p in pts])
        sc = ax.scatter(px, py, c=vals, s=60, marker="s", cmap="viridis", zorder=1)
        fig.colorbar(sc, ax=ax, label=result["observable"])
    for i, s in enumerate(solvers):
        col = _hex(_colour(i))
        mine = [p for p in result["points"] if p["solver"] == s]
        ax.plot([p["params"][x["name"]] for p in mine],
                [p["params"][y["name"]] if y else 0.0 for p in mine], ".", ms=2.5, color=col,
                zorder=2)
        b = result["boundaries"].get(s, [])
        if b:
            # later solvers smaller and dashed: boundaries that agree stay visible together
            style = dict(ms=max(3, 10 - 2.5 * i), mew=2, lw=max(0.8, 2.5 - 0.6 * i),
                         color=col, zorder=3 + i)
            ax.plot([c["x"] for c in b], [c["y"] if y else 0.0 for c in b],
                    "o" if y else "|", ls="none", label=f"{s} boundary", **style)
            for seg in _segments(b, mine, y) if y else ():
                ax.plot(*seg, ls="-" if i == 0 else "--", **style)
        else:                       # in the legend all the same: a missing boundary shows
            ax.plot([], [], "|", color=col, label=f"{s}: no crossing")
    # crossings without a counterpart in another solver: a disagreement or a gap, never hidden
    for outcome, mark, col in ((Verdict.DISAGREE, "X", "#d62728"),
                               (Verdict.INCOMPLETE, "X", "#ff7f0e")):
        miss = [u for v in result.get("verdicts", []) for u in v.get("unmatched", [])
                if u["outcome"] == outcome]
        if miss:
            ax.plot([u["x"] for u in miss], [u["y"] if y else 0.0 for u in miss], mark,
                    ms=11, color=col, mec="k", ls="none", zorder=10,
                    label=f"no counterpart ({outcome})")
    ax.set_xlabel(f"{x['name']} [{x['unit']}]")
    ax.set_ylabel(f"{y['name']} [{y['unit']}]" if y else "")
    if not y:
        ax.set_yticks([])
    from ..scenes import get_scene
    fixed = params_title(get_scene(result["scene"]), result.get("set"))
    ax.set_title(f"map: {result['scene']}{fixed}"
                 + (f" — {result['observable']}" if result["observable"] else " — regimes")
                 + (f"\n{status_line(result)}" if result.get("status") else ""), fontsize=9)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=7, loc="best")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    save_figure(fig, path)


def markdown(result):
    x, y = result["x"], result["y"]
    md = [f"## Map: {result['scene']} over {x['name']}" + (f" × {y['name']}" if y else ""),
          "", f"{x['name']} ∈ [{x['lo']:g}, {x['hi']:g}] {x['unit']}"
          + (f", {y['name']} ∈ [{y['lo']:g}, {y['hi']:g}] {y['unit']}" if y else "")
          + f"; brackets ≤ {result['bracket_width']:.3g} {x['unit']} (resolution "
          f"{result['resolution']:g} of the range); coarse grid {result['coarse']}; "
          f"set {result['set'] or '—'}.", "",
          "| solver | runs | uniform grid | points / core-s |", "|---|---|---|---|"]
    for s, n in result["runs"].items():
        pps = result["points_per_core_second"].get(s)
        md.append(f"| {s} | {n} | {result['uniform_grid_runs']} | "
                  f"{'—' if pps is None else f'{pps:.0f}'} |")
    if result.get("slope_at_lo"):
        md += ["", f"Slope of {result['observable']} at the low end of {x['name']}: "
               + "; ".join(f"{s} {d['slope']:.8g}" for s, ds in result["slope_at_lo"].items()
                           for d in ds[:1]) + " (first step of each solver's first line)."]
    for v in result.get("value_deviation", []):
        md.append(f"- {v['a']} ~ {v['b']}: largest |Δ {result['observable']}| "
                  f"{v['max_abs']:.3g} over {v['points']} common points")
    if any(result["boundaries"].values()):
        md += ["", "| solver | row | from → to | crossing | bracket | error estimate | "
               "regime holds at tighter settings |", "|---|---|---|---|---|---|---|"]
    for s, cs in result["boundaries"].items():
        for c in cs:
            e, row = c.get("error"), c["y"]
            md.append(f"| {s} | {'—' if row is None else f'{row:.6g}'} | "
                      f"{c['from']} → {c['to']} | {c['x']:.6g} | [{c['bracket'][0]:.6g}, "
                      f"{c['bracket'][1]:.6g}] | {'—' if e is None else f'{e:.2g}'} | "
                      f"{ {True: 'yes', False: 'no', None: '—'}[c.get('holds')] } |")
    verdicts = result["verdicts"]
    if verdicts:
        md += ["", f"**{status_line(result)}**", "", "| pair | verdict | why |",
               "|---|---|---|"]
        for v in verdicts:
            md.append(f"| {v['a']} ~ {v['b']} | {v['verdict']} | {'; '.join(v['why'])} |")
    md += ["", "![map](map.png)", ""]
    return md


def write_map_recording(path, result):
    """Points per solver (coloured by regime index or value) and each boundary as a strip."""
    import rerun as rr
    x, y = result["x"], result["y"]
    key, labels = _labels(result)
    with atomic_path(path) as tmp, \
            rr.RecordingStream(APPLICATION_ID, recording_id=f"map-{path.parent.name}") as rec:
        rec.save(str(tmp))
        for i, s in enumerate(result["runs"] or result["boundaries"]):
            mine = [p for p in result["points"] if p["solver"] == s]
            pos = [[p["params"][x["name"]], p["params"][y["name"]] if y else 0.0, 0.0]
                   for p in mine]
            if pos:
                rec.log(f"map/{s}/points", rr.Points3D(
                    pos, colors=[_colour(i)] * len(pos), radii=0.004 * (x["hi"] - x["lo"]),
                    labels=[str(p[key]) for p in mine]), static=True)
            b = result["boundaries"].get(s, [])
            if b:
                strip = [[c["x"], c["y"] if y else 0.0, 0.0] for c in b]
                rec.log(f"map/{s}/boundary", rr.LineStrips3D([strip], colors=[_colour(i)]),
                        static=True)
    return path


def write_map_outputs(out_dir, result, record=True):
    """map.png, report.md (the map section), map.rrd and, last, map.json (the result dict with
    these files in "files" and "map") in `out_dir` (made if missing); returns the result dict."""
    out_dir.mkdir(parents=True, exist_ok=True)
    plot_map(out_dir / "map.png", result)
    from ..scenes import get_scene
    head = header_lines(get_scene(result["scene"]), result.get("set"))
    write_text(out_dir / "report.md", "\n".join([f"# Map: {result['scene']}", "", *head]
                                                 + markdown(result)[2:]) + "\n")
    files = {"plot": str(out_dir / "map.png"), "report": str(out_dir / "report.md")}
    if record:
        files["recording"] = str(write_map_recording(out_dir / "map.rrd", result))
    result["files"], result["map"] = files, files["plot"]
    write_json(out_dir / "map.json", result)
    return result
