"""Rerun recordings (rerun-sdk 0.41): columnar, one entity per solver under each channel so the
curves overlay, a 3D view of the bodies, and a blueprint that lays the comparison out.

Everything is logged after the runs with `send_columns` (per-step `log` costs more than a step
of a cheap integrator). One recording file per process: callers pass a path of their own.
"""
import numpy as np
import rerun as rr
import rerun.blueprint as rrb

from .atomic import atomic_path
from .report import analytic_curve

PALETTE = [(31, 119, 180), (255, 127, 14), (44, 160, 44), (214, 39, 40), (148, 103, 189),
           (140, 86, 75), (227, 119, 194), (127, 127, 127)]


def _time(t):
    return [rr.TimeColumn("sim_time", duration=np.asarray(t, float))]


def blueprint(scene, with_3d):
    plots = [rrb.TimeSeriesView(origin=f"/{ch}", name=ch) for ch in scene.channels]
    right = rrb.Grid(*plots)
    left = [rrb.Spatial3DView(origin="/world", name="3D")] if with_3d else []
    return rrb.Blueprint(rrb.Horizontal(rrb.Vertical(*left, rrb.TextDocumentView(
        origin="/summary", name="comparison")), right, column_shares=[1, 2]),
        collapse_panels=True)


def write_run_recording(path, result):
    scene, trs = result.scene, result.trajectories
    draw = scene.draw_3d
    # written under a temporary name and renamed when complete (the `with` block finalises
    # the file sink): a kill mid-write leaves the previous recording or none, never a cut one
    with atomic_path(path) as tmp, \
            rr.RecordingStream("xval", recording_id=f"{scene.name}-{path.parent.name}") as rec:
        rec.save(str(tmp), default_blueprint=blueprint(scene, draw is not None))
        for i, tr in enumerate(trs):
            color = PALETTE[i % len(PALETTE)]
            for ch in scene.channels:
                ent = f"{ch}/{tr.solver}"
                rec.log(ent, rr.SeriesLines(names=tr.solver, colors=[color], widths=1.5),
                        static=True)
                v = tr.channels[ch]
                ok = np.isfinite(v)
                if ok.any():
                    rec.send_columns(ent, indexes=_time(tr.t[ok]),
                                     columns=rr.Scalars.columns(scalars=v[ok]))
            if draw and tr.status in ("ok", "diverged"):
                draw(rec, result.params, tr, color, np.array([1.0 * i, 0.0, 0.0]))
        for ch in scene.channels:
            curve = analytic_curve(result, ch)
            if curve is not None:
                t, v, label = curve
                ent = f"{ch}/{label}"
                rec.log(ent, rr.SeriesLines(names=label, colors=[[0, 0, 0]], widths=1.0),
                        static=True)
                rec.send_columns(ent, indexes=_time(t), columns=rr.Scalars.columns(scalars=v))
        rec.log("summary", rr.TextDocument(summary_markdown(result),
                                           media_type=rr.MediaType.MARKDOWN), static=True)
    return path


def summary_markdown(result):
    lines = [f"# {result.scene.name}", "", "| solver | status | wall s |", "|---|---|---|"]
    lines += [f"| {t.solver} | {t.status} | {t.wall_s:.3g} |" for t in result.trajectories]
    lines += ["", "| a | b | channel | max rel | verdict |", "|---|---|---|---|---|"]
    lines += [f"| {c.a} | {c.b} | {c.channel} | {c.max_rel:.2e} | {c.verdict} |"
              for c in result.comparisons]
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
