"""How far `xval identify` can be trusted: the coverage of its intervals over synthetic
records (each solver's data fitted by each other solver), and the smallest defect a channel set
tells from none at stated false-alarm and miss rates. Nothing is written here."""
from __future__ import annotations

import math
import time

import numpy as np

from .. import solvers
from ..analysis import estimates as est
from ..analysis.metrics import Comparison
from ..analysis.verdict import Verdict
from ..errors import BadInput
from ..scenes import get_scene
from .identify import Model, chosen_unknowns, fit_one
from .measured import add_noise, clean_record, fit_spec
from .plan import names


def coverage(scene_name: str, pairs, records: int, params: dict | None = None,
             noise: dict | None = None, seed: int = 0, unknowns=None, channels=None,
             log=None) -> dict:
    """How often the truth lies in the 95 % interval: for each (synthesising solver, fitting
    solver) pair, `records` records (one clean run of the synthesiser, white noise drawn from
    `seed`, `seed` + 1, …) fitted by the other solver from the truth (this measures the
    intervals; the multi-start that finds the basin is checked apart), σ stated. Per pair and
    unknown: hits/records (a fit that failed or left the unknown undetermined is a miss)."""
    log = log or (lambda *a: None)
    scene = get_scene(scene_name)
    spec = fit_spec(scene)
    truth = scene.resolve(params or {})
    unknowns, scale = chosen_unknowns(scene, spec, unknowns, {})
    sig = {**spec.noise, **(noise or {})}
    clean = {}
    out = {"scene": scene.name, "records": records, "seed": seed, "noise": sig,
           "truth": {n: float(truth[n]) for n in unknowns}, "pairs": []}
    for syn, fitter in pairs:
        if syn not in clean:
            clean[syn] = clean_record(scene_name, syn, params, channels)
        chans = [c for c in clean[syn] if c != "t"]
        (s,) = solvers.pick(scene, [fitter])
        hits = {n: 0 for n in unknowns}
        t0 = time.perf_counter()
        for k in range(records):
            rec = add_noise(scene_name, clean[syn], noise, seed + k)
            fixed = {q: v for q, v in (params or {}).items() if q not in unknowns}
            model = Model(scene, s, fixed, unknowns, scale, rec, chans,
                          {c: sig[c] for c in chans})
            u0 = np.array([truth[n] for n in unknowns]) / np.array(scale)
            f = fit_one(model, u0, spec, scan=False, profile=False, log=log)
            for i, n in enumerate(unknowns):
                if f["converged"] and f["identifiable"][i]:
                    d = abs(est.wrap(f["values"][i] - truth[n], spec.periodic.get(n)))
                    hits[n] += d <= f["half_width"][i]
        row = {"synthesised_by": syn, "fitted_by": fitter, "hits": hits,
               "rate": {n: hits[n] / records for n in unknowns},
               "wall_s": time.perf_counter() - t0}
        log(f"coverage {syn} → {fitter}: " + ", ".join(
            f"{n} {row['rate'][n]:.0%}" for n in unknowns) + f" ({row['wall_s']:.3g} s)")
        out["pairs"].append(row)
    return out


# ------------------------------------------------------------------ detection limits
NOISE_FACTORS = (0.1, 0.3, 1.0, 3.0, 10.0)   # × the scene's Fit.noise
PROBE = 1e-6        # the size the signature is measured at (× its scale's unit: linear there)
DETECT_TOL = 1e-3   # relative: two solvers' limits agree within this plus their linearity


