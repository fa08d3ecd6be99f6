"""The frequency table as a figure and a recording, for a modes result that draws neither a
Campbell diagram nor mode shapes (the helicopters' engine cases: Exudyn and MuJoCo return
frequencies, no shapes, and the scene sweeps its Campbell diagram with the paper's solvers
only): frequencies.png — each solver's frequencies mode by mode with its own error bar, and
below them |Δf| of every compared pair with the bound its verdict used (error estimates +
allowance, read from the comparison) — and frequencies.rrd, the same frequencies per solver
on a `mode` timeline. Nothing here names a scene."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..analysis.metrics import frequency_errors
from ..atomic import atomic_path
from .recording import APPLICATION_ID
from .report import bound_of, params_title, plot_style, save_figure


def _modes(results):
    return [m for m in results if m.status == "ok" and len(m.frequencies_hz)]


def write_figure(path, scene, params, results, comparisons) -> str | None:
    """frequencies.png; None where no solver gave a frequency."""
    ok = _modes(results)
    if not ok:
        return None
    plt = plot_style()
    fig, (top, low) = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
    labels = list(dict.fromkeys(lb for m in ok for lb in m.labels))
    x = {lb: i for i, lb in enumerate(labels)}
    shift = np.linspace(-0.15, 0.15, len(ok)) if len(ok) > 1 else [0.0]
    for k, m in enumerate(ok):
        err = frequency_errors(m)
        xs = [x[lb] + shift[k] for lb in m.labels]
        top.errorbar(xs, m.frequencies_hz, yerr=err, fmt="o", ms=4, capsize=3, label=m.solver)
    pairs = {}
    for c in comparisons:
        if c.channel in x and np.isfinite(c.deviation):
            pairs.setdefault((c.a, c.b), []).append(c)
    for k, ((a, b), cs) in enumerate(pairs.items()):
        dx = 0.3 * (k / max(len(pairs) - 1, 1) - 0.5) if len(pairs) > 1 else 0.0
        xs = [x[c.channel] + dx for c in cs]
        line, = low.semilogy(xs, [max(c.deviation, 1e-17) for c in cs], "o", ms=4,
                             label=f"{a} − {b}")
        bounds = [(xc, bound_of(c)) for xc, c in zip(xs, cs) if bound_of(c) is not None]
        if bounds:
            low.plot(*zip(*bounds), "_", ms=12, mew=2, color=line.get_color())
    top.set_ylabel("frequency [Hz]")
    top.set_title(f"{scene.name}: frequencies per solver{params_title(scene, params)} "
                  "(bars: each solver's own error estimate)", fontsize=9)
    top.legend(fontsize=7)
    low.set_ylabel("|Δf| [Hz]")
    low.set_title("|Δf| per pair (●) and the bound its verdict used (—: error estimates + "
                  "allowance)", fontsize=9)
    if low.lines:
        low.legend(fontsize=7, ncol=2)
    low.set_xticks(range(len(labels)), labels, rotation=30, ha="right", fontsize=7)
    for ax in (top, low):
        ax.grid(alpha=0.3)
    fig.tight_layout()
    return save_figure(fig, path)


def write_recording(path, results, recording_id) -> Path | None:
    """frequencies.rrd: per solver and mode its frequency (and error estimate), on the `mode`
    timeline (the mode's index in the table)."""
    import rerun as rr
    ok = _modes(results)
    if not ok:
        return None
    labels = list(dict.fromkeys(lb for m in ok for lb in m.labels))
    with atomic_path(path) as tmp, rr.RecordingStream(APPLICATION_ID,
                                                      recording_id=recording_id) as rec:
        rec.save(str(tmp))
        for m in ok:
            idx = [labels.index(lb) for lb in m.labels]
            rec.send_columns(f"frequencies/{rr.escape_entity_path_part(m.solver)}",
                             indexes=[rr.TimeColumn("mode", sequence=idx)],
                             columns=rr.Scalars.columns(scalars=np.asarray(m.frequencies_hz,
                                                                           float)))
    return Path(path)


def overview_figure(scene_name, runs, campbell):
    """A bare matplotlib Figure of a modes result (`ModesResult.figure`): the Campbell diagram
    where the scene sweeps, else each solver's frequencies side by side."""
    from matplotlib.figure import Figure
    fig = Figure(figsize=(7.5, 4.8))
    ax = fig.subplots()
    if campbell and campbell["lines_hz"]:
        x = campbell["values"]
        for k, (s, lines) in enumerate(campbell["lines_hz"].items()):
            for j, (key, f) in enumerate(lines.items()):
                ax.plot(x, f, lw=1, ls=["-", "--", ":", "-."][k % 4], color=f"C{j % 10}",
                        label=f"{s}: {key}")
        ax.set_xlabel(campbell["parameter"])
        ax.legend(fontsize=6, ncol=2)
    else:
        for i, m in enumerate(runs.values()):
            ax.plot([i] * len(m.frequencies_hz), m.frequencies_hz, "_", ms=30, mew=2)
        ax.set_xticks(range(len(runs)), list(runs))
        ax.set_yscale("log")
    ax.set_ylabel("frequency [Hz]")
    ax.grid(alpha=0.3)
    ax.set_title(scene_name)
    fig.tight_layout()
    return fig

