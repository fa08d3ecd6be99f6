"""`xval identify`: a scene's unknown parameters fitted to a measured record, by each solver's
runs as the model, and the estimates judged solver against solver.

The fit (scipy's `least_squares`, trust-region reflective within the parameters' admissible
ranges): residuals (model − data)/σ over every channel the record holds, the model run on a
uniform grid from t = 0 (the scene's initial state) to the record's end and read at the record's
times (a cubic spline, exact where the record lies on the grid). Unknowns are scaled by the
scene's `Fit.scale`. The first solver fits from a multi-start: `Fit.starts` points across each
periodic unknown (the others at their given values), the three lowest local minima of that scan
refined; the other solvers start from its optimum (each converges to its own). σ per channel: as
stated, else estimated from the record's second differences and, after a first fit, from the
residuals (refit once). Intervals: the Jacobian's (central differences of the solver's runs,
step SENS_STEP of each scale) covariance, 95 %; checked on the first solver by the profile of
the cost at each interval's ends (Δχ² against z², CONFIRMED the accepted ratio). An unknown whose
interval is wider than its scale (a quarter period when periodic) or lies in a direction the data
do not see is reported undetermined, with no value. Records are read, checked and synthesised
in measured.py; the intervals' coverage and the detection limits in detection.py. Nothing is
written here.
"""
from __future__ import annotations

import math
import time

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.optimize import least_squares

from .. import solvers
from ..analysis import estimates as est
from ..analysis import poincare
from ..analysis.metrics import Comparison
from ..errors import BadInput
from ..results.identify import IdentifyResult
from ..scenes import get_scene
from ..scenes.params import RUN_PARAMS
from .measured import check_record, fit_spec
from .plan import names

SENS_STEP = 1e-3       # central-difference step of the Jacobian, in each unknown's scale
DIFF_STEP = 1e-4       # least_squares' own forward-difference step (relative)
MAX_NFEV = 200
TOL = 1e-8             # least_squares' xtol, ftol, gtol
REFINE = 3             # scan minima refined by the first solver
CONFIRMED = (0.5, 2.0)  # Δχ² at an interval's end over z²: the profile confirms it
FAIL_RESIDUAL = 1e3    # each residual of a run that failed (the fit steps back from it)


# ------------------------------------------------------------------ the model
def model_grid(t: np.ndarray, output_dt: float) -> tuple[np.ndarray, float]:
    """A uniform grid from 0 through the record's end, its step at most `output_dt` and, for a
    uniformly sampled record, a whole fraction of its step (so the record lies on the grid)."""
    dt = float(np.median(np.diff(t)))
    h = min(output_dt, dt)
    if np.allclose(np.diff(t), dt, rtol=1e-9, atol=0) and \
            abs(t[0] / dt - round(t[0] / dt)) < 1e-6:
        h = dt / math.ceil(dt / output_dt - 1e-9)
    n = math.ceil(t[-1] / h - 1e-9)
    return np.arange(n + 1) * h, h


