"""Mode shapes drawn in 3D (`xval modes`, scenes with a `mode_shape_3d` hook): the report figure
`mode_shapes.png` (one panel per mode) and the rerun recording `mode_shapes.rrd` (one 3D view per
mode, each solver's deflected structure animated over one period).

The modes are those of the first solver that returned shapes (the reference); every other
solver's mode of the same label (else of the nearest frequency, `metrics.match_modes`) is
overlaid in its colour. The hook turns each solver's own row layout into geometry in metres,
so solvers sampled at different stations overlay too. Mode shapes have no amplitude: each
solver's displacement is scaled so that its largest point displacement is `FRACTION` of the
structure's largest dimension, and turned to the reference's phase (least squares over the
nearest points of the two geometries), so a sign flip between solvers is not drawn as a
disagreement. Nothing here names a scene.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..analysis.metrics import frequency_errors, match_modes
from ..atomic import atomic_path
from ..physics.whirl import shown_label
from .recording import APPLICATION_ID, PALETTE
from .report import params_title

FRACTION = 0.1      # largest drawn displacement / the structure's largest dimension
FRAMES = 36         # frames per period in the recording
TIMELINE = "t_over_T"   # the recording's timeline: 1 s of it = one period of each mode
STYLES = ["-", "--", ":", "-."]      # line style per solver in the figure


@dataclass
class Panel:
    """One mode: its label and frequency (reference solver), the undeformed strips and each
    solver's scaled, phase-aligned displacement on its own strips."""
    label: str
    frequency_hz: float
    undeformed: list
    solvers: dict          # solver -> (list of points arrays, list of displacement arrays)


def _flat(strips):
    return np.vstack([p for p, _ in strips]), np.vstack([d for _, d in strips])


def structure_size(strips) -> float:
    pts = np.vstack([p for p, _ in strips])
    return float(np.max(np.ptp(pts, axis=0)))


def _scaled(strips, size):
    """Displacements scaled to FRACTION·size at the point that moves most."""
    _, d = _flat(strips)
    top = np.max(np.sqrt(np.sum(np.abs(d) ** 2, axis=1)))
    k = FRACTION * size / top if top > 0 else 0.0
    return [np.asarray(d, complex) * k for _, d in strips]


def _peak_phase(d):
    """exp(iα) that makes Re(d·e^{iα}) largest (a standing mode stored as complex becomes
    real; a whirl keeps its shape)."""
    s = np.sum(d * d)
    return np.exp(-0.5j * np.angle(s)) if abs(s) > 0 else 1.0


def _align(pts, d, ref_pts, ref_d):
    """exp(iα) minimising |d·e^{iα} − ref| over each point's nearest reference point."""
    near = np.argmin(np.sum((pts[:, None, :] - ref_pts[None, :, :]) ** 2, axis=2), axis=1)
    c = np.sum(np.conj(ref_d[near]) * d)
    return np.conj(c) / abs(c) if abs(c) > 0 else 1.0


def panels(scene, params, results) -> list[Panel]:
    """The panels of every mode of the reference solver (none when no solver gave shapes)."""
    ok = [r for r in results if r.status == "ok" and r.shapes is not None and len(r.shapes)]
    if not ok:
        return []
    ref = ok[0]
    pairs = {r.solver: dict(match_modes(list(ref.frequencies_hz), ref.labels,
                                        list(r.frequencies_hz), r.labels)) for r in ok[1:]}
    out = []
    for i, f in enumerate(ref.frequencies_hz):
        strips = scene.mode_shape_3d(params, ref.solver, ref.shapes[i])
        size = structure_size(strips)
        d = _scaled(strips, size)
        d = [x * _peak_phase(np.concatenate(d)) for x in d]
        ref_pts, ref_d = np.vstack([p for p, _ in strips]), np.vstack(d)
        solvers = {ref.solver: ([p for p, _ in strips], d)}
        for r in ok[1:]:
            j = pairs[r.solver].get(i)
            if j is None:
                continue
            s = scene.mode_shape_3d(params, r.solver, r.shapes[j])
            ds = _scaled(s, size)
            turn = _align(np.vstack([p for p, _ in s]), np.vstack(ds), ref_pts, ref_d)
            solvers[r.solver] = ([p for p, _ in s], [x * turn for x in ds])
        out.append(Panel(ref.labels[i] or f"mode {i + 1}", float(f),
                         [p for p, _ in strips], solvers))
    return out


def _whirls(ds) -> bool:
    d = np.vstack(ds)
    return np.max(np.abs(d.imag)) > 0.05 * np.max(np.abs(d))


