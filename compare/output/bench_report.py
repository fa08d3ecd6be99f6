"""`xval bench`'s folder: report.md, bench.json and the work-precision figure of the time
bench, the frequency bench and the throughput bench (the numbers from compare/workflows/bench.py
and bench_modes.py; the caller sets `obj["result"]`)."""
from __future__ import annotations

from pathlib import Path

from .report import fmt_value, plot_style, save_figure
from .study import write_study

LEVELS = (1e-3, 1e-6, 1e-9)        # the summary's error levels (workflows/work_precision.py)
FIGURE = "work_precision.png"


def bench_dir(out) -> Path:
    """The bench's folder: `out` itself (--out names the result's folder), made if missing
    (the rungs' trajectories stream into it while the bench runs)."""
    out_dir = Path(out)
    out_dir.mkdir(parents=True, exist_ok=True)
    return out_dir


def knob_text(knob: dict) -> str:
    """A frequency rung's knobs, e.g. "rtol=1e-09", "elements=flap 36/lag 24"."""
    def text(v):
        if isinstance(v, dict):            # per part (e.g. a mesh per mode family)
            return (str(next(iter(v.values()))) if len(set(v.values())) == 1
                    else "/".join(f"{k} {x}" for k, x in v.items()))
        return f"{v:g}" if isinstance(v, float) else str(v)
    return ", ".join(f"{k}={text(v)}" for k, v in knob.items())


def _settings_text(settings: dict) -> str:
    return ", ".join(f"{k}={fmt_value(v)}" for k, v in settings.items() if v is not None)


def _dash(x, spec: str) -> str:
    return "—" if x is None else format(x, spec)


def time_markdown(obj: dict, ref_settings: dict) -> list[str]:
    """The time bench's report: the reference (its run's settings `ref_settings`), the summary
    lines, one table row per rung."""
    ref, key = obj["reference"], obj["key_channel"]
    names, check = ref["solvers"], ref["cross_check_rel"]
    bm = ref.get("kind") == "benchmark"
    if bm:              # the problem's own error against its reference (no reference run)
        head = [f"Reference: {ref['what']}. Each rung's error is the problem's: the largest "
                f"deviation of the monitored quantities from the reference over the run, in "
                f"{ref['unit']} (`error`), and that over {ref['scale']:.6g} {ref['unit']} "
                f"(`rel. error`, which the walk and the summary read); the reference's own "
                f"error is ~{ref['uncertainty']:g} {ref['unit']}. The figure is the library's "
                f"accuracy against its CPU time (the median wall time) per solver."]
    else:
        head = [f"Reference: {names[0]} ({_settings_text(ref_settings)}), "
                f"final {key} = {ref['value']:.15g}"
                + (f"; {names[1]} agrees to {check:.1e} relative" if check is not None else "")]
    unit = f"error [{ref['unit']}] | " if bm else ""
    md = [f"# Work-precision: {obj['scene']}", "", *head,
          "", *[f"- {x}" for x in obj["summary_lines"]], "", *error_bar_lines(obj),
          f"| solver | method | setting | {unit}rel. error | energy residual [J] | "
          "median wall [s] | compile [s] | steps | RHS evals | ns / RHS |",
          "|---" * (11 if bm else 10) + "|"]
    for r in obj["rows"]:
        knob = r["settings"].get("rtol") if "rtol" in r["settings"] and r["method"] in (
            "dop853", "dopri5", "rk23", "ode23") else r["settings"].get("dt")
        md.append(f"| {r['solver']} | {r['method']} | {fmt_value(knob)} | "
                  + (f"{_dash(r.get('error'), '.2e')} | " if bm else "")
                  + f"{_dash(r['rel_error'], '.2e')} | {_dash(r['energy_residual'], '.2e')} | "
                  f"{r['wall_s']:.4g} | "
                  f"{fmt_value(r['compile_s'], 3) if r['compile_s'] else '—'} | {r['steps']} | "
                  f"{r['rhs_evals'] or '—'} | {_dash(r['ns_per_rhs'], '.0f')} |")
    return md


def error_bar_lines(obj: dict) -> list[str]:
    """The cost of an error bar (`error_bars`: each solver's run with its estimate, per
    verdict over their comparisons); none for a bench without it."""
    cost = obj.get("error_bars")
    if not cost:
        return []
    per = (f"{cost['runs_per_verdict']:.3g} runs, {cost['seconds_per_verdict']:.3g} s per "
           "verdict" if cost["verdicts"] else "no pair compared")
    return [f"Cost of the error bars at these parameters: {cost['runs']} runs, "
            f"{cost['seconds']:.3g} s for {cost['verdicts']} verdicts ({per}).", "",
            "| solver | runs | run [s] | estimate [s] | estimate by |", "|---|---|---|---|---|",
            *[f"| {n} | {b['runs']} | {b['run_s']:.3g} | {b['estimate_s']:.3g} | "
              f"{b['by'] or b['status']} |" for n, b in cost["by_solver"].items()], ""]


