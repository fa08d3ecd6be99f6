"""Markdown reports with PNG plots (matplotlib, Agg backend).

Plots carry a unit on every axis (the scene's `Channel`s carry them), never offset notation
(a flat channel such as a conserved energy is drawn as its deviation from the initial value,
which the label states), and numbers in the text are printed
to their meaningful digits (`fmt_value`: 1e-13, not 9.999999999999999e-14).
"""
from pathlib import Path

import numpy as np

from ..analysis import metrics
from ..analysis.verdict import MARGINAL
from ..atomic import atomic_path, write_text
from .citations import cite, cite_short, papers_in
from .tables import VERDICT_HEADER, markdown, verdict_rows


def channel_unit(scene, ch):
    return scene.unit(ch)


def channel_label(scene, ch):
    unit = channel_unit(scene, ch)
    return f"{ch} [{unit}]" if unit else f"{ch} [–]"


def changed_params(scene, params, skip=()) -> list[str]:
    """`name = value unit` for each parameter of `params` that differs from the scene's
    default (what a title and a report header name: the defaults are the scene's own),
    except those in `skip`."""
    def value(p):                      # a --set string (a map's `set`) read as the parameter
        v = params[p.name]
        if isinstance(v, str):
            try:
                return p.parse(v)
            except Exception:          # shown as given
                return v
        return v
    return [f"{p.name} = {fmt_value(value(p))}" + (f" {p.unit}" if p.unit else "")
            for p in scene.params if p.name in (params or {}) and p.name not in skip
            and not np.array_equal(np.asarray(value(p)), np.asarray(p.default))]


def params_title(scene, params) -> str:
    """` (torque = 3.2 N·m)` for a figure title, or "" at the defaults."""
    changed = changed_params(scene, params)
    return f" ({', '.join(changed)})" if changed else ""


def source_line(scene) -> str:
    """`Source: <the papers, cited as papers>.` (never the scene data's "seed NNN")."""
    refs = papers_in(scene.source) or [cite(scene.source)]
    return "Source: " + "; ".join(refs) + "."


def header_lines(scene, params, inputs: dict | None = None) -> list[str]:
    """A report's header: the source papers, the parameters that differ from the scene's
    defaults, and the inputs a study adds (`inputs`: {name: value} the study sets on top of the
    defaults, e.g. the unbalance response's eccentricity and external damping), said to be the
    study's, not the scene's defaults."""
    inputs = inputs or {}
    units = {p.name: p.unit for p in scene.params}
    changed = changed_params(scene, params, skip=inputs)
    out = [source_line(scene), "",
           f"Parameters: defaults{'; ' + ', '.join(changed) if changed else ''}."]
    if inputs:
        given = ", ".join(f"{k} = {fmt_value((params or {}).get(k, v))}"
                          + (f" {units[k]}" if units.get(k) else "") for k, v in inputs.items())
        out += ["", f"Inputs this study adds: {given} — the study's own values, not the "
                f"scene's defaults (`xval show {scene.name}` lists those); `--set` overrides "
                "them."]
    return out + [""]


def fmt_value(x, digits=6):
    """A parameter or setting as a reader wants it: 1e-13, 0.01, 3.2, 0,0,-9.81."""
    if isinstance(x, (list, tuple, np.ndarray)):
        return ",".join(fmt_value(v, digits) for v in np.asarray(x).ravel())
    if isinstance(x, (bool, np.bool_)) or not isinstance(x, (int, float, np.number)):
        return str(x)
    return format(float(x), f".{digits}g") if isinstance(x, (float, np.floating)) else str(x)


DPI = 110
# figure.dpi = the saved dpi: tight_layout then measures the text with the canvas's renderer
# that savefig reuses (Agg keeps it while size and dpi hold), so the text is laid out once,
# not at 100 dpi for the layout and again at 110 for the file (text measurements per figure
# halved; channels + deviation of a 1 s spin-up 1.94 → 1.66 CPU-s, mean of 5, shared machine)
STYLE = {"axes.formatter.useoffset": False, "font.size": 9, "axes.formatter.limits": (-4, 5),
         "figure.dpi": DPI}


def plot_style():
    """pyplot with offset notation off and a readable default size. Files only: the Agg
    backend, unless pyplot is in use already (a notebook's inline backend stays)."""
    import sys

    import matplotlib
    if "matplotlib.pyplot" not in sys.modules:
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    plt.rcParams.update(STYLE)
    return plt


_plt = plot_style


