"""`xval bench` for frequency scenes: the time each solver needs for a given accuracy of the
natural frequencies, and its default settings against the source's published computing times.

Each solver is walked along its own accuracy knobs (coarse → fine, from its default outwards,
with bench.py's walk): a tolerance (`rtol` of a root refinement, `fd_step` of a finite
difference, factors of 10), a mesh (integer settings named `*elements` / `*segments`, scaled
together by factors of 2, each such ladder with the solver's accuracy switch — Richardson
extrapolation — off and on), a root search's grid step (`step_hz`, factors of 2); a solver with
none has one rung. A rung's error is the largest relative deviation over the scene's modes from
the reference (modes paired by label where both name them uniquely, else by nearest frequency:
`metrics.match_modes`; where that leaves modes unpaired, by order); a rung with fewer modes has
no error (missed modes). The reference is the finest rung of the scene's first reference
solver; the second one's best rung confirms it. Times are medians of repeated warm calls (each
solver is called once first: import and compile time are reported apart); the summary ranks
wall times, as the time bench does, and each row keeps its CPU time too (on a shared machine
the better estimate of an idle one's wall time, with single-threaded BLAS: the
OPENBLAS_NUM_THREADS in effect is recorded). Summary and plot are the time bench's.
"""
from __future__ import annotations

import os
import time

import numpy as np

from .. import solvers
from ..analysis import metrics
from ..leafinfo import MESH_SUFFIXES
from ..output.bench_report import knob_text as _knob_text
from ..results import BenchResult
from ..scenes import Scene
from .plan import plan
from .work_precision import (
    FLOOR_ERR,
    convergence_orders,
    order_lines,
    repeat_timed,
    summarise,
    walk,
)

TOLERANCES = {"rtol": tuple(10.0 ** -k for k in range(1, 14)),      # root refinement
              "fd_step": tuple(10.0 ** -k for k in range(1, 11))}    # finite-difference step
MESH_FACTORS = tuple(2.0 ** k for k in range(-3, 4))     # 1/8 … 8 × the default mesh
SWITCHES = ("richardson", "extrapolate")                 # accuracy switches of a mesh
# a root search's grid step (bracketing; too coarse a grid misses roots): 8× … 1/8× the default
GRID_STEPS = ("step_hz",)


def ladders(info, preset: dict) -> list[tuple[str, list[dict], int]]:
    """(label, [settings coarse → fine], index of the default rung) per accuracy knob:
    tolerances first (the finest rung of a solver's first ladder is its tightest run, the
    bench's reference), then meshes, then grid steps."""
    base = {**info.modes_defaults, **preset}
    out = []
    for k, values in TOLERANCES.items():
        if isinstance(base.get(k), (int, float)) and not isinstance(base.get(k), bool):
            start = int(np.argmin(np.abs(np.log(values) - np.log(base[k]))))
            out.append((k, [{**base, k: v} for v in values], start))
    mesh = [k for k, v in base.items() if k.endswith(MESH_SUFFIXES)
            and isinstance(v, int) and not isinstance(v, bool)]
    switch = next((k for k in SWITCHES if isinstance(base.get(k), bool)), None)
    if mesh:
        name = mesh[0] if len(mesh) == 1 else "mesh"
        for on in ((False, True) if switch else (None,)):
            sts = [{**base, **{k: max(1, round(base[k] * f)) for k in mesh},
                    **({} if on is None else {switch: on})} for f in MESH_FACTORS]
            out.append((name + (f"+{switch}" if on else ""), sts, MESH_FACTORS.index(1.0)))
    for k in GRID_STEPS:
        if isinstance(base.get(k), float):
            out.append((k, [{**base, k: base[k] / f} for f in MESH_FACTORS],
                        MESH_FACTORS.index(1.0)))
    return out or [("defaults", [base], 0)]


def deviation(ref, m) -> tuple[float | None, str]:
    """Largest relative frequency deviation of `m` from `ref` and the mode it is at (or None
    and why: a failed run, missed modes)."""
    if m.status != "ok":
        return None, f"{m.status}: {m.reason}"
    fr, fm = list(ref.frequencies_hz), list(m.frequencies_hz)
    pairs = metrics.match_modes(fr, ref.labels, fm, m.labels)
    if len(pairs) < len(fr) <= len(fm):
        # repeated roots named differently (a shaft at rest: "whirl 1", "whirl 2" against
        # "whirl 1" twice) pair neither by label nor by nearest value: by order
        pairs = list(zip(np.argsort(fr, kind="stable"), np.argsort(fm, kind="stable")[:len(fr)]))
    if len(pairs) < len(fr):
        return None, f"paired {len(pairs)} of the reference's {len(fr)} modes"
    rel = [abs(fm[j] - fr[i]) / abs(fr[i]) for i, j in pairs]
    k = int(np.argmax(rel))
    return float(rel[k]), ref.labels[pairs[k][0]] or f"mode {pairs[k][0] + 1}"