def modes_markdown(obj: dict) -> list[str]:
    """The frequency bench's report: the reference and its confirmation, first-call times,
    the summary lines, one table row per rung."""
    ref, reps = obj["reference"], obj["repeats"]
    check = ref["confirmed_by"]
    md = [f"# Work-precision: {obj['scene']} (natural frequencies)", "",
          f"Reference: {ref['solver']} ({knob_text(ref['settings'])}): "
          + ", ".join(f"{lb} {f:.10g} Hz" for lb, f in zip(ref["labels"], ref["frequencies_hz"])),
          "", (f"Confirmed by {check['solver']} ({knob_text(check['settings'])}) to "
               + (f"{check['rel']:.1e} relative (at {check['worst_mode']})"
                  if check["rel"] is not None else f"— ({check['worst_mode']})"))
          if check else "No second reference solver.", "",
          "First call (import, compile): " + ", ".join(f"{s} {t:.2f} s"
                                                       for s, t in obj["first_call_s"].items())
          + f"; OPENBLAS_NUM_THREADS={obj['blas_threads'] or 'unset'}; median of {reps} warm "
            f"calls ({reps * 5} under 50 ms).", "", *[f"- {x}" for x in obj["summary_lines"]],
          "", "| solver | ladder | setting | max rel. error | at | median wall [s] | "
          "median CPU [s] |", "|---|---|---|---|---|---|---|"]
    md += [f"| {r['solver']} | {r['method']} | {knob_text(r['knob'])} | "
           f"{_dash(r['rel_error'], '.2e')} | {r.get('worst_mode') or r.get('reason')} | "
           f"{r['wall_s']:.4g} | {r['cpu_s']:.4g} |" for r in obj["rows"]]
    return md


def throughput_markdown(obj: dict, title: str) -> list[str]:
    """The throughput bench's report (`title`: the scene as asked for): one row per solver."""
    rows = obj["rows"]
    md = [f"# Throughput: {title}", "", f"{rows[0]['points'] if rows else 0}"
          f" points over the default map `{obj['map']}` ({obj['x']['name']}"
          + (f" × {obj['y']['name']}" if obj["y"] else "") + f"), set {obj['set']}, after a "
          "warm-up batch: each solver at its accurate default settings everywhere, and "
          "accuracy-adaptive as a map runs its grid (a cheap tolerance first, the accurate one "
          "for every point next to a regime change); `labels differ`: points whose adaptive "
          "regime is not the all-accurate one (0: the same boundary).", "",
          "| solver | points | points / s (adaptive) | points / core-s | points / s (accurate) "
          "| rerun accurate | labels differ |", "|---|---|---|---|---|---|---|"]
    md += [f"| {r['solver']} | {r['points']} | {r['points_per_second']:.1f} | "
           f"{r['points_per_core_second']:.1f} | {r['accurate_points_per_second']:.1f} | "
           + (f"{r['rerun_fraction']:.1%} | {r['labels_differ']} |" if "rerun_fraction" in r
              else "— | — |") for r in rows]
    return md


def plot(path, rows, scene, ylabel, summary=None, xlabel="median wall time [s]"):
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
    ax.set_xlabel(xlabel)
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


def _write(out_dir, obj: dict, md: list[str], ylabel: str, **kw) -> dict:
    """The figure, report.md (the figure linked at its end) and bench.json; `obj` with its
    report path."""
    plot(Path(out_dir) / FIGURE, obj["rows"], obj["scene"], ylabel, obj["summary"], **kw)
    md = md + ["", f"![work-precision]({FIGURE})"]
    return write_study(out_dir, md, obj, "bench.json", report_in_json=False)


def write_time_bench(out_dir, obj: dict, ref_settings: dict | None = None) -> dict:
    """The time bench's folder (error of the final key channel over wall time, or a benchmark
    problem's error against its reference); `ref_settings`: the reference run's settings
    (default: the JSON's)."""
    ref = obj["reference"]
    if ref_settings is None:
        ref_settings = ref.get("settings") or {}
    if ref.get("kind") == "benchmark":      # the library's accuracy against its CPU time
        return _write(out_dir, obj, time_markdown(obj, ref_settings),
                      f"{ref['problem']} error (max |deviation|) / {ref['scale']:.3g} "
                      f"{ref['unit']}", xlabel="CPU time: median wall time of a run [s]")
    return _write(out_dir, obj, time_markdown(obj, ref_settings),
                  f"relative error of final {obj['key_channel']}")


def write_modes_bench(out_dir, obj: dict) -> dict:
    """The frequency bench's folder (largest relative frequency error over wall time)."""
    return _write(out_dir, obj, modes_markdown(obj), "largest relative frequency error")


def write_throughput(out_dir, obj: dict, title: str) -> dict:
    """The throughput bench's folder: report.md and bench.json (no figure)."""
    return write_study(out_dir, throughput_markdown(obj, title), obj, "bench.json",
                       report_in_json=False)
