"""The speed where a root starts to grow (`Scene.threshold`: issue 28's internal-damping
threshold), side by side: the closed form; each solver's eigenvalues (its largest growth rate
crossing zero, located by brentq); the growth of the time solvers' free responses — released at
constant speed, the growing root fitted by matrix pencil, its zero located by brentq and
interpolated between the evaluated speeds that bracket it. Each time-domain growth rate is
checked against the closed form's at the speed the run measured. Nothing here names a scene;
nothing is written.
"""
from __future__ import annotations

import math
import time

import numpy as np
from scipy.optimize import brentq

from .. import solvers
from ..analysis.identify import growing_pole
from ..analysis.response import mean_spin
from .response import time_runs

BRACKET = 0.05      # the zero is sought within ±5 % of the closed form's speed
EIGEN_XTOL = 1e-9   # relative resolution of the eigenvalue thresholds (their σ: ~1e-12 /s)
RESOLUTION = 1e-6   # relative resolution of the time-domain search (brentq's xtol)
RECORD_S = 5.0      # each free response; fitted over its first half and over all of it
SAMPLES = 16        # output samples per revolution (≥ 20 per period of a whirl slower than Ω)
# lags of the pencil: a record of `roots` exponentials needs few. 16 keeps the SVD at a
# millisecond where BLAS runs threaded on busy cores (under pytest numpy loads before compare
# caps its threads: 64 lags took 0.02–2.3 s there, N/3 up to 50 s); at 0.95/1.05 Ω_th σ was
# the same to 2e-12 /s with 16, 32 and 64 lags and to 1e-11 with N/3
PENCIL = 16