def fixed_margins(fig, left=0.75, right=0.2, top=0.55, bottom=0.55, wgap=0.85, hgap=0.35):
    """Lay out a grid of axes with margins and gaps in inches — room for the axis label, the
    offset text above an axes and the title — set directly: tight_layout measured every tick
    label before savefig drew them again, a third of a run report's plotting (rotor-spinup,
    channels + deviation: 1.2 → 0.77 CPU-s, best of 7, one process). The room left of each
    column grows with its widest y tick label (24.52504 needs more than 0.75 in)."""
    w, h = fig.get_size_inches()
    nrow, ncol = fig.axes[0].get_subplotspec().get_gridspec().get_geometry()
    room = [left] + [wgap] * (ncol - 1)
    for ax in fig.axes:
        if ax.axison:
            col = ax.get_subplotspec().colspan.start
            room[col] = max(room[col], _ylabels_room(ax))
    left, wgap = room[0], max(room[1:], default=wgap)
    aw = (w - left - right - (ncol - 1) * wgap) / ncol
    ah = (h - top - bottom - (nrow - 1) * hgap) / nrow
    fig.subplots_adjust(left=left / w, right=1 - right / w, top=1 - top / h, bottom=bottom / h,
                        wspace=wgap / aw, hspace=hgap / ah)


# DejaVu Sans (matplotlib's default): a digit 0.64 em wide, '−' 0.84 em ('.' narrower, counted
# as a digit)
_EM_DIGIT, _EM_MINUS = 0.64, 0.84


def _ylabels_room(ax):
    """Inches an axes' y tick labels and axis label take left of it, from the labels' text
    (linear axes; a log axis's 10ⁿ labels fit the default room)."""
    if ax.get_yscale() != "linear":
        return 0.0
    labels = ax.yaxis.major.formatter.format_ticks(ax.yaxis.get_majorticklocs())
    em = max((len(t) * _EM_DIGIT + t.count("\N{MINUS SIGN}") * (_EM_MINUS - _EM_DIGIT)
              for t in labels), default=0.0)
    size = ax.yaxis.get_ticklabels()[0].get_fontsize() if labels else 0.0
    # the widest label, then the axis label's line and ~16 pt of tick marks and pads
    return (em * size + ax.yaxis.label.get_fontsize() + 16) / 72


def save_figure(fig, path):
    """Write the figure atomically; returns its file name (for the Markdown link)."""
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=DPI, format="png")
    _plt().close(fig)
    return Path(path).name


_savefig = save_figure


def _flat(v):
    """True when a channel varies by less than 1e-6 of its size: drawn as v − v(0)."""
    f = v[np.isfinite(v)]
    return len(f) > 1 and np.ptp(f) < 1e-6 * max(np.max(np.abs(f)), 1e-300) and np.ptp(f) > 0


def analytic_curve(result, ch):
    """(t, values, label) of the scene's closed form for `ch`, from the first trajectory that
    carries it, or None."""
    key = result.scene.analytic.get(ch)
    for tr in result.trajectories if key else ():
        v = tr.extra.get(key[0])
        if v is not None and len(v) == len(tr.t):
            return tr.t, np.asarray(v, float), key[1]
    return None


def plot_channels(result, path):
    return _savefig(channels_figure(result), path)


def channels_figure(result, channels=None):
    """Each channel (default: every channel of the scene) per solver, the closed form dashed
    where the scene has one. A bare matplotlib Figure (no pyplot state: a notebook shows the
    returned figure once, the report saves it)."""
    import matplotlib
    with matplotlib.rc_context(STYLE):     # the report's style, the caller's rcParams kept
        return _channels_figure(result, list(channels or result.scene.channels))