def write_figure(path, panels_: list[Panel], colors: dict, title: str = ""):
    """One 3D panel per mode: the undeformed structure in grey, each solver's deflected
    structure at its peak (t = T/4 of the recording); where a mode whirls, the orbit of each
    strip's last point over a period."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from mpl_toolkits.mplot3d.art3d import Line3DCollection
    n = len(panels_)
    cols = min(4, int(np.ceil(np.sqrt(n))))
    rows = -(-n // cols)
    fig = plt.figure(figsize=(3.4 * cols, 3.0 * rows + 0.5))
    phase = np.exp(2j * np.pi * np.linspace(0, 1, 49))
    for k, pn in enumerate(panels_):
        ax = fig.add_subplot(rows, cols, k + 1, projection="3d", computed_zorder=False)
        # one collection per solver: a plot call per strip costs seconds for the helicopter
        ax.add_collection3d(Line3DCollection(pn.undeformed, colors="0.75", linewidths=0.8))
        every = [np.vstack(pn.undeformed)]
        for j, (solver, (pts, ds)) in enumerate(pn.solvers.items()):
            lines = [p + d.real for p, d in zip(pts, ds)]
            if _whirls(ds):
                lines += [p[-1] + np.real(np.outer(phase, d[-1])) for p, d in zip(pts, ds)]
            # a line style per solver (as in the Campbell diagram): coinciding lines show
            # every solver's colour in turn
            ax.add_collection3d(Line3DCollection(lines, colors=[colors[solver]],
                                                 linewidths=2.0 if j == 0 else 1.5,
                                                 linestyles=STYLES[j % len(STYLES)],
                                                 zorder=2 + j))
            every += lines
        allp = np.vstack(every)
        lo, hi = allp.min(axis=0), allp.max(axis=0)
        span = np.maximum(hi - lo, 0.3 * np.max(hi - lo))
        mid = 0.5 * (lo + hi)
        ax.set_xlim(mid[0] - span[0] / 2, mid[0] + span[0] / 2)
        ax.set_ylim(mid[1] - span[1] / 2, mid[1] + span[1] / 2)
        ax.set_zlim(mid[2] - span[2] / 2, mid[2] + span[2] / 2)
        ax.set_box_aspect(span)
        ax.locator_params(nbins=3)
        ax.tick_params(labelsize=5, pad=0)
        ax.set_title(f"{pn.label}: {pn.frequency_hz:.5g} Hz", fontsize=8)
    solvers = list(dict.fromkeys(s for pn in panels_ for s in pn.solvers))
    handles = [plt.Line2D([], [], color=colors[s], ls=STYLES[j % len(STYLES)], label=s)
               for j, s in enumerate(solvers)]
    handles.append(plt.Line2D([], [], color="0.75", label="undeformed"))
    fig.legend(handles=handles, loc="upper center", ncol=len(handles), fontsize=8,
               frameon=False)
    fig.text(0.5, 0.005, f"{title}largest displacement drawn = {FRACTION:.0%} of the "
             "structure's size (rotating frame, metres); whirling modes: the orbit of each "
             "strip's end",
             ha="center", va="bottom", fontsize=8)
    fig.subplots_adjust(left=0.01, right=0.99, bottom=0.04, top=1 - 0.45 / fig.get_figheight(),
                        wspace=0.05, hspace=0.15)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=90, format="png")
    plt.close(fig)
    return Path(path)


def mode_entity(k: int, pn: Panel) -> str:
    import rerun as rr
    return "modes/" + rr.escape_entity_path_part(f"{k + 1:02d}_{pn.label}".replace(" ", "_"))


def _frames(pts, ds, rot):
    """The strips of every frame, p + Im(z·d), as one Arrow array (frame-major): handing rerun
    tens of thousands of small arrays costs seconds for the helicopter."""
    import pyarrow as pa
    from rerun.components import LineStrip3DBatch
    P, D = np.vstack(pts), np.vstack(ds)
    flat = (P[None] + np.imag(rot[:, None, None] * D[None])).astype(np.float32).ravel()
    lengths = np.tile([len(p) for p in pts], len(rot))
    offsets = np.concatenate([[0], np.cumsum(lengths)]).astype(np.int32)
    dtype = LineStrip3DBatch._ARROW_DATATYPE
    inner = pa.FixedSizeListArray.from_arrays(pa.array(flat), type=dtype.value_type)
    return pa.ListArray.from_arrays(pa.array(offsets), inner, type=dtype)


def write_recording(path, panels_: list[Panel], colors: dict, recording_id: str):
    """Entities `modes/<NN label>/<solver>`: the deflected strips, q(t) = Im(d·e^{2πit/T})
    (shape·sin(2πt/T) for a standing mode) at FRAMES instants of one period on the timeline
    TIMELINE (1 s = one period); `modes/<NN label>/undeformed` static and faint. One 3D view
    per mode in the blueprint."""
    import rerun as rr
    import rerun.blueprint as rrb
    t = np.arange(FRAMES) / FRAMES
    rot = np.exp(2j * np.pi * t)
    views = [rrb.Spatial3DView(origin=f"/{mode_entity(k, pn)}",
                               name=f"{pn.label}: {pn.frequency_hz:.5g} Hz")
             for k, pn in enumerate(panels_)]
    bp = rrb.Blueprint(rrb.Grid(*views), collapse_panels=True)
    with atomic_path(path) as tmp, \
            rr.RecordingStream(APPLICATION_ID, recording_id=recording_id) as rec:
        rec.save(str(tmp), default_blueprint=bp)
        for k, pn in enumerate(panels_):
            ent = mode_entity(k, pn)
            size = structure_size([(p, None) for p in pn.undeformed])
            radius = 2e-3 * size
            rec.log(f"{ent}/undeformed",
                    rr.LineStrips3D(pn.undeformed, radii=radius, colors=[(170, 170, 170, 90)]),
                    static=True)
            for solver, (pts, ds) in pn.solvers.items():
                ent_s = f"{ent}/{solver}"
                rec.log(ent_s, rr.LineStrips3D.from_fields(colors=[colors[solver]],
                                                           radii=[1.5 * radius]), static=True)
                rec.send_columns(ent_s, indexes=[rr.TimeColumn(TIMELINE, duration=t)],
                                 columns=rr.LineStrips3D.columns(strips=_frames(pts, ds, rot))
                                 .partition([len(pts)] * FRAMES))
    return Path(path)


REPEATED = ("repeated frequency: the solvers' mode shapes span the same plane and may differ "
            "within it")


def repeated_frequencies(results) -> list[str]:
    """Report lines naming each solver's modes whose frequencies coincide within their error
    bars (the solver's own estimate, at least 1e-9 relative): any two shapes spanning such a
    mode's plane are valid, so the solvers' shapes may differ without either being wrong."""
    groups = {}
    for m in results:
        f = np.asarray(m.frequencies_hz, float)
        if m.status != "ok" or len(f) < 2:
            continue
        e = frequency_errors(m)
        e = np.zeros_like(f) if e is None else np.nan_to_num(e)
        labels = list(m.labels) if len(m.labels) == len(f) else [f"mode {i + 1}"
                                                                 for i in range(len(f))]
        whirl = m.whirl if m.whirl is not None and len(m.whirl) == len(f) else [None] * len(f)
        labels = [shown_label(lb, w) for lb, w in zip(labels, whirl)]    # no sense at rest
        order = np.argsort(f)
        run = [order[0]]
        for i in list(order[1:]) + [None]:     # runs of neighbours within their bars
            j = run[-1]
            if i is not None and abs(f[i] - f[j]) <= e[i] + e[j] + 1e-9 * max(abs(f[i]),
                                                                                abs(f[j])):
                run.append(i)
                continue
            if len(run) > 1:
                lo, hi = f"{f[run[0]]:.6g}", f"{f[run[-1]]:.6g}"
                key = (tuple(labels[k] for k in run), lo if lo == hi else f"{lo}–{hi}")
                groups.setdefault(key, []).append(m.solver)
            run = [i]
    return [f"- {' / '.join(names)} at {hz} Hz ({', '.join(s)}): {REPEATED}."
            for (names, hz), s in groups.items()]


def write(out_dir: Path, scene, params, results) -> dict:
    """Figure and recording into out_dir; returns the files and a sentence for the report
    ({} when no solver returned shapes)."""
    pn = panels(scene, params, results)
    if not pn:
        return {}
    colors = {r.solver: PALETTE[i % len(PALETTE)] for i, r in enumerate(results)}
    mpl = {s: tuple(c / 255 for c in rgb) for s, rgb in colors.items()}
    png = write_figure(out_dir / "mode_shapes.png", pn, mpl,
                       f"{scene.name}{params_title(scene, params)}: ")
    rrd = write_recording(out_dir / "mode_shapes.rrd", pn, colors,
                          f"mode-shapes-{out_dir.name}")
    solvers = list(dict.fromkeys(s for p in pn for s in p.solvers))
    text = (f"Modes of `{solvers[0]}` (label and frequency in each panel)"
            + (f", with the matching modes of {', '.join(f'`{s}`' for s in solvers[1:])} "
               "overlaid (each solver's own stations)" if len(solvers) > 1 else "")
            + f"; largest displacement drawn = {FRACTION:.0%} of the structure's size, "
            "rotating frame. `mode_shapes.rrd` animates each mode over one period "
            f"(timeline `{TIMELINE}`, 1 s = one period).")
    return {"figure": png, "recording": rrd, "text": text}
