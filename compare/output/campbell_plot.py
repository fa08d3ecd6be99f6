"""The Campbell diagram of `xval modes`: campbell.png (every solver's mode lines in the frame
asked, the excitation lines labelled, critical speeds, veerings) and campbell.rrd (the lines in
the solvers' frame, in rerun)."""
from __future__ import annotations

import numpy as np

from ..atomic import atomic_path
from ..physics.whirl import order_seen
from ..scenes.base import UNBALANCE
from .mode_shapes import REPEATED
from .report import params_title


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
    for e in cb.active(params):                  # the loads the system has at `params`
        seen = {order_seen(e.order, e.frame, frame, w): w for w in ("backward", "forward")}
        for order, w in sorted(seen.items()):
            how = "" if e.frame == frame else f" ({e.order}× {e.frame}), {w.lower()} whirl"
            ax.plot(values, order * speed, ls=":", lw=1, color=str(next(grey)),
                    label=f"{order}× {e.name}{how}")
    at = {}            # one label per speed and excitation: the solvers agree on the crossing
    for es in entries.values():
        for c in es:
            y = order_seen(c["order"], c["frame"], frame, c["whirl"]) \
                * cb.excitation_hz(params, c["value"])
            quiet = not_excited(c)
            ax.plot([c["value"]], [y], "o", ms=4, mec="k", mfc="none" if quiet else "k")
            key = (f"{c['speed_rpm']:.4g}", c["order"], c["excitation"])
            x0, y0, cs = at.get(key, (c["value"], y, []))
            if not any(o["whirl"] == c["whirl"] for o in cs):
                cs.append(c)
            at[key] = (x0, max(y0, y), cs)
    for x0, y0, cs in at.values():
        right = x0 > 0.6 * values[-1] + 0.4 * values[0]          # near the right: leftwards
        ax.annotate(crossing_label(cs), (x0, y0), xytext=(-6 if right else 6, 6),
                    textcoords="offset points", fontsize=7, ha="right" if right else "left",
                    va="bottom", bbox={"boxstyle": "round,pad=0.2", "fc": "white", "ec": "0.7",
                                       "alpha": 0.85})
    veer = [(e.at, np.nanmean([lines[k][np.searchsorted(values, e.at)] for k in e.lines]))
            for s, lines in lines_by_solver.items() for e in (events or {}).get(s, [])
            if e.kind != "crossing"]
    if veer:        # where two lines hand their shapes over without crossing
        ax.plot(*zip(*veer), "o", mfc="none", mec="k", ms=7, label="veering (shapes exchanged)")
    ax.set_xlabel(f"{cb.parameter} [{cb.unit or '–'}]")
    rpm = 60 * speed                         # the rotation speed in rpm at each sampled value
    if len(values) > 1 and np.all(np.diff(rpm) > 0):
        v = np.asarray(values, float)
        a, b = np.polyfit(v, rpm, 1)
        if np.max(np.abs(a * v + b - rpm)) <= 1e-9 * np.max(np.abs(rpm)):   # rpm ∝ the sweep
            fwd, inv = (lambda x: a * x + b), (lambda r: (r - b) / a)
        else:                                  # a monotonic, nonlinear map: within the sweep
            fwd, inv = (lambda x: np.interp(x, v, rpm)), (lambda r: np.interp(r, rpm, v))
        rpm_ax = ax.secondary_xaxis("top", functions=(fwd, inv))
        rpm_ax.set_xlabel("rotation speed [rpm]", fontsize=8)
        rpm_ax.tick_params(labelsize=8)
    ax.set_ylabel(f"frequency [Hz], {frame} frame")
    top = max(np.nanmax(f) for lines in lines_by_solver.values() for f in lines.values())
    ax.set_ylim(0, 1.1 * top)
    ax.grid(alpha=0.3)
    crossings = [c for es in entries.values() for c in es]
    if crossings:
        ax.plot([], [], "ko", ms=4, label="critical speed")
    if any(not_excited(c) for c in crossings):
        ax.plot([], [], "o", ms=4, mec="k", mfc="none",
                label="backward whirl: not excited by unbalance")
    ax.legend(fontsize=7, ncol=2)
    legend = ", ".join(f"{s}: '{styles[k % len(styles)]}'" for k, s in enumerate(lines_by_solver))
    ax.set_title(f"{scene.name}: Campbell diagram{params_title(scene, params)}\n"
                 f"line style per solver — {legend}", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def not_excited(c) -> bool:
    """A backward-whirl crossing of the 1× fixed-frame unbalance line: unbalance drives forward
    synchronous whirl only, so nothing resonates there."""
    return (c.get("whirl") == "backward" and c.get("order") == 1 and c.get("frame") == "fixed"
            and c.get("excitation") == UNBALANCE.name)


def crossing_label(cs) -> str:
    """`392.1 rpm, 1× unbalance, forward whirl` for a critical speed (an entry of
    compare.workflows.modes), or for the crossings of one speed and excitation together
    (`288 rpm, 1× unbalance, forward whirl; backward whirl (not excited)`)."""
    cs = [cs] if isinstance(cs, dict) else list(cs)
    whirls = "; ".join(f"{c['whirl']} whirl" + (" (not excited)" if not_excited(c) else "")
                       for c in cs if c.get("whirl"))
    c = cs[0]
    return f"{c['speed_rpm']:.4g} rpm, {c['order']}× {c['excitation']}" + (
        f", {whirls}" if whirls else "")


def critical_notes(entries: dict) -> dict:
    """{(solver, crossing name): note} for the critical-speed table: backward whirl on the
    unbalance line (`not_excited`), and crossings of one solver whose frequencies coincide
    within their error bars (a repeated frequency: any pair of shapes spanning its plane is a
    valid answer, so two solvers' shapes may differ within it)."""
    notes = {}
    for s, es in entries.items():
        for i, e in enumerate(es):
            words = ["backward whirl: not excited by unbalance"] if not_excited(e) else []
            for j, o in enumerate(es):
                bar = max([1e-9 * abs(e["frequency_hz"])] + [
                    abs(x["error"] * x["slope_hz"]) for x in (e, o)
                    if x.get("error") is not None and x.get("slope_hz") is not None])
                if j != i and abs(o["frequency_hz"] - e["frequency_hz"]) <= bar:
                    words.append(REPEATED)
                    break
            if words:
                notes[(s, e["name"])] = "; ".join(words)
    return notes


def critical_table(cb, entries: dict) -> list[str]:
    """The critical speeds as ROSS tabulates them: speed in rad/s and rpm side by side, the
    frequency met in Hz and rad/s, the excitation, whirl and frame of each crossing, and a note
    where a crossing needs one (`critical_notes`)."""
    p = f"{cb.parameter} [{cb.unit}]" if cb.unit else cb.parameter
    notes = critical_notes(entries)
    md = [f"Critical speeds (a mode line crosses an excitation line, both seen in the frame "
          f"given; the solvers' lines are in the {cb.frame} frame):", "",
          f"| solver | crossing | excitation | whirl | frame | {p} | speed [rad/s] | "
          "speed [rpm] | frequency [Hz] | frequency [rad/s] | note |",
          "|---|---|---|---|---|---|---|---|---|---|---|"]
    md += [f"| {s} | {e['name']} | {e['order']}× {e['excitation']} | {e['whirl'] or '—'} | "
           f"{e['frame']} | {e['value']:.6f} | {e['speed_rad_s']:.6g} | {e['speed_rpm']:.6g} | "
           f"{e['frequency_hz']:.6g} | {e['frequency_rad_s']:.6g} | "
           f"{notes.get((s, e['name']), '')} |"
           for s, es in entries.items() for e in es]
    return md


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