def _channels_figure(result, chs):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    ncol = 2 if len(chs) > 1 else 1
    nrow = (len(chs) + ncol - 1) // ncol
    fig = Figure(figsize=(11 if ncol == 2 else 7, 2.6 * nrow))
    FigureCanvasAgg(fig)                   # its renderer, kept from the layout to the file
    axes = fig.subplots(nrow, ncol, sharex=True, squeeze=False)
    for ax, ch in zip(axes.flat, chs):
        flat = any(_flat(tr.channels[ch]) for tr in result.trajectories)
        ref0 = next((tr.channels[ch][0] for tr in result.trajectories
                     if np.isfinite(tr.channels[ch][0])), 0.0) if flat else 0.0
        for tr in result.trajectories:
            v = tr.channels[ch] - ref0
            line, = ax.plot(tr.t, v, lw=1, label=tr.solver)
            _error_band(ax, tr.t, v, tr.errors.get(ch), line.get_color())
        curve = analytic_curve(result, ch)
        if curve is not None:
            ax.plot(curve[0], curve[1] - ref0, "k--", lw=1, label=curve[2])
            ax.legend(fontsize=7)
        unit = channel_unit(result.scene, ch) or "–"
        ax.set_ylabel(f"{ch} − {ref0:.10g} [{unit}]" if flat else channel_label(result.scene,
                                                                                 ch),
                      fontsize=8)
        ax.grid(alpha=0.3)
    for ax in axes.flat[len(chs):]:
        ax.axis("off")
        above = axes.flat[list(axes.flat).index(ax) - ncol]      # its time axis is the last
        above.xaxis.set_tick_params(labelbottom=True)
        above.set_xlabel("t [s]")
    axes.flat[0].legend(fontsize=8)
    for ax in axes[-1]:
        ax.set_xlabel("t [s]")
    fig.suptitle(f"{result.scene.name}: channels per solver"
                 f"{params_title(result.scene, result.params)}", y=1 - 0.12 / fig.get_figheight())
    fixed_margins(fig)
    return fig


# An error band is drawn where it is wider than the line: a 1 px line on an axes ~250 px tall
# spans ~1/250 of the data range
_BAND_VISIBLE = 1 / 250


def _error_band(ax, t, v, err, color):
    """The solver's own error estimate (its tighter rerun) as a band ±err about its curve,
    where the band is wider than the line; nothing where no estimate was made."""
    if err is None or len(err) != len(t):
        return
    err = np.asarray(err, float)
    span = np.ptp(v[np.isfinite(v)]) if np.isfinite(v).any() else 0.0
    wide = np.isfinite(err) & (err > _BAND_VISIBLE * max(span, 1e-300))
    if wide.any():
        ax.fill_between(t, v - err, v + err, where=wide, color=color, alpha=0.25, lw=0)


def comparison_of(comparisons, a, b, channel):
    """The comparison of the pair (a, b) on `channel`, in either order, or None."""
    return next((c for c in comparisons or () if c.channel == channel
                 and {c.a, c.b} == {a, b}), None)


def bound_of(c) -> float | None:
    """The bound the verdict of comparison `c` used (error estimates + allowance, SI), as the
    comparison stored it; None where it was not compared."""
    b = c.tolerance * c.scale if c is not None else np.nan
    return float(b) if np.isfinite(b) and b > 0 else None


def plot_deviation(result, path):
    return _savefig(deviation_figure(result), path)


def deviation_figure(result):
    """|Δ| of the key channel per solver pair with the bound its verdict was judged against
    (dashed, the comparison's error estimates + allowance; the verdict in the legend), and
    each solver's energy-balance drift."""
    from matplotlib.ticker import NullLocator
    plt = _plt()
    sc, trs = result.scene, [t for t in result.trajectories if t.status == "ok"]
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 3.6))
    for i, a in enumerate(trs):
        for b in trs[i + 1:]:
            d = np.abs(a.channels[sc.key_channel] - b.channels[sc.key_channel])
            c = comparison_of(getattr(result, "comparisons", None), a.solver, b.solver,
                              sc.key_channel)
            bound = bound_of(c)
            label = f"{a.solver} − {b.solver}" + (
                f": {c.shown} (Δ/bound {metrics.ratio_text(c.ratio)})" if c is not None else "")
            line, = a1.semilogy(a.t, np.maximum(d, 1e-17), lw=1, label=label)
            if bound is not None:
                a1.axhline(bound, color=line.get_color(), ls="--", lw=1)
        if sc.energy_channel:
            e = a.channels[sc.energy_channel]
            a2.semilogy(a.t, np.maximum(np.abs(e - e[0]), 1e-17), lw=1, label=a.solver)
    a1.set_title(f"|Δ {sc.key_channel}| between solvers; dashed: the bound (error "
                 "estimates + allowance)", fontsize=8)
    fig.suptitle(f"{sc.name}: deviation{params_title(sc, result.params)}", fontsize=9,
                 y=1 - 0.08 / fig.get_figheight())
    a1.set_ylabel(f"|Δ {channel_label(sc, sc.key_channel)}|")
    a2.set_title("drift of the energy balance")
    a2.set_ylabel("|E(t) − E(0)| [J]")
    for ax in (a1, a2):
        ax.set_xlabel("t [s]")
        lo, hi = ax.get_ylim()
        if ax.get_yscale() == "log" and hi > 1e3 * lo:
            # over more than three decades the minor ticks carry no label and were ~40 % of
            # this figure's drawing (rotor-spinup, 1 s: 0.40 → 0.21–0.23 CPU-s): majors only
            ax.yaxis.set_minor_locator(NullLocator())
        ax.grid(alpha=0.3, which="both")
        if ax.lines:
            ax.legend(fontsize=7)
    fixed_margins(fig, top=0.55)
    return fig