class Model:
    """One solver's runs as the model of a record: residuals of scaled unknowns u."""

    def __init__(self, scene, solver, base: dict, unknowns, scale, rec, chans, sigma,
                 estimated=(), section=None):
        self.scene, self.solver, self.unknowns = scene, solver, list(unknowns)
        self.scale = np.asarray(scale, float)
        self.rec = rec
        self.sigma, self.estimated = dict(sigma), list(estimated)
        # section: (phase, angle, x, y channels): x, y fitted once per revolution, not in time
        self.section = section
        self.chans = [c for c in chans if not section or c not in section[2:]]
        self.needed = list(dict.fromkeys(self.chans + list(section[1:] if section else [])))
        self.data_section = self._section(rec) if section else None
        out_dt = scene.resolve(base)["output_dt"]
        self.grid, self.h = model_grid(rec["t"], out_dt)
        self.base = {**base, "t_end": self.grid[-1], "output_dt": self.h}
        self.settings = solvers.settings_for(solver, scene, t_out=self.grid)
        self.runs, self.failures, self.wall = 0, [], 0.0
        self._cache = {}

    def params(self, u) -> dict:
        return self.scene.resolve({**self.base, **dict(zip(self.unknowns, u * self.scale))})

    def curves(self, u) -> dict | None:
        """The model's channels at the record's times (None: the run failed, its reason kept)."""
        key = tuple(np.round(np.asarray(u, float), 15))
        if key in self._cache:
            return self._cache[key]
        try:
            p = self.params(u)
        except BadInput as e:
            self.failures.append(str(e))
            return None
        tr = solvers.simulate(self.scene, self.solver, p, self.settings, warm_up=False,
                              t_out=self.grid)
        self.runs += 1
        self.wall += tr.wall_s
        if tr.status != "ok":
            self.failures.append(f"{tr.status}: {tr.reason}")
            out = None
        else:
            out = {c: CubicSpline(self.grid, tr.channels[c])(self.rec["t"])
                   for c in self.needed}
        if len(self._cache) > 64:
            self._cache.clear()
        self._cache[key] = out
        return out

    def _section(self, curves) -> dict:
        phase, a, x, y = self.section
        return poincare.section(self.rec["t"], curves[a], curves[x], curves[y], phase)

    def section_residuals(self, y) -> tuple[np.ndarray, np.ndarray]:
        """Model − data of the section's x and y at the record's revolutions."""
        return poincare.matched(self.data_section, self._section(y), FAIL_RESIDUAL *
                                max(self.sigma[c] for c in self.section[2:]))

    def residuals(self, u) -> np.ndarray:
        y = self.curves(u)
        n = len(self.rec["t"]) * len(self.chans) + (
            2 * len(self.data_section["k"]) if self.section else 0)
        if y is None:
            return np.full(n, FAIL_RESIDUAL)
        parts = [(y[c] - self.rec[c]) / self.sigma[c] for c in self.chans]
        if self.section:
            dx, dy = self.section_residuals(y)
            parts += [dx / self.sigma[self.section[2]], dy / self.sigma[self.section[3]]]
        return np.concatenate(parts)

    def jacobian(self, u, only=None) -> np.ndarray:
        """Central differences of the residuals, step SENS_STEP in each scaled unknown (one
        sided at a bound); columns of `only` (default: all)."""
        cols = []
        lo, hi = self.bounds()
        for i in (range(len(u)) if only is None else only):
            up, dn = np.array(u, float), np.array(u, float)
            up[i] = min(u[i] + SENS_STEP, hi[i])
            dn[i] = max(u[i] - SENS_STEP, lo[i])
            cols.append((self.residuals(up) - self.residuals(dn)) / (up[i] - dn[i]))
        return np.column_stack(cols)

    def bounds(self):
        """The unknowns' admissible ranges in scaled units (an open end kept a step off)."""
        lo, hi = [], []
        for name, s in zip(self.unknowns, self.scale):
            p = self.scene.param(name)
            a = p.lo + (1e-6 * s if p.open_lo else 0.0)
            lo.append(a / s)
            hi.append(p.hi / s)
        return np.array(lo), np.array(hi)


# ------------------------------------------------------------------ one solver's fit
def _solve(model, u0, free=None, fixed_u=None):
    """least_squares over the `free` unknowns (default all), the others held at `fixed_u`."""
    lo, hi = model.bounds()
    free = list(range(len(u0))) if free is None else list(free)
    full = np.array(u0 if fixed_u is None else fixed_u, float)

    def f(v):
        w = np.array(full)
        w[free] = v
        return model.residuals(w)

    start = np.clip(np.asarray(u0, float)[free], lo[free], hi[free])
    sol = least_squares(f, start, bounds=(lo[free], hi[free]), method="trf", x_scale=1.0,
                        diff_step=DIFF_STEP, xtol=TOL, ftol=TOL, gtol=TOL,
                        max_nfev=MAX_NFEV)
    w = np.array(full)
    w[free] = sol.x
    return w, sol


