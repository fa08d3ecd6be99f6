"""The Campbell diagram of `xval modes`: campbell.png (every solver's mode lines, the
excitation orders, critical speeds, veerings) and campbell.rrd (the lines in rerun)."""
from __future__ import annotations

import numpy as np

from ..atomic import atomic_path


def png(path, scene, values, lines_by_solver, crit, params, events=None):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    cb = scene.campbell
    fig, ax = plt.subplots(figsize=(7.5, 4.8))
    styles = ["-", "--", ":", "-."]
    keys = list(dict.fromkeys(k for lines in lines_by_solver.values() for k in lines))
    for k, lines in enumerate(lines_by_solver.values()):
        for key, f in lines.items():           # one colour per mode, the same in every solver
            j = keys.index(key)
            colour = f"C{j % 10}" if len(keys) <= 10 else plt.cm.tab20(j % 20)
            ax.plot(values, f, lw=1, ls=styles[k % len(styles)], color=colour,
                    marker=".", ms=2, label=key if k == 0 else None)   # dots: the samples
    if cb.excitation_hz is not None:
        for order in cb.orders:
            ax.plot(values, [order * cb.excitation_hz(params, v) for v in values], "k:", lw=1,
                    label=f"{order}× excitation")
    for c in crit.values():
        for v in c.values():
            ax.plot([v], [cb.excitation_hz(params, v)], "ko", ms=3)
    veer = [(e.at, np.nanmean([lines[k][np.searchsorted(values, e.at)] for k in e.lines]))
            for s, lines in lines_by_solver.items() for e in (events or {}).get(s, [])
            if e.kind != "crossing"]
    if veer:        # where two lines hand their shapes over without crossing
        ax.plot(*zip(*veer), "o", mfc="none", mec="k", ms=7, label="veering (shapes exchanged)")
    ax.set_xlabel(f"{cb.parameter} [{cb.unit or '–'}]")
    ax.set_ylabel("frequency [Hz]")
    top = max(np.nanmax(f) for lines in lines_by_solver.values() for f in lines.values())
    ax.set_ylim(0, 1.1 * top)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    legend = ", ".join(f"{s}: '{styles[k % len(styles)]}'" for k, s in enumerate(lines_by_solver))
    ax.set_title(f"Campbell diagram (line style per solver — {legend})", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def rrd(path, scene, values, lines_by_solver):
    import rerun as rr
    with atomic_path(path) as tmp, \
            rr.RecordingStream("xval", recording_id=f"campbell-{path.parent.name}") as rec:
        rec.save(str(tmp))
        idx = [rr.TimeColumn(scene.campbell.parameter, duration=values)]   # 1 s = 1 unit
        for solver, lines in lines_by_solver.items():
            for key, f in lines.items():
                rec.send_columns(f"campbell/{rr.escape_entity_path_part(key)}/{solver}",
                                 indexes=idx, columns=rr.Scalars.columns(scalars=f))
    return path