def _fmt(x, spec=".4g"):
    if x is None or (isinstance(x, float) and not np.isfinite(x)):
        return "—"
    return format(x, spec)


def run_markdown(result, figures):
    sc, trs = result.scene, result.trajectories
    out = [f"# {sc.name}: {sc.title}", "", source_line(sc), ""]
    if sc.notes:
        out += [cite_short(sc.notes), ""]
    out += [*header_lines(sc, result.params)[2:], "## Runs", "",
            "| solver | status | wall [s] | compile [s] | steps | settings | "
            f"final {sc.key_channel} | energy residual [J] | invariants |",
            "|---|---|---|---|---|---|---|---|---|"]
    for tr in trs:
        st = tr.status + (f" at t = {tr.t_fail:.4g} s: {tr.reason}" if tr.status != "ok" and
                          tr.t_fail is not None else (f": {tr.reason}" if tr.reason else ""))
        settings = ", ".join(f"{k}={fmt_value(v)}" for k, v in tr.settings.items()
                             if v is not None)
        inv = ", ".join(f"{k} {v:.1e}" for k, v in tr.invariants.items())
        er = metrics.energy_residual(tr, sc.energy_channel) if sc.energy_channel else None
        out.append(f"| {tr.solver} | {st} | {tr.wall_s:.3g} | "
                   f"{_fmt(tr.stats.get('compile_s'), '.3g')} | {tr.stats.get('steps', '—')} | "
                   f"{settings} | {_fmt(tr.final()[sc.key_channel], '.10g')} | "
                   f"{_fmt(er, '.2e')} | {inv} |")
    if result.findings:
        out += ["", "## Findings", ""] + [f"- {f.text}" for f in result.findings]
    out += ["", "## Agreement", "",
            "Verdict per pair and channel: the deviation max|Δ| against its bound — both "
            "solvers' error estimates (their tighter reruns) plus the scene's modelling "
            f"allowance; Δ/bound ≤ 1 agrees, above {MARGINAL:g} it is marginal.", "",
            markdown(VERDICT_HEADER, verdict_rows(result.comparisons))]
    out += power_markdown(getattr(result, "power", None))
    out += [""] + [f"![{f}]({f})" for f in figures]
    return "\n".join(out) + "\n"


def power_markdown(power) -> list[str]:
    """The detection power of a run's verdicts: per parameter and solver the relative change,
    reaching that solver only, that turns an agreeing verdict to disagree (`xval power`)."""
    if power is None:
        return []
    out = ["", "## Detection power", "", power["summary"] + ".", ""]
    if not power["rows"]:
        return out
    out += ["ε*: the smallest relative change of a parameter in one solver that turns one of "
            "these verdicts to disagree (`xval power` confirms each with runs).", "",
            "| parameter | solver | ε* | flips | channel | how |", "|---|---|---|---|---|---|"]
    out += [f"| {r['parameter']} | {r['solver']} | {_fmt(r['epsilon'], '.2g')} | "
            f"{' vs '.join(r['pair'] or ['—'])} | {r['channel'] or '—'} | {r['how']} |"
            for r in power["rows"]]
    return out


def write_run_report(out_dir, result):
    out_dir = Path(out_dir)
    figures = [plot_channels(result, out_dir / "channels.png")]
    if len([t for t in result.trajectories if t.status == "ok"]):
        figures.append(plot_deviation(result, out_dir / "deviation.png"))
    if result.scene.plots is not None:
        import matplotlib.pyplot as plt
        plot_style()
        fig = plt.figure(figsize=(11, 4))
        result.scene.plots(result.params, result.trajectories, fig)
        fig.suptitle(f"{result.scene.name}{params_title(result.scene, result.params)}",
                     fontsize=9)
        fig.tight_layout()
        figures.append(save_figure(fig, out_dir / "scene.png"))
        plt.close(fig)
    path = out_dir / "report.md"
    write_text(path, run_markdown(result, figures))
    return path
