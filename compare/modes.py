"""`xval modes`: natural frequencies from every solver that can linearise, matched mode by mode;
for rotor scenes a Campbell sweep with critical speeds, and frequencies identified from free
responses of the time-domain solvers."""
from pathlib import Path

import numpy as np
from scipy.optimize import brentq

from . import metrics, solvers
from .atomic import write_json, write_text
from .errors import BadInput
from .identify import fft_peak, matrix_pencil, transverse_components
from .runner import new_run_dir
from .scenes import get_scene


def campbell(solver, params, spins):
    """(backward, forward) whirl lines [rad/s] over `spins` from one solver."""
    leaf = solver.leaf("rotor-whirl")
    if hasattr(leaf, "whirl_sweep"):
        b, f = leaf.whirl_sweep(params, spins)
        return np.asarray(b, float), np.asarray(f, float)
    res = [leaf.modes(dict(params, spin=s), {}) for s in spins]
    return (np.array([2 * np.pi * r["frequencies_hz"][0] for r in res]),
            np.array([2 * np.pi * r["frequencies_hz"][1] for r in res]))


def critical_speeds(solver, params, spins, lines):
    """Spins where a whirl line crosses the 1× line, refined by root finding on the solver."""
    out = {}
    for k, name in enumerate(("backward", "forward")):
        g = lines[k] - spins
        idx = np.nonzero(np.sign(g[:-1]) != np.sign(g[1:]))[0]
        if len(idx):
            i = idx[0]
            fun = lambda s: campbell(solver, params, np.array([s]))[k][0] - s   # noqa: E731
            try:
                out[name] = brentq(fun, spins[i], spins[i + 1], xtol=1e-12, rtol=1e-14)
            except Exception:
                # a body-frame linearisation loses the mode exactly at the crossing (its
                # body-frame frequency is 0 there): fit a parabola through points beside it
                s0 = spins[i] - g[i] * (spins[i + 1] - spins[i]) / (g[i + 1] - g[i])
                ds = 1e-3 * (spins[i + 1] - spins[i])
                x = s0 + ds * np.array([-3.0, -2.0, 2.0, 3.0])
                y = campbell(solver, params, x)[k] - x
                roots = np.roots(np.polyfit(x - s0, y, 2)).real + s0
                out[name] = float(roots[np.argmin(np.abs(roots - s0))])
    return out


def free_response_frequencies(params, time_solvers, t_end=2.0, dt=1e-3, tilt0=1e-3):
    """Release the rotor with a small tilt and no torque; identify the tilt frequency from each
    time-domain solver's record, for several record lengths (convergence)."""
    spin_scene = get_scene("rotor-spinup")
    p = spin_scene.resolve()
    for k in ("l", "k", "m", "R", "eccentricity", "gravity"):
        p[k] = params[k]
    p.update(torque=0.0, tilt0=tilt0, t_end=t_end, output_dt=dt)
    rows = []
    for s in time_solvers:
        leaf = s.leaf(spin_scene.name)
        settings = dict(leaf.DEFAULT_SETTINGS)
        if settings.get("dt") and settings["dt"] > dt:     # fixed steps must fit the record grid
            settings["dt"] = dt
        tr = solvers.simulate(spin_scene, s, p, settings)
        if tr.status != "ok" or "orientation" not in tr.extra:
            rows.append({"solver": s.name, "status": tr.status, "reason": tr.reason})
            continue
        gx, _ = transverse_components(tr.extra["orientation"])
        lengths = [t_end / 8, t_end / 4, t_end / 2, t_end]
        rec = {"solver": s.name, "status": "ok", "record_s": lengths, "matrix_pencil": [],
               "fft": []}
        for T in lengths:
            n = int(round(T / dt)) + 1
            w, _ = matrix_pencil(gx[:n], dt, n_modes=2)
            rec["matrix_pencil"].append(float(w[np.argmax(w > 1.0)]) if np.any(w > 1) else None)
            rec["fft"].append(float(fft_peak(gx[:n], dt)))
        rows.append(rec)
    return rows


