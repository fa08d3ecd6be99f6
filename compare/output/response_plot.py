"""The folder of `xval response`: report.md, response.json, bode.png (amplitude and phase lag
vs speed, every solver's curve with its error bars, the critical speed marked) and polar.png
(the response phasor relative to the heavy spot, every solver)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..atomic import atomic_path
from .study import write_study

MARKERS = {"frequency": ("-", "."), "time": ("none", "o")}


def _draw(result, bode: Path, polar: Path):
    # bare Figures: no pyplot state, the caller's backend and rcParams stay as they were
    from matplotlib.figure import Figure
    d = result.data
    fig = Figure(figsize=(7.5, 6))
    ax_a, ax_p = fig.subplots(2, 1, sharex=True)
    figp = Figure(figsize=(5.5, 5.5))
    ax_r = figp.add_subplot(projection="polar")
    for k, name in enumerate(result.solvers):
        w, a, err = result.curve(name)
        ls, mk = MARKERS["frequency" if name in d["frequency"] else "time"]
        style = dict(ls=ls, marker=mk, ms=4 if mk == "o" else 3, mfc="none", color=f"C{k}",
                     label=name)
        ax_a.errorbar(w, np.abs(a), yerr=err, **style)
        ax_p.plot(w, result.lag_deg(a), **style)
        z = d["high_spot"] * a
        ax_r.plot(np.angle(z), np.abs(z), **style)
    for ax in (ax_a, ax_p):
        ax.axvline(d["critical_rad_s"], color="0.6", lw=0.8, ls=":")
        ax.grid(alpha=0.3)
    ax_a.set_ylabel("|a|")
    ax_a.set_yscale("log")
    rpm = ax_a.secondary_xaxis("top", functions=(lambda w: w * 30 / np.pi,
                                                 lambda r: r * np.pi / 30))
    rpm.set_xlabel("rotation speed [rpm]", fontsize=8)
    rpm.tick_params(labelsize=8)
    from ..scenes import get_scene
    from .report import params_title
    given = params_title(get_scene(d["scene"]), d.get("params"))[2:-1]   # e, c_ext among them
    ax_a.set_title(f"{d['scene']}: unbalance response ({d['amplitude']})"
                   + (f"\n{given}" if given else ""), fontsize=9)
    ax_p.set_ylabel("phase lag [deg]")
    ax_p.set_xlabel("spin [rad/s] (dotted: first critical)")
    ax_a.legend(fontsize=8)
    ax_r.set_title("high spot relative to the heavy spot (angle 0)", fontsize=9)
    ax_r.legend(fontsize=7, loc="lower left")
    for f, path in ((fig, bode), (figp, polar)):
        f.tight_layout()
        with atomic_path(path) as tmp:
            f.savefig(tmp, dpi=110, format="png")


def write_response(out_dir: Path, result) -> Path:
    out_dir.mkdir(parents=True, exist_ok=True)
    _draw(result, out_dir / "bode.png", out_dir / "polar.png")
    md = result.markdown() + ["", "![Bode](bode.png)", "", "![polar](polar.png)"]
    result.data.update(files={"bode": str(out_dir / "bode.png"),
                              "polar": str(out_dir / "polar.png")})
    write_study(out_dir, md, result.data, result.JSON)
    return out_dir
