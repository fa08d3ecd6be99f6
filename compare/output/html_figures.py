"""The interactive figures of report.html as plotly.js specs ({"data", "layout"} dicts that
html_report.py hands to `Plotly.newPlot`), built from plain numbers: no plotly Python objects
(their validation would cost more than the run's PNGs). What the PNGs show: each channel per
solver over time, |Δ| of the key channel per pair against its bound, the energy drift; for a
modes result the frequencies per solver and the Campbell lines; for any result with
comparisons each deviation against its bound."""
from __future__ import annotations

import math

import numpy as np

MAX_POINTS = 2000   # per trace: a longer trajectory is drawn at every k-th sample (and its last)


def _xs(v):
    """A number list for JSON: non-finite values as None (a gap in the line)."""
    return [x if math.isfinite(x) else None for x in np.asarray(v, float).tolist()]


def _thin(t, *ys):
    n = len(t)
    if n <= MAX_POINTS:
        return (t, *ys)
    idx = np.unique(np.r_[np.arange(0, n, math.ceil(n / MAX_POINTS)), n - 1])
    return (t[idx], *(y[idx] for y in ys))


def _layout(title, xlabel, ylabel, log_y=False, log_x=False, height=320):
    return {"title": {"text": title, "font": {"size": 13}}, "height": height,
            "margin": {"l": 70, "r": 20, "t": 40, "b": 45},
            "xaxis": {"title": {"text": xlabel}, "type": "log" if log_x else "linear"},
            "yaxis": {"title": {"text": ylabel}, "type": "log" if log_y else "linear",
                      "exponentformat": "e"},
            "legend": {"font": {"size": 10}}, "hovermode": "closest"}


def _label(scene, ch):
    return f"{ch} [{scene.unit(ch) or '–'}]"


def run_figures(result, analytic_curve, flat) -> list[dict]:
    """A time run's figures: one per channel (the closed form dashed where the scene has
    one), |Δ key channel|(t) per pair with each pair's bound, the energy drift per solver.
    A channel `flat(values)` calls flat is drawn as its change from the first value, as the
    PNG draws it."""
    sc, trs = result.scene, result.trajectories
    figs = []
    for ch in sc.channels:
        data = []
        ref0 = next((tr.channels[ch][0] for tr in trs if np.isfinite(tr.channels[ch][0])),
                    0.0) if any(flat(tr.channels[ch]) for tr in trs) else 0.0
        for tr in trs:
            t, v = _thin(tr.t, tr.channels[ch] - ref0)
            data.append({"x": _xs(t), "y": _xs(v), "name": tr.solver, "mode": "lines",
                         "type": "scatter"})
        curve = analytic_curve(result, ch)
        if curve is not None:
            t, v = _thin(np.asarray(curve[0]), np.asarray(curve[1]) - ref0)
            data.append({"x": _xs(t), "y": _xs(v), "name": curve[2], "mode": "lines",
                         "type": "scatter", "line": {"dash": "dash", "color": "black"}})
        figs.append({"id": f"channel-{ch}", "data": data,
                     "layout": _layout(ch, "t [s]", f"{ch} − {ref0:.10g} [{sc.unit(ch) or '–'}]"
                                       if ref0 else _label(sc, ch))})
    ok = [tr for tr in trs if tr.status == "ok"]
    key = sc.key_channel
    if key and len(ok) > 1:
        bounds = {(c.a, c.b): c.tolerance * c.scale for c in result.comparisons
                  if c.channel == key}
        data = []
        for i, a in enumerate(ok):
            for b in ok[i + 1:]:
                t, d = _thin(a.t, np.abs(a.channels[key] - b.channels[key]))
                data.append({"x": _xs(t), "y": _xs(np.maximum(d, 1e-17)), "mode": "lines",
                             "type": "scatter", "name": f"{a.solver} − {b.solver}",
                             "legendgroup": f"{a.solver}-{b.solver}"})
                bound = bounds.get((a.solver, b.solver))
                if bound is not None and math.isfinite(bound) and bound > 0:
                    data.append({"x": [float(a.t[0]), float(a.t[-1])], "y": [bound, bound],
                                 "mode": "lines", "type": "scatter",
                                 "name": f"bound {a.solver} − {b.solver}",
                                 "legendgroup": f"{a.solver}-{b.solver}",
                                 "line": {"dash": "dot", "width": 1}})
        figs.append({"id": "deviation", "data": data,
                     "layout": _layout(f"|Δ {key}| between solvers, against its bound "
                                       "(error estimates + allowance, dotted)", "t [s]",
                                       f"|Δ {_label(sc, key)}|", log_y=True)})
    if sc.energy_channel and ok:
        data = []
        for tr in ok:
            e = tr.channels[sc.energy_channel]
            t, d = _thin(tr.t, np.abs(e - e[0]))
            data.append({"x": _xs(t), "y": _xs(np.maximum(d, 1e-17)), "mode": "lines",
                         "type": "scatter", "name": tr.solver})
        figs.append({"id": "energy-drift", "data": data,
                     "layout": _layout("drift of the energy balance", "t [s]",
                                       "|E(t) − E(0)| [J]", log_y=True)})
    return figs