def _rung_text(row) -> str:
    """e.g. "rtol=1e-09", "n_segments=10, extrapolate"."""
    switch = row["method"].partition("+")[2]
    return (_knob_text(row["knob"]) or row["method"]) + (f", {switch}" if switch else "")


def _mesh_step(row) -> float | None:
    """1/n for a mesh rung whose (first) mesh knob is one number n, the same in every part
    (a leaf may refine some parts beyond the request: those rungs have no single h)."""
    if row.get("knob_kind") != "mesh" or not row["knob"] or row["rel_error"] is None:
        return None
    n = next(iter(row["knob"].values()))
    if isinstance(n, dict):
        n = set(n.values()).pop() if len(set(n.values())) == 1 else None
    return 1.0 / n if isinstance(n, int) and n > 0 else None


def falling(rows) -> list[dict]:
    """The mesh rungs that are still converging: per ladder, from the coarsest rung with a
    single h, each finer one while its error is below half the previous one (the walk's
    stall rule) — past that the error is at the solver's floor (round-off, the reference)."""
    out = []
    for key in dict.fromkeys((r["solver"], r["method"]) for r in rows):
        mine = sorted((r for r in rows if (r["solver"], r["method"]) == key
                       and _mesh_step(r) is not None), key=_mesh_step, reverse=True)
        for i, r in enumerate(mine):
            if i and not r["rel_error"] < 0.5 * mine[i - 1]["rel_error"]:
                break
            out.append(r)
    return out


def _rung(call, s, st, label, kind, knobs, ref, seen, repeats, log):
    """One rung's row: timed calls (bench.repeat_timed), its error. `seen` (effective
    settings -> row) spares a rerun: a rung another ladder of the solver ran (its default) is
    that row again; one this ladder ran is None (the leaf raised the request to a rung already
    run: nothing coarser exists)."""
    effective = lambda m: repr(sorted(m.settings.items()))   # noqa: E731
    cpus = []

    def timed():
        c0 = time.process_time()
        m = call(s, st)
        cpus.append(time.process_time() - c0)
        return m
    m = timed()
    old = seen.get(effective(m)) if m.status == "ok" else None
    if old is not None:
        return None if old["method"] == label else {
            **old, "method": label, "knob_kind": kind,
            "knob": {k: m.settings.get(k, st[k]) for k in knobs}}
    walls = [m.wall_s]
    if m.status == "ok":
        repeat_timed(walls, timed, repeats)
    err, at = deviation(ref, m)
    row = {"solver": s.name, "method": label, "knob_kind": kind,
           "knob": {k: m.settings.get(k, st[k]) for k in knobs},
           "settings": m.settings or st, "status": m.status,
           "wall_s": float(np.median(walls)), "cpu_s": float(np.median(cpus)), "rel_error": err,
           "worst_mode" if err is not None else "reason": at, "n_modes": len(m.frequencies_hz)}
    if m.status == "ok":
        seen[effective(m)] = row
    log(f"  {s.name} {label} {_knob_text(row['knob'])}: err "
        f"{'—' if err is None else f'{err:.2e}'} ({at}), wall {row['wall_s']:.3g} s")
    return row


def against_published(sc, chosen, timing_params, call, repeats):
    """Each solver's default-settings time for each of the scene's published timings (the
    sum over its cases of the median warm wall time; CPU time beside it, the better estimate
    on a shared machine) and its ratio to each published time: (entries, lines)."""
    entries, lines = [], []
    for pt, cases in zip(sc.published_timings, timing_params):
        for s in chosen:
            wall, cpu, ok = [], [], True
            for p in cases:
                walls, cpus = [], []

                def timed(s=s, p=p, cpus=cpus):
                    c0 = time.process_time()
                    m = call(s, {}, p)
                    cpus.append(time.process_time() - c0)
                    return m
                ok &= repeat_timed(walls, timed, repeats).status == "ok"
                wall.append(float(np.median(walls)))
                cpu.append(float(np.median(cpus)))
            total = sum(wall)
            entries.append({"what": pt.what, "solver": s.name, "wall_s": total,
                            "cpu_s": sum(cpu), "ok": ok, "per_case_s": wall,
                            "cases": list(pt.cases), "published_s": dict(pt.seconds),
                            "ratio": {tool: total / t for tool, t in pt.seconds.items()}})
            lines.append(f"{pt.what}: {s.name} {total:.3g} s (CPU {sum(cpu):.3g} s)"
                         + ("" if ok else " (a run failed)")
                         + ",".join(f" vs {t:g} s {tool} = " + (f"1/{t / total:.0f}" if total < t
                                                                 else f"{total / t:.2f}×")
                                    for tool, t in pt.seconds.items()))
    return entries, lines


