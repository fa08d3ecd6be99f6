"""`xval bench`: the speed/accuracy trade (work-precision) of every solver of a scene.

For each solver and integrator, a ladder of steps (fixed-step methods, factors of 2) or
tolerances (error-controlled methods, factors of 10) walked from the default outwards: coarser
until the error reaches ~1e-2 (or the run fails), finer until the method's floor (the error stops
falling, reaches what the reference can resolve, or a rung gets too slow). The error of each run
is the relative error of the key channel's final value against a reference (the tightest run of
the first solver, confirmed by the second) — or, for a scene that is a benchmark problem whose
reference is known at the parameters (`Scene.bench_reference`), the problem's own error against
that reference (relative: over the reference's largest value); the time is the median wall
time over `repeats` runs (5 × as many for runs under 50 ms), compile time reported apart; the
leaf's `rhs_evals` and integration time give the cost of one right-hand-side evaluation (ns).
A step-size-bound explicit method whose step is picked from its stability limit ("auto") has
one rung. Every run's trajectory is kept in the bench directory. The summary names, for the
error levels 1e-3, 1e-6 and 1e-9, the fastest solver and every other solver's time ratio to
it — all measured in this one run — and each fixed-step method's observed convergence order
(flagged where it falls short of the method's order).
"""
import numpy as np

from .. import solvers
from ..analysis import metrics
from ..analysis.verdict import Verdict
from ..errors import BadInput
from ..leafinfo import ORDERS, Adaptive, Fixed, snap  # noqa: F401  (ORDERS: the tests' table)
from ..output.bench_report import bench_dir
from ..output.run_folder import write_trajectory
from ..results import BenchResult
from ..scenes import get_scene
from . import budget
from .bench_modes import run_bench_modes
from .plan import Limits, plan
from .work_precision import (
    FLOOR_ERR,
    convergence_orders,
    order_lines,
    repeat_timed,
    summarise,
    walk,
)


def ladder(info, dt_out, preset=None, t_end=None):
    """Per integrator: (label, [settings coarse → fine], index of the starting rung), along
    the knob's own ladder (`Adaptive.ladder`, `Fixed.ladder`)."""
    base = {**info.defaults, **(preset or {})}
    adaptive = info.adaptive
    t_end = t_end or 1e3 * dt_out
    out = []
    if base.get("integrator") in adaptive:
        # the default error-controlled method, and dopri5 where offered (fewer stages: cheaper
        # at loose tolerances)
        knobs, start = Adaptive.ladder()
        for name in dict.fromkeys([base["integrator"]] + [a for a in adaptive if a == "dopri5"]):
            out.append((name, [{**base, "integrator": name, "rtol": k.rtol} for k in knobs],
                        start))
        fixed = "rk4" if "rk4" in info.integrator_names else None
        dt0 = 1e-3
    else:
        fixed, dt0 = base.get("integrator"), base.get("dt") or 1e-3
        if dt0 == "auto":      # a fixed number behind "auto" can be laddered; a stability-bound
            dt0 = info.auto_dt.get(fixed, dt0)                  # explicit step cannot
    if fixed and not isinstance(dt0, (int, float)):     # e.g. "auto": the leaf picks its step
        out.append((fixed, [base], 0))
    elif fixed:
        steps, start = Fixed(dt0).ladder(dt_out, t_end)
        out.append((fixed, [{**base, "integrator": fixed, "dt": k.dt} for k in steps], start))
    return out


def _tightest(solver, info, dt_out):
    base = {**info.defaults, **solver.preset}
    if base.get("integrator") in info.adaptive:
        return {**base, "rtol": 1e-13}
    dt0 = base.get("dt")
    if dt0 == "auto":
        dt0 = info.auto_dt.get(base.get("integrator"), dt0)
    return {**base, "dt": snap(dt0 / 8, dt_out)} if isinstance(dt0, (int, float)) else base


def _ladders(pl, solver, dt_out, vary):
    """(label, [(settings, params) coarse → fine], start) per integrator: the accuracy-knob
    ladders, or with `vary` = (NAME, values) one ladder of the solver's default settings at
    each value of that model parameter (e.g. the paper's advice to lower the thread stiffness
    for design runs), every value run."""
    if vary is None:
        return [(label, [(st, pl.params) for st in sts], start) for label, sts, start in
                ladder(solver.info(pl.scene), dt_out, solver.preset, pl.params["t_end"])]
    name, values = vary
    st = pl.settings[solver.name]
    return [(f"{name}={v}", [(st, pl.scene.resolve({**pl.overrides, name: v}))], 0)
            for v in values]




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


