"""`xval bench`: the speed/accuracy trade (work-precision) of every solver of a scene.

For each solver and integrator, a ladder of steps (fixed-step methods: the default step × 4, 2,
1, ½, snapped to divisors of the output step) or tolerances (error-controlled methods); the
error of each run is the relative error of the key channel's final value against a reference
(the tightest run of the first solver, confirmed by the second); the time is the median wall time
over `repeats` runs, compile time reported apart. A step-size-bound explicit method whose step
is picked from its stability limit ("auto") has one rung. Every run's trajectory is kept in the
bench directory. The summary names, for stated error levels,
the fastest solver and every other solver's time ratio to it — all measured in this one run.
"""
import datetime
from pathlib import Path

import numpy as np

from . import budget, metrics, solvers
from .atomic import write_json, write_text
from .errors import BadInput
from .report import fmt_value, plot_style, save_figure
from .scenes import get_scene

LEVELS = (1e-3, 1e-6)
RTOLS = (1e-5, 1e-7, 1e-9, 1e-11)


def _snap(dt, dt_out):
    """Largest step ≤ dt that divides the output step into whole steps."""
    return dt_out / max(1, int(np.ceil(dt_out / dt - 1e-9)))


def ladder(leaf, dt_out, preset=None):
    """(label, settings) pairs walking each integrator's accuracy knob."""
    base = {**leaf.DEFAULT_SETTINGS, **(preset or {})}
    adaptive = tuple(getattr(leaf, "ADAPTIVE", ()))
    out = []
    if base.get("integrator") in adaptive:
        # the default error-controlled method, and dopri5 where offered: at loose tolerances
        # its 6 stages beat dop853's 12 when the output grid caps the step
        for name in dict.fromkeys([base["integrator"]] + [a for a in adaptive if a == "dopri5"]):
            out += [(name, {**base, "integrator": name, "rtol": r}) for r in RTOLS]
        fixed = "rk4" if "rk4" in leaf.INTEGRATORS else None
        dt0 = 1e-3
    else:
        fixed, dt0 = base.get("integrator"), base.get("dt") or 1e-3
        if dt0 == "auto":      # a fixed number behind "auto" can be laddered; a stability-bound
            dt0 = getattr(leaf, "AUTO_DT", {}).get(fixed, dt0)   # explicit step cannot
    if fixed and not isinstance(dt0, (int, float)):     # e.g. "auto": the leaf picks its step
        out.append((fixed, base))
    elif fixed:
        out += [(fixed, {**base, "integrator": fixed, "dt": _snap(dt0 * f, dt_out)})
                for f in (4, 2, 1, 0.5)]
    return out


def _tightest(solver, scene_name, dt_out):
    leaf = solver.leaf(scene_name)
    base = {**leaf.DEFAULT_SETTINGS, **solver.preset}
    if base.get("integrator") in getattr(leaf, "ADAPTIVE", ()):
        return {**base, "rtol": 1e-13}
    steps = [st["dt"] for _, st in ladder(leaf, dt_out, solver.preset)
             if isinstance(st.get("dt"), (int, float))]
    return {**base, "dt": min(steps) / 4} if steps else base


def _rungs(sc, solver, overrides, params, dt_out, vary):
    """(label, settings, params) per run: the accuracy-knob ladder, or with `vary` = (NAME,
    values) the solver's default settings at each value of that model parameter (e.g. the
    paper's advice to lower the thread stiffness for design runs)."""
    if vary is None:
        return [(label, st, params) for label, st in
                ladder(solver.leaf(sc.name), dt_out, solver.preset)]
    name, values = vary
    st = solvers.settings_for(solver, sc.name)
    return [(f"{name}={v}", st, sc.resolve({**overrides, name: v})) for v in values]


def parse_vary(text, sc):
    """NAME=v1,v2,... → (NAME, [v1, v2, ...]), checked against the scene's parameters."""
    name, sep, values = (text or "").partition("=")
    vals = [v.strip() for v in values.split(",") if v.strip()]
    if not sep or not vals:
        raise BadInput(f"--vary {text!r}: expected NAME=V1,V2,...")
    if name in ("t_end", "output_dt"):
        raise BadInput(f"--vary {name}: the output grid must stay the reference's")
    for v in vals:
        sc.resolve({name.strip(): v})          # one-line error for an unknown name or bad value
    return name.strip(), vals


