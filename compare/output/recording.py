"""Rerun recordings (rerun-sdk 0.41) a reviewer can review: every channel per solver overlaid,
the bodies in 3D from every solver (the scene's `draw_3d`, one colour per solver — the plots'
palette), where the solvers part (|Δ|(t) per compared pair and channel against the bound the
verdict used), the events on the timeline (findings with a time, a solver's failure), the
parameters and the verdict table, and a blueprint whose first screen answers "do they agree,
and where not".

Everything is logged after the runs with `send_columns` (per-step `log` costs more than a step
of a cheap integrator). One recording file per process: callers pass a path of their own; all
recordings share the application id "xval", so the viewer opens a campaign's cases together.

Entities: `<channel>/<solver>` (SI), `deviation/<channel>/<a>~<b>` = log10 |Δ|(t) with
`.../bound` = log10(error estimates + allowance) (log10 so the viewer's linear axis reads as a
log scale), `events` (TextLog at each event's time), `world/<solver>/…` (3D), `summary` and
`params` (Markdown).
"""
import numpy as np
import rerun as rr
import rerun.blueprint as rrb

from ..analysis.verdict import Verdict
from ..atomic import atomic_path
from .report import analytic_curve, source_line
from .tables import VERDICT_HEADER, markdown, verdict_rows

PALETTE = [(31, 119, 180), (255, 127, 14), (44, 160, 44), (214, 39, 40), (148, 103, 189),
           (140, 86, 75), (227, 119, 194), (127, 127, 127)]
APPLICATION_ID = "xval"


def _time(t):
    return [rr.TimeColumn("sim_time", duration=np.asarray(t, float))]


def pair_entity(channel, a, b):
    return f"deviation/{channel}/{rr.escape_entity_path_part(f'{a}~{b}')}"


def view_channels(scene):
    return scene.view_channels or tuple(c for c in (scene.key_channel, scene.energy_channel)
                                        if c)


def blueprint(scene, with_3d):
    """3D and the verdicts on the left; the key channels and where the solvers part on the
    right; every other channel in a tab behind them."""
    key = view_channels(scene)
    left = [rrb.Spatial3DView(origin="/world", name="3D")] if with_3d else []
    left += [rrb.Tabs(rrb.TextDocumentView(origin="/summary", name="verdicts"),
                      rrb.TextDocumentView(origin="/params", name="parameters")),
             rrb.TextLogView(origin="/events", name="events")]
    channels = rrb.Grid(*[rrb.TimeSeriesView(origin=f"/{ch}", name=ch) for ch in key])
    others = rrb.Grid(*[rrb.TimeSeriesView(origin=f"/{ch}", name=ch) for ch in scene.channels
                        if ch not in key]) if len(scene.channels) > len(key) else None
    deviations = rrb.Grid(*[rrb.TimeSeriesView(origin=f"/deviation/{ch}",
                                               name=f"log10 |Δ| {ch}") for ch in key
                            if ch in scene.tolerances])
    right = rrb.Vertical(rrb.Tabs(*[v for v in (channels, others) if v is not None]),
                         deviations)
    return rrb.Blueprint(rrb.Horizontal(rrb.Vertical(*left), right, column_shares=[1, 2]),
                         collapse_panels=True)


def _series(rec, ent, t, v, name, color, width=1.5):
    rec.log(ent, rr.SeriesLines(names=name, colors=[color], widths=width), static=True)
    ok = np.isfinite(v)
    if ok.any():
        rec.send_columns(ent, indexes=_time(t[ok]), columns=rr.Scalars.columns(scalars=v[ok]))


def _deviations(rec, result, colors):
    """log10 |Δ|(t) per compared pair and channel, and the bound the verdict weighed it
    against (the two error estimates over time plus the allowance)."""
    trs = {t.solver: t for t in result.trajectories}
    for c in result.comparisons:
        if c.verdict == Verdict.SKIPPED:
            continue
        a = trs[c.a]
        if c.formula:          # a solver against a closed form (FormulaCheck) and its own error
            fc = next(f for f in result.scene.formula_checks
                      if f.label == c.b and f.channel == c.channel)
            d = np.abs(a.channels[c.channel] - fc.formula(result.params, a.t))
            errs = [a.errors.get(c.channel)]
        else:
            b = trs[c.b]
            d = np.abs(a.channels[c.channel] - b.channels[c.channel])
            errs = [a.errors.get(c.channel), b.errors.get(c.channel)]
        ent = pair_entity(c.channel, c.a, c.b)
        _series(rec, ent, a.t, np.log10(np.maximum(d, 1e-300)), f"{c.a}~{c.b}",
                colors[c.a if c.formula else c.b])
        bound = np.full(len(a.t), c.allowance)       # NaN where the formula states none
        if all(e is not None for e in errs):
            bound = bound + sum(errs)
        _series(rec, f"{ent}/bound", a.t, np.log10(np.maximum(bound, 1e-300)),
                f"bound {c.a}~{c.b}", (0, 0, 0), width=1.0)