def run_throughput(scene_name, solver_names, overrides, n_points, log=print):
    """`xval bench SCENE --points N`: each solver's points per second on its accurate defaults
    over N points of the scene's first default map, through the map's batch path (the bench's
    JSON; compare.output.bench_report.write_throughput writes its folder)."""
    from .maps import throughput
    obj = throughput(scene_name, solver_names, overrides, n_points, log=log)
    def more(r):
        return (f"; accurate everywhere {r['accurate_points_per_second']:.1f}, "
                f"{r['rerun_fraction']:.1%} rerun accurate, {r['labels_differ']} labels "
                "differ" if "rerun_fraction" in r else "")
    lines = [f"{r['solver']}: {r['points']} points in {r['wall_s']:.3g} s — "
             f"{r['points_per_second']:.1f} points/s ({r['points_per_core_second']:.1f} per "
             f"core-second, {obj['workers']} workers{more(r)})" for r in obj["rows"]]
    obj["summary_lines"], obj["result"] = lines, BenchResult.TYPE
    return obj


def run_bench(scene_name, solver_names, overrides, out, repeats=3, log=print, vary=None,
              max_output_gib=None, max_steps=None, make_out=None):
    """The bench's JSON (compare.output.bench_report writes its folder). Everything is checked
    (names, values, the size of the work) before `make_out(out)` creates the output folder
    (the CLI's, which turns a refusal into one line); with `out` the rungs' trajectories
    stream into it as they run, without it (a bench held in memory) they are not kept."""
    sc = get_scene(scene_name)
    if not (isinstance(repeats, int) and repeats >= 1):
        raise BadInput(f"--repeats must be at least 1, got {repeats!r}")
    bench = sc.either(time=_bench_time, modes=_bench_modes)
    return bench(sc, solver_names, overrides, out, repeats, log, vary, max_output_gib,
                 max_steps, make_out)


def _bench_modes(sc, solver_names, overrides, out, repeats, log, vary, max_output_gib,
                 max_steps, make_out):
    if vary is not None:
        raise BadInput("--vary: frequency scenes are benched along the solvers' own "
                       "accuracy knobs only")
    return run_bench_modes(sc, solver_names, overrides, out, repeats, log, make_out)


def _bench_time(sc, solver_names, overrides, out, repeats, log, vary, max_output_gib,
                max_steps, make_out):
    pl = plan(sc, overrides, solver_names or list(sc.bench_solvers),
              limits=Limits(max_output_gib, max_steps))
    chosen, params = list(pl.solvers), pl.params
    vary = parse_vary(vary, sc) if vary is not None else None
    for s in chosen:
        for _, rungs, start in _ladders(pl, s, params["output_dt"], vary):
            st, p = rungs[start]
            budget.check_steps(s.name, s.info(sc), p, st, max_steps)
    if make_out and out is not None:
        make_out(out)
    dt_out = params["output_dt"]
    key = sc.key_channel
    out_dir = None if out is None else bench_dir(out)
    bm = sc.bench_reference(params)     # the scene answers what the rungs are measured against
    if bm is not None:
        reference, measure, ref_settings, done = _benchmark_reference(sc, bm, params, log)
        what = (f"on problem {bm.problem}'s error (over {reference['scale']:.3g} "
                f"{reference['unit']})")
    else:
        reference, measure, ref_settings, done = _solver_reference(sc, params, out_dir, log)
        what = f"on final {key}"
    ref_check = reference["cross_check_rel"]

    rows = []
    for s in chosen:
        info = s.info(sc)
        for label, rungs, start in _ladders(pl, s, dt_out, vary):
            ran: set = set()

            def run(i, s=s, info=info, label=label, rungs=rungs, ran=ran):
                st, p = rungs[i]
                try:
                    info.check(st, sc.output_grid(p))
                    budget.check_steps(s.name, info, p, st, max_steps)
                except (ValueError, BadInput):
                    return None
                row = _run_rung(sc, s, info, label, st, p, params, done, repeats, measure,
                                out_dir, f"{s.name}-{label}-{i}", vary, log)
                # a leaf that clamped the knob (an engine's step ≤ the output interval) to what
                # an earlier rung ran: the walk goes no coarser instead of repeating it
                clamped = any(k.endswith("_requested") for k in row["settings"])
                used = repr(sorted((k, v) for k, v in row["settings"].items()
                                   if not k.endswith("_requested"))) + repr(p)
                if clamped and used in ran and vary is None:
                    return None
                ran.add(used)
                return row
            rows += walk(rungs, start, run, exhaustive=vary is not None)

    infos = {s.name: s.info(sc) for s in chosen}
    summary, lines = summarise(rows, [s.name for s in chosen], what)
    floor = reference.get("floor_rel", 0.0)
    orders = convergence_orders(rows, 100 * max(FLOOR_ERR, ref_check or 0.0, floor), _fixed_dt,
                                lambda r: infos[r["solver"]].order(r["method"]))
    lines += order_lines(orders, "dt", " s")
    cost = error_bar_cost(pl, log) if vary is None else None
    if cost and cost["verdicts"]:
        lines.append(f"error bars: {cost['runs_per_verdict']:.3g} runs, "
                     f"{cost['seconds_per_verdict']:.3g} s per verdict ({cost['runs']} runs, "
                     f"{cost['seconds']:.3g} s for {cost['verdicts']} verdicts)")
    obj = {"scene": sc.name, "params": params, "key_channel": key, "error_bars": cost,
           "vary": vary and {"name": vary[0], "values": vary[1]},
           "reference": {**reference, "settings": ref_settings},
           "repeats": repeats, "rows": rows, "summary": summary, "orders": orders,
           "summary_lines": lines, "result": BenchResult.TYPE}
    return obj


