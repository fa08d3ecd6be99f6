"""`xval bench SCENE --identify`: the identification's speed (issue 50, item 5).

A record is synthesised from the first chosen solver (the scene's order puts its fastest first:
the one `xval identify` fits from the multi-start) at the scene's parameters with `--set` — the
truth — with the scene's `Fit.noise` (seed SEED). Then, `repeats` times: (a) xval's
identification (`identify`, no profile check: the fit and its intervals) of the default
unknowns with every chosen solver, σ as synthesised; (b) a plain `scipy.optimize.least_squares`
over the same first solver's runs — the same residuals (model − data)/σ on the record's grid,
the same scaled unknowns and bounds, started at the scene's defaults, scipy's default options.
Median walls, runs, χ²/dof, the estimates against the truth, and the ratio of (a)'s first fit
to (b), both measured in this one run. Nothing is written here (compare/output/bench_identify.py).
"""
from __future__ import annotations

import math
import time

import numpy as np
from scipy.optimize import least_squares

from .. import solvers
from ..analysis import estimates as est
from ..errors import BadInput
from ..output.bench_identify import summary_lines
from ..results import BenchResult
from ..scenes import get_scene
from .identify import Model, chosen_unknowns
from .identify import identify as run_identify
from .measured import fit_spec, synthesise
from .plan import names

SEED = 0        # the synthetic record's noise seed


def _off(a: float, b: float, period: float | None) -> float:
    """|a − b|, the shorter way round a period."""
    return abs(est.wrap(a - b, period))


def plain_fit(scene, solver, fixed, unknowns, scale, rec, chans, sigma, start) -> dict:
    """scipy's least_squares from `start` (physical units) with its default options over the
    solver's runs: the residuals, scaling and bounds of `identify`'s `Model`."""
    model = Model(scene, solver, fixed, unknowns, scale, rec, chans, sigma)
    lo, hi = model.bounds()
    t0 = time.perf_counter()
    sol = least_squares(model.residuals, np.clip(np.asarray(start) / model.scale, lo, hi),
                        bounds=(lo, hi))
    wall = time.perf_counter() - t0
    dof = max(len(sol.fun) - len(unknowns), 1)
    return {"wall_s": wall, "runs": model.runs, "nfev": int(sol.nfev),
            "converged": bool(sol.success), "status": int(sol.status),
            "message": str(sol.message), "cost": float(sol.cost),
            "chi2_dof": 2.0 * float(sol.cost) / dof, "values": (sol.x * model.scale).tolist()}


