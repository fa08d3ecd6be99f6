"""The files of `xval identify`: a record (CSV with a header row or .npz: `t` and channel
columns — what `--synthesise` writes and `--data` reads), and the study's folder: report.md,
identify.json, fit.png (each channel of the record with every solver's fitted model over it,
and the residuals) and, with a Poincaré section, poincare.png."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..atomic import atomic_path
from .study import write_study


def write_record(path, rec: dict) -> Path:
    """`rec` ({"t": …, channel: …}) as .npz or (any other suffix) CSV, atomically."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    cols = ["t", *[k for k in rec if k != "t"]]
    if path.suffix == ".npz":
        with atomic_path(path) as tmp:
            with open(tmp, "wb") as fh:
                np.savez(fh, **{k: np.asarray(rec[k], float) for k in cols})
        return path
    table = np.column_stack([np.asarray(rec[k], float) for k in cols])
    with atomic_path(path) as tmp:
        np.savetxt(tmp, table, delimiter=",", header=",".join(cols), comments="", fmt="%.17g")
    return path


def _draw(result, png: Path):
    from matplotlib.figure import Figure
    rec, d = result.record, result.data
    chans = d["channels"]
    fig = Figure(figsize=(9, 2.2 * len(chans) + 0.6))
    axes = fig.subplots(len(chans), 2, squeeze=False, gridspec_kw={"width_ratios": (3, 1)})
    t = rec["t"]
    for k, c in enumerate(chans):
        ax, ar = axes[k]
        ax.plot(t, rec[c], ".", ms=1.5, color="0.55", label="data")
        for j, (name, y) in enumerate(result.curves.items()):
            ax.plot(t, y[c], lw=0.8, color=f"C{j}", label=name)
            ar.plot(t, rec[c] - y[c], ".", ms=1, color=f"C{j}", label=name)
        ax.set_ylabel(c, fontsize=8)
        ar.set_ylabel("data − fit", fontsize=8)
        if k == 0:
            ax.legend(fontsize=7, loc="upper right")
    axes[-1][0].set_xlabel("t [s]")
    axes[-1][1].set_xlabel("t [s]")
    fig.suptitle(f"{d['scene']}: fit of {', '.join(d['unknowns'])} to {Path(d['data']).name}",
                 fontsize=9)
    fig.tight_layout()
    with atomic_path(png) as tmp:
        fig.savefig(tmp, dpi=100, format="png")


def _draw_poincare(result, png: Path):
    from matplotlib.figure import Figure
    pc = result.data["poincare"]
    fig = Figure(figsize=(5.5, 5))
    ax = fig.add_subplot()
    for j, (name, pts) in enumerate(pc["sections"].items()):
        x, y = np.asarray(pts["x"]), np.asarray(pts["y"])
        style = dict(ls="none", marker=".", color="k") if name == "data" else dict(
            ls="-", marker="o", mfc="none", color=f"C{j}")
        ax.plot(1e6 * x, 1e6 * y, ms=3, lw=0.5, label=name, **style)
    ax.set(xlabel=f"{pc['x']} [µm]", ylabel=f"{pc['y']} [µm]",
           title=f"{pc['x'][:-2]} once per revolution at {pc['angle']} = {pc['phase']:g} + 2πk")
    ax.legend(fontsize=7)
    fig.tight_layout()
    with atomic_path(png) as tmp:
        fig.savefig(tmp, dpi=100, format="png")


def _record_poincare(result, path: Path):
    """poincare.rrd: each section as 2D points (µm) per source, on the timeline `revolution`
    (k), so the viewer steps through the revolutions; the summary as Markdown."""
    import rerun as rr

    from .recording import APPLICATION_ID, PALETTE
    pc = result.data["poincare"]
    with atomic_path(path) as tmp, \
            rr.RecordingStream(APPLICATION_ID,
                               recording_id=f"{result.data['scene']}-poincare") as rec:
        rec.save(str(tmp))
        for j, (name, sec) in enumerate(pc["sections"].items()):
            color = (0, 0, 0) if name == "data" else PALETTE[j % len(PALETTE)]
            ent = "section/" + "".join(ch if ch.isalnum() else "_" for ch in name)
            pts = 1e6 * np.column_stack([sec["x"], sec["y"]])
            rec.log(f"{ent}/all", rr.Points2D(pts, radii=0.05, colors=[color],
                                              labels=[name] * len(pts)), static=True)
            for k, p in zip(sec["k"], pts):
                rec.set_time("revolution", sequence=int(k))
                rec.log(f"{ent}/now", rr.Points2D([p], radii=0.15, colors=[color]))
        rec.log("summary", rr.TextDocument("\n".join(result.markdown()),
                                           media_type=rr.MediaType.MARKDOWN), static=True)
    return path


def write_identify(out_dir: Path, result) -> Path:
    out_dir.mkdir(parents=True, exist_ok=True)
    md = result.markdown()
    files = {}
    if result.record is not None and result.curves:
        _draw(result, out_dir / "fit.png")
        files["fit"] = str(out_dir / "fit.png")
        md += ["", "![fit over the data](fit.png)"]
    if result.data.get("poincare"):
        _draw_poincare(result, out_dir / "poincare.png")
        files["poincare"] = str(out_dir / "poincare.png")
        files["poincare_rrd"] = str(_record_poincare(result, out_dir / "poincare.rrd"))
        md += ["", "![Poincaré section](poincare.png)"]
    result.data["files"] = files
    write_study(out_dir, md, result.data, result.JSON)
    return out_dir


def write_detection(out_dir: Path, result) -> Path:
    """report.md, detection.json and detection.png: the limit against the noise factor, one
    panel per channel set, a line per speed, a marker per solver (the boundary: a defect
    above its line is told from none at the stated rates)."""
    from matplotlib.figure import Figure
    out_dir.mkdir(parents=True, exist_ok=True)
    d = result.data
    sets = list(d["channel_sets"])
    fig = Figure(figsize=(4 * len(sets), 3.8))
    axes = fig.subplots(1, len(sets), sharey=True, squeeze=False)[0]
    solvers = list(dict.fromkeys(r["solver"] for r in d["rows"]))
    marks = "os^dv"
    for ax, label in zip(axes, sets):
        for j, w in enumerate(d["speeds"]):
            for m, s in enumerate(solvers):
                r = next((r for r in d["rows"] if r["set"] == label and r["speed"] == w
                          and r["solver"] == s and r["status"] == "ok"), None)
                if r is not None:
                    ax.loglog(d["noise_factors"], np.asarray(r["limit"]) * 1e6,
                              marker=marks[m % len(marks)], mfc="none", color=f"C{j}",
                              lw=0.8, label=f"{d['speed_param']} {w:g}, {s}")
        ax.set(title=label, xlabel="noise × the scene's σ")
        ax.grid(alpha=0.3, which="both")
    axes[0].set_ylabel(f"smallest {d['size']} [µm]")
    axes[0].legend(fontsize=6)
    fig.suptitle(f"{d['scene']}: false alarm {d['alpha']:g}, miss {d['beta']:g}", fontsize=9)
    fig.tight_layout()
    with atomic_path(out_dir / "detection.png") as tmp:
        fig.savefig(tmp, dpi=100, format="png")
    result.data["files"] = {"map": str(out_dir / "detection.png")}
    write_study(out_dir, result.markdown() + ["", "![detection limits](detection.png)"],
                result.data, result.JSON)
    return out_dir
