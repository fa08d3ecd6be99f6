"""Markdown reports with PNG plots (matplotlib, Agg backend)."""
from pathlib import Path

import numpy as np

from .atomic import atomic_path, write_text
from . import metrics


def _plt():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def _savefig(fig, path):
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    _plt().close(fig)
    return Path(path).name


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
    plt = _plt()
    chs = result.scene.channels
    ncol = 2
    nrow = (len(chs) + ncol - 1) // ncol
    fig, axes = plt.subplots(nrow, ncol, figsize=(11, 2.6 * nrow), sharex=True, squeeze=False)
    for ax, ch in zip(axes.flat, chs):
        for tr in result.trajectories:
            ax.plot(tr.t, tr.channels[ch], lw=1, label=tr.solver)
        curve = analytic_curve(result, ch)
        if curve is not None:
            ax.plot(curve[0], curve[1], "k--", lw=1, label=curve[2])
            ax.legend(fontsize=7)
        ax.set_ylabel(ch)
        ax.grid(alpha=0.3)
    for ax in axes.flat[len(chs):]:
        ax.axis("off")
    axes.flat[0].legend(fontsize=8)
    for ax in axes[-1]:
        ax.set_xlabel("t [s]")
    fig.suptitle(f"{result.scene.name}: channels per solver")
    fig.tight_layout()
    return _savefig(fig, path)


def plot_deviation(result, path):
    """|Δ| of the key channel per solver pair, and each solver's energy-balance drift."""
    plt = _plt()
    sc, trs = result.scene, [t for t in result.trajectories if t.status == "ok"]
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 3.6))
    for i, a in enumerate(trs):
        for b in trs[i + 1:]:
            d = np.abs(a.channels[sc.key_channel] - b.channels[sc.key_channel])
            a1.semilogy(a.t, np.maximum(d, 1e-17), lw=1, label=f"{a.solver} − {b.solver}")
        if sc.energy_channel:
            e = a.channels[sc.energy_channel]
            a2.semilogy(a.t, np.maximum(np.abs(e - e[0]), 1e-17), lw=1, label=a.solver)
    a1.set_title(f"|Δ {sc.key_channel}| between solvers")
    a2.set_title("|E(t) − E(0)| of the energy balance [J]")
    for ax in (a1, a2):
        ax.set_xlabel("t [s]")
        ax.grid(alpha=0.3, which="both")
        if ax.lines:
            ax.legend(fontsize=7)
    fig.tight_layout()
    return _savefig(fig, path)


def _fmt(x, spec=".4g"):
    if x is None or (isinstance(x, float) and not np.isfinite(x)):
        return "—"
    return format(x, spec)


def run_markdown(result, figures):
    sc, trs = result.scene, result.trajectories
    out = [f"# {sc.name}: {sc.title}", "", f"Source: {sc.source}.", ""]
    if sc.notes:
        out += [sc.notes, ""]
    changed = ", ".join(f"{p.name} = {result.params[p.name]}" for p in sc.params
                        if not np.array_equal(np.asarray(result.params[p.name]),
                                              np.asarray(p.default)))
    out += [f"Parameters: defaults{'; ' + changed if changed else ''}.", "", "## Runs", "",
            "| solver | status | wall [s] | compile [s] | steps | settings | "
            f"final {sc.key_channel} | energy residual [J] | invariants |",
            "|---|---|---|---|---|---|---|---|---|"]
    for tr in trs:
        st = tr.status + (f" at t = {tr.t_fail:.4g} s: {tr.reason}" if tr.status != "ok" and
                          tr.t_fail is not None else (f": {tr.reason}" if tr.reason else ""))
        settings = ", ".join(f"{k}={v}" for k, v in tr.settings.items() if v is not None)
        inv = ", ".join(f"{k} {v:.1e}" for k, v in tr.invariants.items())
        er = metrics.energy_residual(tr, sc.energy_channel) if sc.energy_channel else None
        out.append(f"| {tr.solver} | {st} | {tr.wall_s:.3g} | "
                   f"{_fmt(tr.stats.get('compile_s'), '.3g')} | {tr.stats.get('steps', '—')} | "
                   f"{settings} | {_fmt(tr.final()[sc.key_channel], '.10g')} | "
                   f"{_fmt(er, '.2e')} | {inv} |")
    if result.findings:
        out += ["", "## Findings", ""] + [f"- {f.text}" for f in result.findings]
    out += ["", "## Agreement", "",
            "Verdict per pair and channel: max |Δ| relative to the channel's scale (max |value| "
            "of the pair) against the scene's tolerance.", "",
            "| a | b | channel | max abs | rms | max rel | tolerance | verdict |",
            "|---|---|---|---|---|---|---|---|"]
    out += [f"| {c.a} | {c.b} | {c.channel} | {_fmt(c.max_abs, '.3e')} | {_fmt(c.rms, '.3e')} | "
            f"{_fmt(c.max_rel, '.2e')} | {c.tolerance:.0e} | **{c.verdict}** |"
            for c in result.comparisons]
    out += [""] + [f"![{f}]({f})" for f in figures]
    return "\n".join(out) + "\n"


def write_run_report(out_dir, result):
    out_dir = Path(out_dir)
    figures = [plot_channels(result, out_dir / "channels.png")]
    if len([t for t in result.trajectories if t.status == "ok"]):
        figures.append(plot_deviation(result, out_dir / "deviation.png"))
    path = out_dir / "report.md"
    write_text(path, run_markdown(result, figures))
    return path