def _scan(model, u0, spec, log):
    """The cost at `spec.starts` points across each periodic unknown (the rest at u0): the
    starts at the REFINE lowest local minima of the (cyclic) scan."""
    starts = [np.asarray(u0, float)]
    for name, period in spec.periodic.items():
        if name not in model.unknowns:
            continue
        i = model.unknowns.index(name)
        grid = (np.arange(spec.starts) / spec.starts - 0.5) * period
        cost = []
        for a in grid:
            u = np.array(u0, float)
            u[i] = a / model.scale[i]
            r = model.residuals(u)
            cost.append(float(r @ r))
        cost = np.array(cost)
        minima = [k for k in range(len(cost))
                  if cost[k] <= cost[k - 1] and cost[k] <= cost[(k + 1) % len(cost)]]
        minima.sort(key=lambda k: cost[k])
        log(f"  scan of {name}: {spec.starts} starts, lowest at " + ", ".join(
            f"{grid[k]:.3g}" for k in minima[:REFINE]))
        starts = []
        for k in minima[:REFINE]:
            u = np.array(u0, float)
            u[i] = grid[k] / model.scale[i]
            starts.append(u)
    return starts


def _residual_by_channel(model, y) -> dict:
    """Model − data per fitted channel; a section's x and y once per revolution."""
    out = {c: y[c] - model.rec[c] for c in model.chans}
    if model.section:
        dx, dy = model.section_residuals(y)
        out[model.section[2]], out[model.section[3]] = dx, dy
    return out


def _explains(chi2: float, dof: int) -> bool:
    """χ² within 3 standard deviations (√(2·dof)) of its expectation: residuals at the noise."""
    return chi2 <= dof + 3.0 * math.sqrt(2.0 * max(dof, 1))


def fit_one(model, u0, spec, scan: bool, profile: bool, log) -> dict:
    """One solver's fit of the record: multi-start (scan) or from u0, σ re-estimated where not
    stated, intervals, identifiability, correlations, residuals, the profile check."""
    t0 = time.perf_counter()
    best = None
    for u in (_scan(model, u0, spec, log) if scan else [np.asarray(u0, float)]):
        w, sol = _solve(model, u)
        if best is None or sol.cost < best[1].cost:
            best = (w, sol)
        if _explains(2 * best[1].cost, len(sol.fun) - len(u)):
            break      # the fit explains the data to their noise: no other start can do better
    u, sol = best
    if model.estimated:
        y = model.curves(u)
        if y is not None:
            for c, res in _residual_by_channel(model, y).items():
                if c in model.estimated:
                    n_dof = max(len(res) - len(u) / (len(model.chans) + 2 * bool(model.section)),
                                1.0)
                    model.sigma[c] = float(np.sqrt(np.sum(res ** 2) / n_dof))
            u, sol = _solve(model, u)
    y = model.curves(u)
    converged = bool(sol.success and y is not None)
    why = None if converged else (
        f"{sol.message}" + (f"; last failed run: {model.failures[-1]}" if model.failures
                            else ""))
    if not converged:
        return {"solver": model.solver.name, "converged": False, "why": why,
                "runs": model.runs, "wall_s": time.perf_counter() - t0}
    for name, period in spec.periodic.items():
        if name in model.unknowns:
            i = model.unknowns.index(name)
            u[i] = est.wrap(u[i] * model.scale[i], period) / model.scale[i]
    r = model.residuals(u)
    J = model.jacobian(u)
    limit = [spec.periodic[n] / 4 if n in spec.periodic else abs(s)
             for n, s in zip(model.unknowns, model.scale)]
    iv = est.intervals(J, model.scale, width_limit=limit)
    x = u * model.scale
    for name, gate in spec.through.items():
        if name in model.unknowns:
            i = model.unknowns.index(name)
            if gate in model.unknowns:
                g = model.unknowns.index(gate)
                zero = not iv["identifiable"][g] or abs(x[g]) <= iv["half_width"][g]
            else:
                zero = float(model.params(u)[gate]) == 0.0
            if zero:       # no size, no shape: a local interval here is the noise's
                iv["identifiable"][i] = False
    chi2 = float(r @ r)
    out = {"solver": model.solver.name, "converged": True, "why": None,
           "message": str(sol.message), "values": x.tolist(), "sd": iv["sd"].tolist(),
           "half_width": iv["half_width"].tolist(),
           "identifiable": iv["identifiable"].tolist(),
           "correlation": iv["correlation"].tolist(), "chi2": chi2,
           "dof": len(r) - len(u), "sigma": dict(model.sigma),
           "sigma_estimated": list(model.estimated),
           "residual_rms": {(f"{c} (section)" if model.section and c in model.section[2:]
                             else c): float(np.sqrt(np.mean(res ** 2)))
                            for c, res in _residual_by_channel(model, y).items()},
           "curves": {c: y[c] for c in model.needed}}
    if model.section:
        sec = model._section(y)
        out["section"] = {"x": sec["x"].tolist(), "y": sec["y"].tolist(), "k": sec["k"].tolist()}
    if profile:
        out["profile"] = _profile(model, u, chi2, iv)
    out["runs"], out["wall_s"] = model.runs, time.perf_counter() - t0
    out["solver_wall_s"] = model.wall
    return out