def growth_at(scene, params: dict, solver: str, speed: float) -> dict:
    """One time solver's growing root at one speed: the rotor released (scene.threshold.release,
    no forcing) at the speed, `RECORD_S` at its accurate settings and again at its tighter ones.
    Error bar on σ: the fit's change between the half record and the whole plus the solver's
    own error (factor·|σ − σ_tight|). Checked against the closed form's σ at the measured
    speed."""
    th, spec = scene.threshold, scene.response
    free = {**params, **th.free}
    dt = 2 * math.pi / abs(speed) / SAMPLES
    over, extra = spec.time_params(free, speed, math.ceil(RECORD_S / dt) * dt, dt,
                                   release=th.release)
    p_, runs, factor, how = time_runs(spec, over, extra, solver)
    row = {"speed_rad_s": speed}
    bad = next((tr for tr in runs if tr.status != "ok"), None)
    if bad is not None:
        return {**row, "status": bad.status, "reason": bad.reason}
    observed = [spec.observe(p_, tr) for tr in runs]
    fits = [[growing_pole(z[:n], dt, th.roots, PENCIL) for n in (len(z) // 2, len(z))]
            for z, _ in observed]
    spin = mean_spin(runs[0].t, observed[0][1])
    lam = fits[0][1]
    change = abs(lam.real - fits[0][0].real)
    own = factor * abs(lam.real - fits[1][1].real) if len(fits) > 1 else 0.0
    sigma, omega = th.growth(free, spin)
    err = change + own
    return {**row, "status": "ok", "spin_rad_s": spin, "growth_per_s": lam.real,
            "whirl_rad_s": lam.imag, "record_change": change, "solver_error": own,
            "error": err, "error_by": how, "closed_form_growth_per_s": sigma,
            "closed_form_whirl_rad_s": omega, "agrees": bool(abs(lam.real - sigma) <= err),
            "wall_s": sum(tr.wall_s for tr in runs)}


class _Stop(Exception):
    pass


def time_threshold(scene, params: dict, solver: str, w_cf: float, log) -> dict:
    """The speed where the time solver's fitted growth rate crosses zero: brentq over
    ±BRACKET of the closed form to RESOLUTION, then the linear interpolation between the two
    evaluated runs that bracket the zero (in their measured speeds). Error bar: the larger σ
    error of the two over the slope between the bracket's ends, plus how far the quadratic
    through the three runs nearest the zero puts it from the linear one."""
    points, memo = [], {}

    def sigma(w):
        if w not in memo:                      # brentq evaluates its bracket's ends again
            log(f"{scene.name}: {solver} free response at {w:.8g} rad/s …")
            points.append(growth_at(scene, params, solver, float(w)))
            if points[-1]["status"] != "ok":
                raise _Stop
            memo[w] = points[-1]["growth_per_s"]
        return memo[w]
    out = {"solver": solver, "points": points}
    t0 = time.perf_counter()
    lo, hi = w_cf * (1 - BRACKET), w_cf * (1 + BRACKET)
    try:
        if sigma(lo) * sigma(hi) > 0:
            return {**out, "status": "no zero",
                    "reason": f"σ has one sign over {lo:.6g}–{hi:.6g} rad/s"}
        brentq(sigma, lo, hi, xtol=RESOLUTION * w_cf)
    except _Stop:
        return {**out, "status": points[-1]["status"], "reason": points[-1]["reason"]}
    w = np.array([p["spin_rad_s"] for p in points])
    s = np.array([p["growth_per_s"] for p in points])
    e = np.array([p["error"] for p in points])
    below = np.flatnonzero(s < 0)[np.argmax(w[s < 0])]
    above = np.flatnonzero(s >= 0)[np.argmin(w[s >= 0])]
    at = w[below] - s[below] * (w[above] - w[below]) / (s[above] - s[below])
    slope = (s[1] - s[0]) / (w[1] - w[0])                  # the ±BRACKET runs
    near = np.argsort(np.abs(w - at))[:3]
    roots = np.roots(np.polyfit(w[near] - at, s[near], 2)).real + at
    interp = float(np.min(np.abs(roots - at)))
    err = float(max(e[below], e[above]) / abs(slope) + interp)
    return {**out, "status": "ok", "threshold_rad_s": float(at), "error_rad_s": float(err),
            "interpolation_rad_s": interp, "slope_per_s_per_rad_s": float(slope),
            "evaluations": len(points), "wall_s": time.perf_counter() - t0,
            "agrees": bool(abs(at - w_cf) <= err)}


def eigen_threshold(scene, solver, params: dict, w_cf: float) -> dict:
    """The speed where the solver's largest Re λ (`Modes.extra["max_re_per_s"]`) crosses zero:
    brentq over ±BRACKET of the closed form to EIGEN_XTOL."""
    par = scene.threshold.parameter
    memo = {}

    def growth(w):
        if w not in memo:
            m = solvers.modes(scene, solver, {**params, par: float(w)})
            if m.status != "ok":
                raise _Stop(f"{m.status}: {m.reason}")
            memo[w] = m.extra["max_re_per_s"]
        return memo[w]
    t0 = time.perf_counter()
    lo, hi = w_cf * (1 - BRACKET), w_cf * (1 + BRACKET)
    out = {"solver": solver.name}
    try:
        if growth(lo) * growth(hi) > 0:
            return {**out, "status": "no zero",
                    "reason": f"max Re λ has one sign over {lo:.6g}–{hi:.6g} rad/s"}
        at = brentq(growth, lo, hi, xtol=EIGEN_XTOL * w_cf)
    except _Stop as e:
        return {**out, "status": "failed", "reason": str(e)}
    err = EIGEN_XTOL * w_cf
    return {**out, "status": "ok", "threshold_rad_s": float(at), "error_rad_s": err,
            "evaluations": len(memo), "wall_s": time.perf_counter() - t0,
            "agrees": bool(abs(at - w_cf) <= err)}


def run_threshold(scene, params: dict, chosen, names, log) -> dict:
    """The threshold block of `xval modes` (its JSON; compare/output/modes_report.py writes
    its section): the closed form, every chosen solver's eigenvalues, every time solver of the
    scene's response among `names` (all where none are named)."""
    th = scene.threshold
    w_cf = float(th.speed(params))
    obj = {"parameter": th.parameter, "closed_form_rad_s": w_cf if math.isfinite(w_cf) else None}
    if not math.isfinite(w_cf):
        return obj
    timed = [s for s in scene.response.time_solvers if not names or s in names]
    obj["eigenvalues"] = [eigen_threshold(scene, s, params, w_cf) for s in chosen]
    obj["time_domain"] = [time_threshold(scene, params, s, w_cf, log) for s in timed]
    obj.update(release=th.release, record_s=RECORD_S, bracket=BRACKET, resolution=RESOLUTION)
    return obj