def _campbell_png(path, spins, lines, crit):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for name, (b, f) in lines.items():
        ax.plot(spins, b, lw=1, label=f"{name} backward")
        ax.plot(spins, f, lw=1, ls="--", label=f"{name} forward")
    ax.plot(spins, spins, "k:", lw=1, label="1× spin")
    for name, c in crit.items():
        for kind, s in c.items():
            ax.plot([s], [s], "o", ms=5)
            ax.annotate(f"{kind} {s:.3f}", (s, s), fontsize=7)
    ax.set_xlabel("spin Ω [rad/s]")
    ax.set_ylabel("whirl frequency [rad/s]")
    ax.set_ylim(0, max(np.max(f) for _, f in lines.values()) * 1.1)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=6)
    ax.set_title("Campbell diagram")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _campbell_rrd(path, spins, lines):
    import rerun as rr
    with rr.RecordingStream("xval", recording_id=f"campbell-{path.parent.name}") as rec:
        rec.save(str(path))
        idx = [rr.TimeColumn("spin", duration=spins)]       # 1 s on this timeline = 1 rad/s
        rec.send_columns("campbell/one_x", indexes=idx, columns=rr.Scalars.columns(scalars=spins))
        for name, (b, f) in lines.items():
            for kind, v in (("backward", b), ("forward", f)):
                rec.send_columns(f"campbell/{kind}/{name}", indexes=idx,
                                 columns=rr.Scalars.columns(scalars=v))
    return path


def run_modes(scene_name, solver_names, overrides, out, log=print, campbell_sweep=True,
              identify=True, out_dir=None):
    """`out_dir` given: write there (a campaign case); else a new run folder under `out`."""
    sc = get_scene(scene_name)
    if sc.kind != "modes":
        raise BadInput(f"scene {sc.name!r} is a time-domain scene: use `xval run {sc.name}`")
    params = sc.resolve(overrides)
    chosen = solvers.pick(sc, solver_names)
    out_dir = Path(out_dir or new_run_dir(out, sc.name))
    out_dir.mkdir(parents=True, exist_ok=True)
    results = []
    for s in chosen:
        log(f"{sc.name}: {s.name} …")
        results.append(solvers.modes(sc, s, params))
    comparisons = metrics.frequency_comparisons(results, sc.tolerances["frequency"])
    obj = {"scene": sc.name, "params": params,
           "runs": [{"solver": r.solver, "status": r.status, "wall_s": round(r.wall_s, 6),
                     "frequencies_hz": list(r.frequencies_hz), "labels": r.labels,
                     **({"reason": r.reason} if r.reason else {})} for r in results],
           "comparisons": [c.as_dict() for c in comparisons]}
    md = [f"# {sc.name}: {sc.title}", "", "| solver | status | frequencies [Hz] | labels |",
          "|---|---|---|---|"]
    md += [f"| {r.solver} | {r.status} | {', '.join(f'{f:.8g}' for f in r.frequencies_hz)} | "
           f"{', '.join(r.labels)} |" for r in results]
    md += ["", "| a | b | mode | rel. difference | verdict |", "|---|---|---|---|---|"]
    md += [f"| {c.a} | {c.b} | {c.channel} | {c.max_rel:.2e} | {c.verdict} |"
           for c in comparisons]
    if sc.name == "rotor-whirl" and campbell_sweep:
        spins = np.linspace(0.0, params["spin_max"], params["n_spin"])
        lines, crit = {}, {}
        for s in chosen:
            try:
                lines[s.name] = campbell(s, params, spins)
                crit[s.name] = critical_speeds(s, params, spins, lines[s.name])
            except Exception as e:          # a solver failing the sweep is reported, not fatal
                log(f"campbell {s.name}: {type(e).__name__}: {e}")
        obj["critical_speeds_rad_s"] = crit
        _campbell_png(out_dir / "campbell.png", spins, lines, crit)
        obj["recording"] = str(_campbell_rrd(out_dir / "campbell.rrd", spins, lines))
        md += ["", "## Campbell diagram", "", "Critical speeds (whirl line crosses 1× spin):", ""]
        md += [f"- {n}: " + ", ".join(f"{k} {v:.6f} rad/s" for k, v in c.items())
               for n, c in crit.items()]
        md += ["", "![campbell](campbell.png)"]
        if identify and params["spin"] == 0:
            time_solvers = [s for s in solvers.solvers_for("rotor-spinup") if s in chosen
                            or not solver_names]
            ident = free_response_frequencies(params, time_solvers)
            obj["identified_from_free_response"] = ident
            md += ["", "## Frequencies identified from free responses", "",
                   "Rotor released with tilt0 = 1e-3 rad, no torque, 2 s record at 1 ms; "
                   "identified tilt frequency [rad/s] vs record length.", "",
                   "| solver | method | " + " | ".join(f"{T:g} s" for T in (0.25, 0.5, 1, 2)) + " |",
                   "|---|---|---|---|---|---|"]
            for r in ident:
                if r["status"] == "ok":
                    for m in ("matrix_pencil", "fft"):
                        md.append(f"| {r['solver']} | {m} | "
                                  + " | ".join(f"{w:.8g}" if w else "—" for w in r[m]) + " |")
    write_text(out_dir / "report.md", "\n".join(md) + "\n")
    obj["report"] = str(out_dir / "report.md")
    write_json(out_dir / "result.json", obj)
    return obj, results, comparisons