def _profile(model, u, chi2, iv) -> list:
    """Per determined unknown: Δχ² at each end of its interval, the other unknowns refitted
    (a bound in the way: that end is not checked), over z²; confirmed inside CONFIRMED."""
    rows = []
    lo, hi = model.bounds()
    for i, name in enumerate(model.unknowns):
        if not iv["identifiable"][i]:
            rows.append({"parameter": name, "confirmed": None})
            continue
        h = iv["half_width"][i] / model.scale[i]
        ends = []
        for sign in (-1, 1):
            v = u[i] + sign * h
            if not lo[i] <= v <= hi[i]:
                ends.append(None)
                continue
            w = np.array(u, float)
            w[i] = v
            others = [k for k in range(len(u)) if k != i]
            if others:
                w, _ = _solve(model, w, free=others, fixed_u=w)
            r = model.residuals(w)
            ends.append((float(r @ r) - chi2) / est.Z95 ** 2)
        seen = [e for e in ends if e is not None]
        rows.append({"parameter": name, "ratio_low": ends[0], "ratio_high": ends[1],
                     "confirmed": bool(seen) and all(CONFIRMED[0] <= e <= CONFIRMED[1]
                                                     for e in seen)})
    return rows


# ------------------------------------------------------------------ the study
def chosen_unknowns(scene, spec, unknowns, fixed: dict):
    chosen = list(unknowns or spec.unknowns)
    for n in chosen:
        try:
            p = scene.param(n)
        except (KeyError, BadInput):
            raise BadInput(f"--unknown {n}: no parameter of scene {scene.name} "
                           f"(`xval show {scene.name}`)") from None
        if not p.is_float or n in RUN_PARAMS:
            raise BadInput(f"--unknown {n}: not a scalar physical parameter")
        if n in fixed:
            raise BadInput(f"--unknown {n}: also given a value by --set")
    if len(set(chosen)) != len(chosen):
        raise BadInput("--unknown: a parameter named twice")
    scale = [spec.scale.get(n) or abs(float(scene.param(n).default)) or 1.0 for n in chosen]
    return chosen, scale