def error_bar_cost(pl, log=print) -> dict:
    """What the verdicts' error bars cost at the bench's parameters: each solver run once at its
    default settings with its error estimate (`solvers.simulate`), the runs and seconds that
    took (the run, its estimate's reruns), and over the scene's comparisons of those runs the
    runs and seconds per verdict (None where no pair is compared: one solver)."""
    sc, by = pl.scene, {}
    runs = [solvers.simulate(sc, s, pl.params, pl.settings[s.name], t_out=pl.t_out,
                             estimate_error=sc.error_estimate) for s in pl.solvers]
    for tr in runs:
        by[tr.solver] = {"status": tr.status, "runs": 1 + tr.stats.get("error_estimate_runs", 0),
                         "run_s": tr.wall_s, "estimate_s": tr.stats.get("error_estimate_s", 0.0),
                         "by": tr.stats.get("error_estimate_by")}
        log(f"error bar {tr.solver}: {by[tr.solver]['runs']} runs, run {tr.wall_s:.3g} s + "
            f"estimate {by[tr.solver]['estimate_s']:.3g} s ({by[tr.solver]['by']})")
    ok = [tr for tr in runs if tr.status == "ok"]
    n = sum(c.verdict != Verdict.SKIPPED for c in sc.verdicts(pl.params, ok)) if ok else 0
    total = sum(b["runs"] for b in by.values())
    secs = sum(b["run_s"] + b["estimate_s"] for b in by.values())
    return {"by_solver": by, "verdicts": n, "runs": total, "seconds": secs,
            "runs_per_verdict": total / n if n else None,
            "seconds_per_verdict": secs / n if n else None}


def _benchmark_reference(sc, bm, params, log):
    """The benchmark problem's reference: each rung's error is the problem's own (the largest
    |run − reference| over the monitored channels, `Benchmark.deviation`); `rel_error` (what
    the walk, the summary and the orders read) is it over the reference's largest |value|.
    Returns (bench.json's "reference", measure(trajectory) -> row fields, {}, {})."""
    ref = bm.reference(params, sc.output_grid(params))
    vals = np.concatenate([np.asarray(ref[c], float) for c in bm.columns])
    scale = float(np.max(np.abs(vals[np.isfinite(vals)])))
    unit = sc.unit(bm.columns[0])
    held = int(np.isfinite(vals).sum())
    text = (f"IFToMM problem {bm.problem}'s reference: {bm.reference_name}; error = the largest "
            f"|{', '.join(bm.columns)} − reference| over its {held} values on the grid "
            f"(relative: over its largest |value| {scale:.6g} {unit})")
    log(f"reference: {text}")

    def measure(tr):
        dev = bm.deviation(params, tr.t, tr.channels)
        if dev is None:
            return {"rel_error": None, "error": None}
        return {"rel_error": dev["error"] / scale, "error": dev["error"],
                "error_at": {"channel": dev["channel"], "t": dev["t"]}}
    return ({"kind": "benchmark", "what": text, "problem": bm.problem,
             "error": bm.error, "columns": list(bm.columns), "unit": unit, "scale": scale,
             "values": held, "uncertainty": bm.uncertainty, "floor_rel": bm.uncertainty / scale,
             "solvers": [], "value": None, "cross_check_rel": None}, measure, {}, {})