def run_bench(scene_name, solver_names, overrides, out, repeats=3, log=print, vary=None,
              max_output_gib=None, max_steps=None, make_out=None):
    """Everything is checked (names, values, the size of the work) before the bench folder is
    made; `make_out(out)` creates the output folder (the CLI's, which turns a refusal into one
    line)."""
    sc = get_scene(scene_name)
    if sc.kind != "time":
        raise BadInput(f"scene {sc.name!r}: bench sweeps time-domain scenes")
    if not (isinstance(repeats, int) and repeats >= 1):
        raise BadInput(f"--repeats must be at least 1, got {repeats!r}")
    chosen = solvers.pick(sc, solver_names)
    budget.check_output(sc, overrides, len(chosen), max_output_gib)
    params = sc.resolve(overrides)
    vary = parse_vary(vary, sc) if vary is not None else None
    for s in chosen:
        for _, st, p in _rungs(sc, s, overrides, params, params["output_dt"], vary):
            budget.check_steps(s.name, s.leaf(sc.name), p, st, max_steps)
    if make_out:
        make_out(out)
    dt_out = params["output_dt"]
    key = sc.key_channel

    # reference: the tightest run of the scene's reference solver (error-controlled at rtol
    # 1e-13 where it has one, else a quarter of its finest ladder step), confirmed by the
    # second the same way
    refs = ([solvers.get_solver(n) for n in sc.reference_solvers]
            or solvers.solvers_for(sc.name)[:2])
    stamp = datetime.datetime.now().strftime("%Y%m%d-%H%M%S")
    out_dir = Path(out) / "bench" / f"{sc.name}-{stamp}"
    out_dir.mkdir(parents=True, exist_ok=True)
    ref_runs, done = [], {}
    for s in refs:
        st = _tightest(s, sc.name, dt_out)
        tr = solvers.simulate(sc, s, params, st)
        tr.save(out_dir / f"reference-{s.name}.npz")
        ref_runs.append(tr)
        done[(s.name, repr(sorted(st.items())))] = tr     # a ladder rung equal to it reuses it
        log(f"reference {s.name}: {key}(end) = {tr.final()[key]:.15g} ({tr.status}, "
            f"{tr.settings})")
    ref = ref_runs[0].final()[key]
    ref_check = (abs(ref_runs[1].final()[key] - ref) / abs(ref)) if len(ref_runs) > 1 else None

    rows = []
    for s in chosen:
        leaf = s.leaf(sc.name)
        for rung, (label, st, p) in enumerate(_rungs(sc, s, overrides, params, dt_out, vary)):
            walls, tr = [], (done.get((s.name, repr(sorted(st.items())))) if p == params
                             else None)
            if tr is not None:
                walls.append(tr.wall_s)
            while len(walls) < repeats:
                tr = solvers.simulate(sc, s, p, st)
                walls.append(tr.wall_s)
            tr.save(out_dir / f"{s.name}-{rung}-{label}.npz")     # the trajectories stay
            err = abs(tr.final()[key] - ref) / abs(ref) if tr.status == "ok" else None
            rows.append({"solver": s.name, "method": label, "settings": tr.settings,
                         "status": tr.status, "wall_s": float(np.median(walls)),
                         "compile_s": tr.stats.get("compile_s"), "rel_error": err,
                         "energy_residual": metrics.energy_residual(tr, sc.energy_channel)
                         if sc.energy_channel else None,
                         "steps": tr.stats.get("steps"),
                         **({"vary": {vary[0]: p[vary[0]]}} if vary else {})})
            knob = st["rtol"] if label in getattr(leaf, "ADAPTIVE", ()) else st.get("dt")
            log(f"  {s.name} {label} {knob}: err "
                f"{err if err is None else f'{err:.2e}'} wall {np.median(walls):.3g} s")

    summary, lines = {}, []
    for level in LEVELS:
        best = {}
        for r in rows:
            if r["rel_error"] is not None and r["rel_error"] <= level:
                if r["solver"] not in best or r["wall_s"] < best[r["solver"]]["wall_s"]:
                    best[r["solver"]] = r
        if not best:
            continue
        fastest = min(best.values(), key=lambda r: r["wall_s"])
        ratios = {s: r["wall_s"] / fastest["wall_s"] for s, r in best.items()}
        summary[f"{level:g}"] = {"fastest": fastest["solver"], "method": fastest["method"],
                                 "wall_s": fastest["wall_s"], "time_ratio": ratios,
                                 "unreached": [s.name for s in chosen if s.name not in best]}
        lines.append(f"error ≤ {level:g} on final {key}: fastest {fastest['solver']} "
                     f"({fastest['method']}, {fastest['wall_s']:.3g} s); ratios "
                     + ", ".join(f"{s} {v:.2f}×" for s, v in sorted(ratios.items(),
                                                                   key=lambda x: x[1])))
    _plot(out_dir / "work_precision.png", rows, sc.name, key)
    obj = {"scene": sc.name, "params": params, "key_channel": key,
           "vary": vary and {"name": vary[0], "values": vary[1]},
           "reference": {"solvers": [s.name for s in refs], "value": ref,
                         "cross_check_rel": ref_check},
           "repeats": repeats, "rows": rows, "summary": summary, "summary_lines": lines}
    md = [f"# Work-precision: {sc.name}", "",
          f"Reference: {refs[0].name} ({_settings_text(ref_runs[0].settings)}), "
          f"final {key} = {ref:.15g}"
          + (f"; {refs[1].name} agrees to {ref_check:.1e} relative" if ref_check is not None
             else ""), "", *[f"- {x}" for x in lines], "",
          "| solver | method | setting | rel. error | energy residual [J] | median wall [s] | "
          "compile [s] | steps |", "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        knob = r["settings"].get("rtol") if "rtol" in r["settings"] and r["method"] in (
            "dop853", "dopri5", "rk23", "ode23") else r["settings"].get("dt")
        err, er = r["rel_error"], r["energy_residual"]
        md.append(f"| {r['solver']} | {r['method']} | {fmt_value(knob)} | "
                  f"{'—' if err is None else format(err, '.2e')} | "
                  f"{'—' if er is None else format(er, '.2e')} | {r['wall_s']:.4g} | "
                  f"{fmt_value(r['compile_s'], 3) if r['compile_s'] else '—'} | {r['steps']} |")
    md += ["", "![work-precision](work_precision.png)"]
    write_text(out_dir / "report.md", "\n".join(md) + "\n")
    write_json(out_dir / "bench.json", obj)
    obj["report"] = str(out_dir / "report.md")
    return obj


def _settings_text(settings):
    return ", ".join(f"{k}={fmt_value(v)}" for k, v in settings.items() if v is not None)


def _plot(path, rows, scene, key):
    plt = plot_style()
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for (s, m) in dict.fromkeys((r["solver"], r["method"]) for r in rows):
        pts = [(r["wall_s"], r["rel_error"]) for r in rows
               if r["solver"] == s and r["method"] == m and r["rel_error"]]
        if pts:
            x, y = zip(*sorted(pts))
            ax.loglog(x, y, "o-", ms=4, label=f"{s} {m}")
    for level in LEVELS:
        ax.axhline(level, color="grey", lw=0.5, ls=":")
    ax.set_xlabel("median wall time [s]")
    ax.set_ylabel(f"relative error of final {key}")
    ax.set_title(f"work-precision: {scene}")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7)
    # log axes spanning less than a decade get minor labels that overlap: major decades only,
    # and plain numbers where the span is short
    from matplotlib.ticker import LogLocator, NullFormatter
    for axis in (ax.xaxis, ax.yaxis):
        axis.set_major_locator(LogLocator(base=10, numticks=8))
        axis.set_minor_formatter(NullFormatter())
    fig.tight_layout()
    save_figure(fig, path)