def detection(scene_name: str, solver_names=None, params: dict | None = None,
              alpha: float = 0.01, beta: float = 0.05, factors=NOISE_FACTORS,
              log=None) -> dict:
    """The smallest `Fit.size` told from none, per solver, speed and channel set, at noise
    factors × the scene's σ: the defect's signature d(t) = y(size) − y(0) from runs at PROBE
    and 2·PROBE (linear there: `linearity` is how far |d(2·PROBE)| is from 2|d(PROBE)|); a
    matched filter on white noise sees size·|d/size|_σ against unit noise, so with the angle
    searched over `Fit.starts` positions (Bonferroni) the limit is (z(1 − α/starts) +
    z(1 − β)) / |d/size|_σ — false-alarm rate α, miss rate β. Limits scale with σ exactly;
    solvers are compared at factor 1. Returns the map's dict (rows, comparisons)."""
    from scipy.stats import norm
    log = log or (lambda *a: None)
    scene = get_scene(scene_name)
    spec = fit_spec(scene)
    if not (spec.size and spec.speed and spec.channel_sets):
        raise BadInput(f"scene {scene.name} declares no detection limit")
    for name, v in (("--alpha", alpha), ("--beta", beta)):
        if not 0 < v < 0.5:
            raise BadInput(f"{name} {v}: a rate in (0, 0.5)")
    chosen = solvers.pick(scene, names(solver_names) or None)
    starts = spec.starts if spec.periodic else 1
    z = float(norm.isf(alpha / starts) + norm.isf(beta))
    sig = spec.noise
    rows = []
    for s in chosen:
        for w in spec.speeds:
            ys = []
            for h in (0.0, PROBE, 2 * PROBE):
                p = scene.resolve({**(params or {}), spec.size: h, spec.speed: w})
                tr = solvers.simulate(scene, s, p, solvers.settings_for(s, scene))
                ys.append(tr)
            bad = next((tr for tr in ys if tr.status != "ok"), None)
            for label, chans in spec.channel_sets.items():
                row = {"solver": s.name, "set": label, "speed": w}
                if bad is not None:
                    rows.append({**row, "status": bad.status, "reason": bad.reason})
                    continue
                d1 = np.concatenate([(ys[1].channels[c] - ys[0].channels[c]) / sig[c]
                                     for c in chans])
                d2 = np.concatenate([(ys[2].channels[c] - ys[0].channels[c]) / sig[c]
                                     for c in chans])
                g = float(np.linalg.norm(d1)) / PROBE
                lin = abs(float(np.linalg.norm(d2)) / (2 * float(np.linalg.norm(d1))) - 1)
                steady = float(np.mean(ys[0].channels[scene.key_channel][-len(ys[0].t) // 5:]))
                rows.append({**row, "status": "ok", "steady_key": steady, "linearity": lin,
                             "limit": [z / g * f if g > 0 else math.inf for f in factors]})
            log(f"{scene.name}: {s.name} at {spec.speed} = {w:g} done")
    comps = []
    k1 = list(factors).index(1.0) if 1.0 in factors else 0
    for label in spec.channel_sets:
        for w in spec.speeds:
            at = [r for r in rows if r["set"] == label and r["speed"] == w]
            for i, a in enumerate(at):
                for b in at[i + 1:]:
                    ok = a["status"] == "ok" and b["status"] == "ok"
                    la, lb = (a["limit"][k1], b["limit"][k1]) if ok else (math.nan, math.nan)
                    tol = DETECT_TOL + (max(a["linearity"], b["linearity"]) if ok else 0.0)
                    diff = abs(la - lb)
                    v = (Verdict.INCOMPLETE if not ok else
                         Verdict.AGREE if diff <= tol * max(la, lb) else Verdict.DISAGREE)
                    c = Comparison(a["solver"], b["solver"], f"{label} @ {spec.speed}={w:g}",
                                   diff, diff, diff / max(la, lb) if ok else math.nan,
                                   max(la, lb) if ok else math.nan, tol, v,
                                   f"|Δ limit| against {DETECT_TOL:g} + linearity, relative",
                                   deviation=diff, error_estimate=None, allowance=math.nan)
                    comps.append({**c.as_dict(), "set": label, "speed": w})
    return {"scene": scene.name, "size": spec.size, "speed_param": spec.speed,
            "speeds": list(spec.speeds), "channel_sets": {k: list(v) for k, v in
                                                          spec.channel_sets.items()},
            "noise": dict(sig), "noise_factors": list(factors), "alpha": alpha, "beta": beta,
            "starts": starts, "z": z, "probe": PROBE, "key_channel": scene.key_channel,
            "rows": rows, "comparisons": comps}