def run_bench_modes(sc: Scene, solver_names, overrides: dict, out, repeats: int = 3,
                    log=print, make_out=None) -> dict:
    """The frequency bench's JSON (see the module doc; compare.output.bench_report writes its
    folder); everything is checked before `make_out(out)` makes the folder."""
    pl = plan(sc, overrides, solver_names or list(sc.bench_solvers))
    chosen, params = list(pl.solvers), pl.params
    timing_params = [[sc.resolve(case) for case in pt.cases] for pt in sc.published_timings]
    if make_out and out is not None:
        make_out(out)

    def call(s, st, p=params):
        return solvers.modes(sc, s, p, st)

    first_call = {}
    for s in chosen:                        # warm-up: import, compile, caches (timed apart)
        t0 = time.perf_counter()
        call(s, {})
        first_call[s.name] = time.perf_counter() - t0
    refs = ([solvers.get_solver(n) for n in sc.reference_solvers]
            or solvers.solvers_for(sc.name)[:2])
    ref_settings = ladders(refs[0].info(sc), refs[0].preset)[0][1][-1]
    ref = call(refs[0], ref_settings)
    if ref.status != "ok":
        raise RuntimeError(f"reference {refs[0].name} failed: {ref.reason}")
    log(f"reference {refs[0].name} ({_knob_text(ref.settings)}): "
        + ", ".join(f"{lb} {f:.10g}" for lb, f in zip(ref.labels, ref.frequencies_hz)) + " Hz")

    rows = []
    for s in chosen:
        seen, info = {}, s.info(sc)
        for label, rungs, start in ladders(info, s.preset):
            knobs = [k for k in rungs[0] if any(r[k] != rungs[0][k] for r in rungs)]
            kind = "mesh" if any(k.endswith(MESH_SUFFIXES) for k in knobs) else "tolerance"

            def rung(i, s=s, info=info, rungs=rungs, label=label, knobs=knobs, kind=kind,
                     seen=seen):
                try:
                    info.check(rungs[i])
                except ValueError:
                    return None      # a setting the leaf refuses ends the ladder, as in bench
                return _rung(call, s, rungs[i], label, kind, knobs, ref, seen, repeats, log)

            # one rung that does not halve the error ends a ladder: a finer mesh costs 2–8×
            rows += walk(rungs, start, rung, patience=1)

    # the reference's confirmation: the second reference solver's best rung (its defaults
    # when it was not benched)
    check = None
    if len(refs) > 1:
        theirs = [r for r in rows if r["solver"] == refs[1].name and r["rel_error"] is not None]
        if theirs:
            best = min(theirs, key=lambda r: r["rel_error"])
            check = {"solver": refs[1].name, "rel": best["rel_error"],
                     "settings": best["settings"], "worst_mode": best["worst_mode"]}
        else:
            m = call(refs[1], {})
            err, at = deviation(ref, m)
            check = {"solver": refs[1].name, "rel": err, "settings": m.settings,
                     "worst_mode": at}
    confirmed = check["rel"] if check and check["rel"] is not None else None
    what = f"(largest relative error over the {len(ref.frequencies_hz)} modes)"
    best_err = {s.name: min((r["rel_error"] for r in rows if r["solver"] == s.name
                             and r["rel_error"] is not None), default=None) for s in chosen}
    allowance = sc.tolerances_for(params).get("frequency_by_solver") or {}
    why = {s: (f"best {e:.1e}" if e is not None else "no rung ok")
           + (f"; its model differs by up to the scene's allowance {allowance[s]:g}"
              if s in allowance else "") for s, e in best_err.items()}
    summary, lines = summarise(rows, [s.name for s in chosen], what, why, _rung_text)
    # an error within 3× of a floor is not resolved from it: the level the two references
    # agree to, and for a solver whose model differs, the scene's allowance for it
    low = 3 * max(FLOOR_ERR, confirmed or 0.0)
    orders = convergence_orders([r for r in falling(rows)
                                 if r["rel_error"] > 3 * allowance.get(r["solver"], 0.0)],
                                low, _mesh_step, lambda r: None)
    lines += order_lines(orders, "h = 1/n,", "")

    published, timing_lines = against_published(sc, chosen, timing_params, call, repeats)
    lines += timing_lines

    blas = os.environ.get("OPENBLAS_NUM_THREADS")
    obj = {"scene": sc.name, "kind": "modes", "params": params, "repeats": repeats,
           "reference": {"solver": refs[0].name, "settings": ref.settings,
                         "labels": ref.labels, "frequencies_hz": list(ref.frequencies_hz),
                         "confirmed_by": check},
           "first_call_s": first_call, "blas_threads": blas, "rows": rows,
           "summary": summary, "orders": orders, "published_timings": published,
           "summary_lines": lines, "result": BenchResult.TYPE}
    return obj