def _solver_reference(sc, params, out_dir, log):
    """The tightest run of the scene's reference solver (error-controlled at rtol 1e-13 where
    it has one, else an eighth of its default step), confirmed by the second the same way;
    each rung's error is its final key channel's relative to it. Returns (bench.json's
    "reference", measure(trajectory) -> row fields, the reference run's settings, the runs
    done: a ladder rung equal to one reuses it)."""
    dt_out, key = params["output_dt"], sc.key_channel
    refs = ([solvers.get_solver(n) for n in sc.reference_solvers]
            or solvers.solvers_for(sc.name)[:2])
    ref_runs, done = [], {}
    for s in refs:
        st = _tightest(s, s.info(sc), dt_out)
        tr = solvers.simulate(sc, s, params, st)
        if out_dir is not None:
            write_trajectory(out_dir, tr, f"reference-{s.name}")
        ref_runs.append(tr)
        done[(s.name, repr(sorted(st.items())))] = tr     # a ladder rung equal to it reuses it
        log(f"reference {s.name}: {key}(end) = {tr.final()[key]:.15g} ({tr.status}, "
            f"{tr.settings})")
    ref = ref_runs[0].final()[key]
    ref_check = (abs(ref_runs[1].final()[key] - ref) / abs(ref)) if len(ref_runs) > 1 else None

    def measure(tr):
        return {"rel_error": abs(tr.final()[key] - ref) / abs(ref)}
    return ({"kind": "solver", "what": f"the tightest run of {refs[0].name}, final {key}",
             "solvers": [s.name for s in refs], "value": ref, "cross_check_rel": ref_check},
            measure, ref_runs[0].settings, done)


def _run_rung(sc, solver, info, label, st, p, params, done, repeats, measure, out_dir, name,
              vary, log):
    """One rung: timed runs (a run slower than RUNG_WALL_S is not repeated; one faster than
    SHORT_RUN_S is repeated SHORT_REPEATS × as often: one scheduler hiccup is its whole time),
    its row."""
    walls, tr = [], (done.get((solver.name, repr(sorted(st.items())))) if p == params else None)
    if tr is not None:
        walls.append(tr.wall_s)

    tr = repeat_timed(walls, lambda: solvers.simulate(sc, solver, p, st), repeats) or tr
    if out_dir is not None:                                   # the trajectories stay
        write_trajectory(out_dir, tr, name)
    measured = measure(tr) if tr.status == "ok" else {"rel_error": None}
    err = measured["rel_error"]
    evals, t_int = tr.stats.get("rhs_evals"), tr.stats.get("integrate_s")
    row = {"solver": solver.name, "method": label, "settings": tr.settings,
           "status": tr.status, "wall_s": float(np.median(walls)),
           "compile_s": tr.stats.get("compile_s"), **measured,
           "energy_residual": metrics.energy_residual(tr, sc.energy_channel)
           if sc.energy_channel else None,
           "steps": tr.stats.get("steps"), "rhs_evals": evals, "integrate_s": t_int,
           "ns_per_rhs": 1e9 * t_int / evals if evals and t_int and evals > 0 and t_int > 0
           else None,
           **({"vary": {vary[0]: p[vary[0]]}} if vary else {})}
    knob = st.get("rtol") if label in info.adaptive else st.get("dt")
    log(f"  {solver.name} {label} {knob}: err {err if err is None else f'{err:.2e}'} "
        + (f"({measured['error']:.2e} abs) " if measured.get("error") is not None else "")
        + f"wall {row['wall_s']:.3g} s"
        + (f", {row['ns_per_rhs']:.0f} ns/RHS" if row["ns_per_rhs"] else ""))
    return row


def _fixed_dt(row):
    """A fixed-step row's step (None for an error-controlled one)."""
    dt = row["settings"].get("dt")
    return dt if isinstance(dt, (int, float)) and "rtol" not in row["settings"] else None
