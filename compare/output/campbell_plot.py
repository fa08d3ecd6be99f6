"""The Campbell diagram of `xval modes`: campbell.png (every solver's mode lines in the frame
asked, the excitation lines labelled, critical speeds, veerings) and campbell.rrd (the lines in
the solvers' frame, in rerun)."""
from __future__ import annotations

import numpy as np

from ..atomic import atomic_path
from ..physics.whirl import order_seen


def png(path, scene, values, lines_by_solver, entries, params, events=None, frame=None,
        growing=None):
    """The lines of every solver as seen in `frame` (default: the solvers' own), each
    excitation line labelled with its order, name and frame — an excitation of the other frame
    drawn where it meets forward and backward whirl in this one (compare.physics.whirl) — the
    critical speeds (`entries`: solver → the crossings of compare.workflows.modes), and the
    samples where a line's root grows (`growing`: solver → line → bool per sample) in red."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    cb = scene.campbell
    frame = frame or cb.frame
    fig, ax = plt.subplots(figsize=(7.5, 4.8))
    styles = ["-", "--", ":", "-."]
    keys = list(dict.fromkeys(k for lines in lines_by_solver.values() for k in lines))
    for k, lines in enumerate(lines_by_solver.values()):
        for key, f in lines.items():           # one colour per mode, the same in every solver
            j = keys.index(key)
            colour = f"C{j % 10}" if len(keys) <= 10 else plt.cm.tab20(j % 20)
            ax.plot(values, f, lw=1, ls=styles[k % len(styles)], color=colour,
                    marker=".", ms=2, label=key if k == 0 else None)   # dots: the samples
    marked = False
    for s, by_line in (growing or {}).items():
        for key, g in by_line.items():
            f = np.asarray(lines_by_solver.get(s, {}).get(key, []), float)
            if len(f) == len(g) and g.any():
                ax.plot(np.asarray(values)[g], f[g], "o", color="red", ms=3,
                        label=None if marked else "growing root (ζ < 0)")
                marked = True
    speed = np.array([cb.excitation_hz(params, v) for v in values])
    grey = iter(np.linspace(0.0, 0.6, 2 * len(cb.excitations)))
    for e in cb.excitations:
        seen = {order_seen(e.order, e.frame, frame, w): w for w in ("backward", "forward")}
        for order, w in sorted(seen.items()):
            how = "" if e.frame == frame else f" ({e.order}× {e.frame}), {w.lower()} whirl"
            ax.plot(values, order * speed, ls=":", lw=1, color=str(next(grey)),
                    label=f"{order}× {e.name}{how}")
    for es in entries.values():
        for c in es:
            y = order_seen(c["order"], c["frame"], frame, c["whirl"])
            ax.plot([c["value"]], [y * cb.excitation_hz(params, c["value"])], "ko", ms=3)
    veer = [(e.at, np.nanmean([lines[k][np.searchsorted(values, e.at)] for k in e.lines]))
            for s, lines in lines_by_solver.items() for e in (events or {}).get(s, [])
            if e.kind != "crossing"]
    if veer:        # where two lines hand their shapes over without crossing
        ax.plot(*zip(*veer), "o", mfc="none", mec="k", ms=7, label="veering (shapes exchanged)")
    ax.set_xlabel(f"{cb.parameter} [{cb.unit or '–'}]")
    ax.set_ylabel(f"frequency [Hz], {frame} frame")
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