def run_identify_bench(scene_name, solver_names, overrides, repeats=3, log=print) -> dict:
    """The two timings and their rows (`summary_lines`, `rows`, `ratio`): the bench's JSON
    (compare.output.bench_identify writes its folder)."""
    sc = get_scene(scene_name)
    if sc.fit is None:
        raise BadInput(f"--identify: scene {sc.name!r} declares nothing to identify "
                       "(no Fit; `xval list`)")
    spec = fit_spec(sc)
    if not (isinstance(repeats, int) and repeats >= 1):
        raise BadInput(f"--repeats must be at least 1, got {repeats!r}")
    chosen = solvers.pick(sc, names(solver_names) or None)
    over = dict(overrides or {})
    truth_params = sc.resolve(over)          # one line on a bad --set
    unknowns, scale = chosen_unknowns(sc, spec, None, {})
    # the fit holds every --set but the unknowns' (those are the truth it must find)
    fixed = {k: v for k, v in over.items() if k not in unknowns}
    truth = [float(truth_params[n]) for n in unknowns]
    start = [float(sc.resolve(fixed)[n]) for n in unknowns]
    first = chosen[0]
    rec = synthesise(sc.name, first.name, over, None, SEED)
    chans = [c for c in sc.channels if c in rec]
    sigma = {c: float(spec.noise[c]) for c in chans}
    log(f"record: {first.name}, {len(rec['t'])} samples to {rec['t'][-1]:g} s, "
        f"{', '.join(chans)}; truth " + ", ".join(f"{n}={v:g}" for n, v in zip(unknowns, truth)))
    for s in chosen[1:]:                     # compile/load outside the timed fits
        solvers.simulate(sc, s, sc.resolve(fixed), solvers.settings_for(s, sc))

    fits, plains, totals = {s.name: [] for s in chosen}, [], []
    for k in range(repeats):
        t0 = time.perf_counter()
        res = run_identify(sc.name, rec, unknowns, [s.name for s in chosen], fixed, sigma,
                           profile=False, data_label=f"synthetic ({first.name}, seed {SEED})")
        totals.append(time.perf_counter() - t0)
        for f in res.data["fits"]:
            fits[f["solver"]].append(f)
        plains.append(plain_fit(sc, first, fixed, unknowns, scale, rec, chans, sigma, start))
        log(f"  repeat {k + 1}/{repeats}: identify {totals[-1]:.3g} s, least_squares "
            f"{plains[-1]['wall_s']:.3g} s")

    def periods():
        return [spec.periodic.get(n) for n in unknowns]

    rows = []
    for s in chosen:
        fs, last = fits[s.name], fits[s.name][-1]
        row = {"kind": "identify", "solver": s.name,
               "wall_s": float(np.median([f["wall_s"] for f in fs])),
               "walls_s": [f["wall_s"] for f in fs], "runs": last["runs"],
               "converged": last["converged"], "why": last["why"],
               "unknowns": unknowns, "truth": truth, "start": start}
        if last["converged"]:
            inside = [bool(ok) and _off(v, t, p) <= h for v, t, h, ok, p in zip(
                last["values"], truth, last["half_width"], last["identifiable"], periods())]
            row.update(values=last["values"], half_width=last["half_width"],
                       identifiable=last["identifiable"], chi2_dof=last["chi2"] / last["dof"],
                       truth_inside=inside, all_inside=all(inside))
        else:
            row.update(values=None, half_width=None, identifiable=None, chi2_dof=None,
                       truth_inside=None, all_inside=False)
        rows.append(row)
    p_last, ref = plains[-1], rows[0]
    # reached the truth: every estimate within the 95 % half width xval's fit on this solver
    # gives (no interval to judge it by: not reached)
    reached = [None if ref["half_width"] is None else _off(v, t, p) <= h for v, t, h, p in zip(
        p_last["values"], truth, ref["half_width"] or [0] * len(truth), periods())]
    rows.append({"kind": "least_squares", "solver": first.name,
                 "wall_s": float(np.median([p["wall_s"] for p in plains])),
                 "walls_s": [p["wall_s"] for p in plains], "runs": p_last["runs"],
                 "nfev": p_last["nfev"], "converged": p_last["converged"],
                 "status": p_last["status"], "message": p_last["message"],
                 "cost": p_last["cost"], "chi2_dof": p_last["chi2_dof"],
                 "unknowns": unknowns, "truth": truth, "start": start,
                 "values": p_last["values"], "truth_inside": reached,
                 "reached_truth": all(r is True for r in reached)})
    plain = rows[-1]
    ratio = {"wall": ref["wall_s"] / plain["wall_s"] if plain["wall_s"] > 0 else math.inf,
             "runs": ref["runs"] / plain["runs"] if plain["runs"] else math.inf}
    obj = {"scene": sc.name, "params": truth_params, "mode": "identify",
           "result": BenchResult.TYPE, "repeats": repeats,
           "record": {"solver": first.name, "seed": SEED, "samples": len(rec["t"]),
                      "t_end": float(rec["t"][-1]), "channels": chans, "sigma": sigma},
           "unknowns": unknowns, "truth": truth, "start": start,
           "identify_wall_s": float(np.median(totals)), "rows": rows, "ratio": ratio,
           "start_is_truth": all(_off(a, b, p) == 0.0
                                 for a, b, p in zip(start, truth, periods()))}
    obj["summary_lines"] = summary_lines(obj)
    return obj