def _noise(spec, rec, chans, noise: dict | None):
    """σ per channel: stated (`noise`), else estimated from the record (and refined from the
    residuals after the first fit)."""
    noise = dict(noise or {})
    for c in noise:
        if c not in chans:
            raise BadInput(f"--noise {c}: not a channel of the record ({', '.join(chans)})")
        if not (noise[c] > 0 and math.isfinite(noise[c])):
            raise BadInput(f"--noise {c}: σ must be a positive number, got {noise[c]}")
    estimated = [c for c in chans if c not in noise]
    sigma = {**{c: est.noise_sigma(rec[c]) for c in estimated}, **noise}
    for c in estimated:
        if not sigma[c] > 0:
            raise BadInput(f"--data: channel {c} has no measurable noise (a noise-free record:"
                           f" state its σ with --noise {c}=…)")
    return sigma, estimated


def _check_revolution(scene, spec, model, rec):
    """The record turns through one period of the scene's revolution angle: read from the
    record where it has the channel, else from the model at its starting values."""
    if spec.revolution is None:
        return
    if spec.revolution in rec:
        turned = abs(rec[spec.revolution][-1] - rec[spec.revolution][0])
    else:
        p = model.params(model.u0)
        tr = solvers.simulate(scene, model.solver, p, model.settings, warm_up=False,
                              t_out=model.grid)
        ang = CubicSpline(model.grid, tr.channels[spec.revolution])(rec["t"][[0, -1]])
        turned = abs(ang[1] - ang[0]) if tr.status == "ok" else math.inf
    if turned < 2 * math.pi:
        raise BadInput(f"--data: the record covers {turned:.3g} rad of {spec.revolution}, "
                       "less than one revolution (2π)")


def identify(scene_name: str, rec: dict, unknowns=None, solver_names=None,
             overrides: dict | None = None, noise: dict | None = None, profile: bool = True,
             data_label: str = "(in memory)", poincare: float | None = None,
             log=None) -> IdentifyResult:
    """Fit the record `rec` ({"t": …, channel: …}) with each solver's model (the first from a
    multi-start, the others from its optimum), the estimates judged pair by pair. `poincare`:
    a shaft angle — the scene's section channels (`Fit.section`) fitted once per revolution
    there instead of in time."""
    log = log or (lambda *a: None)
    scene = get_scene(scene_name)
    spec = fit_spec(scene)
    chans = check_record(scene, rec)
    fixed = dict(overrides or {})
    unknowns, scale = chosen_unknowns(scene, spec, unknowns, fixed)
    chosen = solvers.pick(scene, names(solver_names) or None)
    sigma, estimated = _noise(spec, rec, chans, noise)
    section = _sectionfit_spec(scene, spec, chans, poincare)
    base = scene.resolve(fixed)
    u0 = np.array([float(base[n]) for n in unknowns]) / np.array(scale)
    fits, first = [], None
    for k, s in enumerate(chosen):
        model = Model(scene, s, fixed, unknowns, scale, rec, chans, sigma, estimated,
                      section)
        model.u0 = u0
        if k == 0:
            _check_revolution(scene, spec, model, rec)
        log(f"{scene.name}: fitting {', '.join(unknowns)} with {s.name} …")
        start = u0 if first is None else first
        f = fit_one(model, start, spec, scan=first is None, profile=profile and k == 0,
                    log=log)
        log(f"{scene.name}: {s.name} " + ("converged" if f["converged"] else
                                           f"did not converge: {f['why']}")
            + f" ({f['runs']} runs, {f['wall_s']:.3g} s)")
        if first is None and f["converged"]:
            first = np.array(f["values"]) / np.array(scale)
        fits.append(f)
    rows = _estimates(unknowns, fits)
    comparisons = _compare(unknowns, spec, fits, scale)
    data = {"scene": scene.name, "data": data_label, "channels": chans,
            "samples": len(rec["t"]), "t_span_s": [float(rec["t"][0]), float(rec["t"][-1])],
            "unknowns": unknowns, "units": [scene.param(n).unit for n in unknowns],
            "fixed": {k: v for k, v in fixed.items()}, "estimates": rows,
            "comparisons": comparisons,
            "residual_rms": next((f["residual_rms"] for f in fits if f["converged"]), {}),
            "fits": [{k: v for k, v in f.items() if k != "curves"} for f in fits]}
    curves = {f["solver"]: f["curves"] for f in fits if f["converged"]}
    if section:
        data["poincare"] = _sections(scene, spec, chosen[0], fixed, rec, section, fits)
    return IdentifyResult(data, record=rec, curves=curves)