def _events(rec, result):
    """Findings with a time and every solver's failure, each at its time on the timeline."""
    for f in result.findings:
        for solver, t in (f.at or {}).items():
            rec.set_time("sim_time", duration=float(t))
            rec.log("events", rr.TextLog(f"{f.name} ({solver}): {f.text}", level="INFO"))
    for tr in result.trajectories:
        if tr.t_fail is not None and tr.status != "ok":
            rec.set_time("sim_time", duration=float(tr.t_fail))
            rec.log("events", rr.TextLog(f"{tr.solver} {tr.status}: {tr.reason}",
                                         level="WARN"))


def write_run_recording(path, result):
    scene, trs = result.scene, result.trajectories
    draw = scene.draw_3d
    colors = {tr.solver: PALETTE[i % len(PALETTE)] for i, tr in enumerate(trs)}
    # written under a temporary name and renamed when complete (the `with` block finalises
    # the file sink): a kill mid-write leaves the previous recording or none, never a cut one
    with atomic_path(path) as tmp, \
            rr.RecordingStream(APPLICATION_ID,
                               recording_id=f"{scene.name}-{path.parent.name}") as rec:
        rec.save(str(tmp), default_blueprint=blueprint(scene, draw is not None))
        for tr in trs:
            for ch in scene.channels:
                _series(rec, f"{ch}/{tr.solver}", tr.t, tr.channels[ch], tr.solver,
                        colors[tr.solver])
            if draw and tr.status in ("ok", "diverged"):
                # overlaid at one place: where two solvers part, their bodies separate
                draw(rec, result.params, tr, colors[tr.solver], np.zeros(3))
        for ch in scene.channels:
            curve = analytic_curve(result, ch)
            if curve is not None:
                t, v, label = curve
                _series(rec, f"{ch}/{label}", t, v, label, (0, 0, 0), width=1.0)
        _deviations(rec, result, colors)
        rec.log("summary", rr.TextDocument(summary_markdown(result),
                                           media_type=rr.MediaType.MARKDOWN), static=True)
        rec.log("params", rr.TextDocument(params_markdown(result),
                                          media_type=rr.MediaType.MARKDOWN), static=True)
        _events(rec, result)
    return path


def summary_markdown(result):
    lines = [f"# {result.scene.name}", "", "| solver | status | wall s |", "|---|---|---|"]
    lines += [f"| {t.solver} | {t.status} | {t.wall_s:.3g} |" for t in result.trajectories]
    lines += ["", markdown(VERDICT_HEADER, verdict_rows(result.comparisons))]
    lines += ["", "## Findings", ""] + [f"- {f.text}" for f in result.findings]
    return "\n".join(lines)


def params_markdown(result):
    sc = result.scene
    lines = [f"# {sc.title}", "", source_line(sc), "", "| parameter | value | unit |",
             "|---|---|---|"]
    for p in sc.params:
        v = result.params[p.name]
        v = ", ".join(f"{x:g}" for x in v) if isinstance(v, np.ndarray) else v
        lines.append(f"| {p.name} | {v} | {p.unit} |")
    return "\n".join(lines)


def load_scalar_series(path, entity, timeline="sim_time"):
    """Read one scalar entity back from an .rrd (for tests and post-processing)."""
    import pyarrow as pa
    import pyarrow.compute as pc
    from rerun.chunk import RrdReader
    ts, vs = [], []
    for chunk in RrdReader(str(path)).stream().filter(content=entity, is_static=False,
                                                      components="Scalars:scalars"):
        rb = chunk.to_record_batch()
        ts.append(rb.column(timeline).cast(pa.int64()).to_numpy(zero_copy_only=False) * 1e-9)
        vs.append(pc.list_flatten(rb.column("Scalars:scalars")).to_numpy(zero_copy_only=False))
    if not ts:
        return np.array([]), np.array([])
    t, v = np.concatenate(ts), np.concatenate(vs)
    o = np.argsort(t, kind="stable")
    return t[o], v[o]


def load_rows(path, entity, component, timeline="sim_time"):
    """(times, values) of one temporal component of an entity read back from an .rrd, e.g.
    ("world/mujoco", "Transform3D:translation") or ("events", "TextLog:text")."""
    import pyarrow as pa
    from rerun.chunk import RrdReader
    ts, vs = [], []
    for chunk in RrdReader(str(path)).stream().filter(content=entity, is_static=False,
                                                      components=component):
        rb = chunk.to_record_batch()
        ts.append(rb.column(timeline).cast(pa.int64()).to_numpy(zero_copy_only=False) * 1e-9)
        vs += rb.column(component).to_pylist()
    if not ts:
        return np.array([]), []
    t = np.concatenate(ts)
    o = np.argsort(t, kind="stable")
    return t[o], [vs[i] for i in o]