def bound_figure(comparisons, label=lambda c: "") -> dict | None:
    """Each comparison's deviation max|Δ| against its bound (error estimates + allowance)
    on log axes, the line |Δ| = bound dashed: below it agrees. `comparisons`: JSON dicts."""
    pts = [(c, c.get("deviation"), (c.get("tolerance") or 0) * (c.get("scale") or 0))
           for c in comparisons]
    pts = [(c, d, b) for c, d, b in pts
           if d is not None and math.isfinite(d) and math.isfinite(b) and b > 0]
    if not pts:
        return None
    # a deviation of exactly 0 is drawn a decade below the smallest number shown (log axes)
    floor = min(v for _, d, b in pts for v in (d, b) if v > 0) / 10
    data, by = [], {}
    for c, d, b in pts:
        by.setdefault(c["verdict"], []).append((c, d, b))
    for verdict, rows in by.items():
        data.append({"x": [b for _, _, b in rows], "y": [max(d, floor) for _, d, _ in rows],
                     "text": [f"{label(c)}{c['a']} vs {c['b']} {c['channel']}: max|Δ| "
                              f"{d:.3g}, bound {b:.3g}, Δ/bound {d / b:.3g}"
                              for c, d, b in rows],
                     "hoverinfo": "text", "mode": "markers", "type": "scatter",
                     "name": verdict})
    lo, hi = floor, max(max(b for _, _, b in pts), max(d for _, d, _ in pts))
    data.append({"x": [lo, hi], "y": [lo, hi], "mode": "lines", "type": "scatter",
                 "name": "|Δ| = bound", "line": {"dash": "dash", "color": "black", "width": 1}})
    return {"id": "deviation-vs-bound", "data": data,
            "layout": _layout("deviation max|Δ| against its bound (below the line: within)",
                              "bound = error estimates + allowance", "max|Δ|", log_y=True,
                              log_x=True, height=380)}


def modes_figures(obj: dict, unit=lambda name: "") -> list[dict]:
    """A modes result's figures: the frequencies per solver, and the Campbell lines in the
    figure's frame where the scene sweeps (`unit(parameter)`: its unit)."""
    figs = []
    runs = [r for r in obj.get("runs", []) if r.get("frequencies_hz")]
    if runs:
        data = [{"x": r.get("labels") or [f"mode {i + 1}" for i in range(
                     len(r["frequencies_hz"]))],
                 "y": _xs(r["frequencies_hz"]), "name": r["solver"], "mode": "markers",
                 "type": "scatter", "marker": {"size": max(12 - 3 * i, 5), "opacity": 0.8}}
                for i, r in enumerate(runs)]
        lay = _layout("frequencies per solver", "mode", "f [Hz]")
        lay["xaxis"]["type"] = "category"
        lay["yaxis"]["rangemode"] = "tozero"
        figs.append({"id": "frequencies", "data": data, "layout": lay})
    camp = obj.get("campbell") or {}
    frame = camp.get("figure_frame") or camp.get("frame")
    lines = (camp.get("lines_hz_by_frame") or {}).get(frame) or camp.get("lines_hz") or {}
    x = camp.get("values")
    if x and lines:
        data = []
        for i, (solver, by_line) in enumerate(lines.items()):
            for name, ys in by_line.items():
                data.append({"x": _xs(x), "y": _xs([np.nan if y is None else y for y in ys]),
                             "mode": "lines", "type": "scatter", "name": f"{solver}: {name}",
                             "legendgroup": solver,
                             "line": {"dash": ["solid", "dash", "dot", "dashdot"][i % 4]}})
        par = camp.get("parameter", "")
        figs.append({"id": "campbell", "data": data,
                     "layout": _layout(f"Campbell diagram ({frame} frame)",
                                       f"{par} [{unit(par) or '–'}]", "f [Hz]", height=420)})
    return figs