def _sectionfit_spec(scene, spec, chans, phase):
    """(phase, angle, x, y) of `--poincare PHASE`, the record holding all three channels."""
    if phase is None:
        return None
    if not spec.section:
        raise BadInput(f"--poincare: scene {scene.name} declares no Poincaré section")
    if not math.isfinite(phase):
        raise BadInput(f"--poincare {phase}: not a finite angle")
    lack = [c for c in spec.section if c not in chans]
    if lack:
        raise BadInput(f"--poincare: the record lacks {', '.join(lack)} (the section needs "
                       f"{', '.join(spec.section)})")
    return (float(phase), *spec.section)


def _sections(scene, spec, solver, fixed, rec, section, fits) -> dict:
    """The record's section, each converged fit's, and the first solver's without the
    feature its `through` unknowns are seen through (defect height 0): the defect's
    signature is the offset between them."""
    phase = section[0]
    model = Model(scene, solver, fixed, [], [], rec, [], {c: 1.0 for c in section[1:]},
                  section=section)
    data = model.data_section
    out = {"phase": phase, "points": len(data["k"]), "angle": section[1],
           "x": section[2], "y": section[3],
           "sections": {"data": {"k": data["k"].tolist(), "x": data["x"].tolist(),
                                 "y": data["y"].tolist()}}}
    for f in fits:
        if f["converged"]:
            out["sections"][f["solver"]] = f["section"]
    absent = {g: 0.0 for g in dict.fromkeys(spec.through.values())}
    if absent:
        bare = Model(scene, solver, {**fixed, **absent}, [], [], rec, [],
                     {c: 1.0 for c in section[1:]}, section=section)
        y = bare.curves(np.zeros(0))
        if y is not None:
            sec = bare._section(y)
            label = f"{solver.name}, " + ", ".join(f"{k} = 0" for k in absent)
            out["sections"][label] = {"k": sec["k"].tolist(), "x": sec["x"].tolist(),
                                      "y": sec["y"].tolist()}
    return out


def _estimates(unknowns, fits) -> list[dict]:
    rows = []
    for f in fits:
        for i, n in enumerate(unknowns):
            ok = f["converged"] and f["identifiable"][i]
            v, h = (f["values"][i], f["half_width"][i]) if ok else (None, None)
            rows.append({"solver": f["solver"], "parameter": n, "value": v,
                         "ci_low": None if v is None else v - h,
                         "ci_high": None if v is None else v + h,
                         "identifiable": bool(ok), "converged": f["converged"]})
    return rows


def _compare(unknowns, spec, fits, scale) -> list[dict]:
    rows = []
    for a_i, fa in enumerate(fits):
        for fb in fits[a_i + 1:]:
            for i, n in enumerate(unknowns):
                side = [{"ok": f["converged"],
                         **({"value": f["values"][i], "half_width": f["half_width"][i],
                             "identifiable": f["identifiable"][i]} if f["converged"] else {})}
                        for f in (fa, fb)]
                j = est.judge(*side, spec.periodic.get(n))
                diff, bound = j.get("difference", math.nan), j.get("bound", math.nan)
                c = Comparison(fa["solver"], fb["solver"], n, diff, diff, diff / scale[i],
                               scale[i], bound / scale[i], j["verdict"],
                               j.get("why") or "|Δ estimate| against √(h_a² + h_b²), the two "
                               "95 % half widths", deviation=diff, error_estimate=bound,
                               allowance=0.0)
                rows.append({**c.as_dict(), "parameter": n, "difference": diff,
                             "bound": bound})
    return rows
