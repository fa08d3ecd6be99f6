"""Calibration as a study (`xval.calibrate`): N admissible parameter sets drawn from the region
the scene declares (`Calibration`), every solver run at each with its error estimate, and two
questions answered over all of them. Do the verdicts hold — no pair disagrees, and how wide is
the widest window (bound / deviation) a comparison leaves? Do the error bars bound the error —
coverage: the fraction of (set, solver, channel or mode) whose true error (against the
solver's own far tighter run, coverage.py's; a frequency scene's: its mesh ×2 (MESH_FAR) and
its root tolerance /1000, or the run of the solver the scene names as its truth) is within its
estimate; sharpness: the median true/estimate. A solver that stops at a set is skipped there
with its status and reason, never compared; where the scene's `outside` declares that stop (a
singular chart), the set is outside the region and nothing there is compared or counted.

The sets are drawn on [0, 1]^axes (numpy's Generator, or a hypothesis strategy: `strategy`),
mapped to each axis (log-uniform or uniform) and kept where `Scene.resolve` admits them.
Writes no file: the Result is held in memory."""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from .. import solvers as adapter
from ..analysis.metrics import ROOTS, frequency_errors, match_modes
from ..analysis.verdict import Verdict
from ..contract import rounds_with
from ..errors import BadInput
from ..leafinfo import MESH_SUFFIXES
from ..output import progress
from ..output.tables import calibration_summary
from ..results.calibrate import CalibrationResult
from ..scenes import Calibration, Scene, get_scene
from ..scenes.params import RUN_PARAMS
from .coverage import FAR_RTOL, bars, reference_run
from .inputs import positive

SPREAD = 2.0        # the default region: default/SPREAD … default·SPREAD (`--spread`)
HORIZON = 0.1       # a time scene's default horizon: this fraction of its default t_end
# a frequency leaf's truth: its mesh (ints named *elements/*segments) ×2, not finer: fem's
# Hermite beam is at its round-off floor past that (stiffness conditioning ∝ N⁴: rotating-beam's
# third mode moves 3e-6 Hz at ×4 and 1.4e-4 Hz at ×8, above the default's own error)
MESH_FAR = 2
FLOOR = 1e3         # a deviation below FLOOR·eps·scale is round-off: it opens no window
TRIES = 100         # draws per admissible set before the region is called inadmissible
EPS = np.finfo(float).eps


@dataclass(frozen=True)
class Axis:
    """One drawn parameter: u in [0, 1] ↦ a value in [lo, hi], log-uniform (lo, hi of one
    sign) or uniform."""
    name: str
    lo: float
    hi: float
    log: bool

    def at(self, u: float) -> float:
        if not self.log:
            return float(self.lo + u * (self.hi - self.lo))
        a, b = np.log(abs(self.lo)), np.log(abs(self.hi))
        return float(np.sign(self.lo) * np.exp(a + u * (b - a)))


def region(scene: Scene, held: dict | None = None,
           spread: float = SPREAD) -> tuple[list[Axis], dict]:
    """The scene's sampling region: (axes, fixed values), `Calibration`'s rules, a default
    axis default/spread … default·spread; `held` (name -> value, as `xval calibrate --set`
    gives them) holds those names out of it at that value."""
    cal = scene.calibration or Calibration()
    held = dict(held or {})
    axes = {}
    for p in scene.params:
        if p.is_float and p.physical and p.name not in RUN_PARAMS and p.default \
                and p.name not in cal.fixed and p.name not in held:
            lo, hi = sorted((p.default / spread, p.default * spread))
            lo = max(lo, np.nextafter(p.lo, np.inf) if p.open_lo else p.lo)
            axes[p.name] = Axis(p.name, lo, min(hi, p.hi), True)
    for name, (lo, hi) in cal.region.items():
        scene.param(name)
        if name in held:
            continue
        log = name in cal.log
        if log and not lo * hi > 0:
            raise BadInput(f"{scene.name}: calibration axis {name} is log-uniform over "
                           f"[{lo:g}, {hi:g}], which spans zero")
        axes[name] = Axis(name, float(lo), float(hi), log)
    fixed = {**cal.fixed, **held}
    if scene.has_output_grid and "t_end" not in fixed:
        dt = fixed.get("output_dt", scene.param("output_dt").default)
        steps = max(1, round(HORIZON * scene.param("t_end").default / dt))
        fixed["t_end"] = steps * dt
    return list(axes.values()), fixed


def overrides(axes: list[Axis], fixed: dict, us) -> dict:
    """The parameter overrides at the point `us` of [0, 1]^axes."""
    return {**fixed, **{a.name: a.at(u) for a, u in zip(axes, us)}}


def admissible(scene: Scene, over: dict) -> dict | None:
    """The resolved parameters, or None where the scene refuses them (a loop that cannot
    close)."""
    try:
        return scene.resolve(over)
    except BadInput:
        return None


def sample(scene: Scene, n: int, seed: int = 0, held: dict | None = None,
           spread: float = SPREAD) -> list[tuple[dict, dict]]:
    """`n` admissible (overrides, resolved parameters) drawn from the scene's region (`held`
    and `spread` as `region`'s)."""
    axes, fixed = region(scene, held, spread)
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(TRIES * n):
        if len(out) == n:
            return out
        over = overrides(axes, fixed, rng.random(len(axes)))
        params = admissible(scene, over)
        if params is not None:
            out.append((over, params))
    raise BadInput(f"{scene.name}: fewer than 1 in {TRIES} draws of its calibration region is "
                   f"admissible ({len(out)} of {n} sets found)")


def strategy(scene: Scene):
    """A hypothesis strategy of admissible overrides from the scene's region (the same map
    from [0, 1]^axes as `sample`)."""
    from hypothesis import strategies as st
    axes, fixed = region(scene)
    unit = st.floats(0.0, 1.0, allow_nan=False)
    return (st.tuples(*[unit] * len(axes)).map(lambda us: overrides(axes, fixed, us))
            .filter(lambda over: admissible(scene, over) is not None))


def modes_far_tighter(info, preset: dict) -> dict | None:
    """A frequency leaf's truth settings: its mesh ×MESH_FAR, its root tolerance ×FAR_RTOL
    (not below 1e-14); None where it has neither (a finite-difference step is no monotone
    accuracy knob, nor a root search's grid step)."""
    base = {**info.modes_defaults, **preset}
    out = dict(base)
    for k, v in base.items():
        if k.endswith(MESH_SUFFIXES) and isinstance(v, int) and not isinstance(v, bool):
            out[k] = v * MESH_FAR
        elif k == "rtol" and isinstance(v, float):
            out[k] = max(v * FAR_RTOL, 1e-14)
    return None if out == base else out


def mode_bars(m, ref) -> dict:
    """Per mode of run `m`: its estimate (plus what the truth `ref` knows of itself) and its
    true error |f − f_ref|, modes paired as bench_modes pairs them — where both runs give
    their roots (`metrics.ROOTS`), root by root: a mixed root may be named, and shifted into
    the rotor frame, one way by the run and another by its truth; or a status saying why
    there is none."""
    if ref is None:
        return {"status": "no tighter discretisation of its own and no declared truth"}
    if ref.status != "ok":
        return {"status": f"truth {ref.status}"}
    if all(ROOTS in r.extra for r in (m, ref)):     # root by root, whatever each run named
        fr, fm = ref.extra[ROOTS], m.extra[ROOTS]
        k = min(len(fr), len(fm))
        est, known = _root_errors(m, k), _root_errors(ref, k)
        return {"status": "ok",
                "estimate": {f"root {i + 1}": float(est[i] + known[i]) for i in range(k)},
                "true": {f"root {i + 1}": float(abs(fm[i] - fr[i])) for i in range(k)},
                "scale": {f"root {i + 1}": float(abs(fr[i])) for i in range(k)}}
    est, known = frequency_errors(m), frequency_errors(ref)
    if est is None:
        return {"status": "no frequency error estimate"}
    known = np.zeros(len(ref.frequencies_hz)) if known is None else known
    fr, fm = list(ref.frequencies_hz), list(m.frequencies_hz)
    pairs = match_modes(fr, ref.labels, fm, m.labels)
    if len(pairs) < len(fr) <= len(fm):       # repeated roots named differently: by order
        pairs = list(zip(np.argsort(fr, kind="stable"), np.argsort(fm, kind="stable")))
    name = lambda j: m.labels[j] or f"mode {j + 1}"      # noqa: E731
    return {"status": "ok",
            "estimate": {name(j): float(est[j] + known[i]) for i, j in pairs},
            "true": {name(j): float(abs(fm[j] - fr[i])) for i, j in pairs},
            "scale": {name(j): float(abs(fr[i])) for i, j in pairs}}


def _root_errors(run, k) -> np.ndarray:
    """A run's error estimate of each of its first k roots: its discretisation's and, where it
    gives it apart, its linearisation's (the run's finite differences are not its truth's)."""
    err = np.asarray(run.extra["roots_error_hz"][:k], float)
    lin = run.extra.get("roots_linearisation_error_hz")
    return err if lin is None else err + np.nan_to_num(np.asarray(lin, float)[:k])


def _run(scene, solver, params, first):
    return scene.either(time=_simulate, modes=_modes)(scene, solver, params, first)


def _modes(scene, solver, params, first):
    return adapter.modes(scene, solver, params)


def _simulate(scene, solver, params, first):
    settings = adapter.settings_for(solver, scene.name, t_out=scene.output_grid(params))
    return adapter.simulate(scene, solver, params, settings, warm_up=first,
                            estimate_error=scene.error_estimate)


def _truth(scene, solver, params, run, cal, cache):
    """The solver's truth at this set (its own far tighter run, else the declared truth
    solver's run or far tighter run), or None."""
    truth = scene.either(time=_time_truth, modes=_modes_truth)
    return truth(scene, solver, params, run, cal, cache)


def _modes_truth(scene, solver, params, run, cal, cache):
    other = cal.truth.get(solver.name)          # a declared truth first, as a time scene's
    if other:
        if other not in cache:
            cache[other] = adapter.modes(scene, adapter.get_solver(other), params)
        return cache[other]
    s = modes_far_tighter(solver.info(scene), solver.preset)
    return None if s is None else adapter.modes(scene, solver, params, s)


def _time_truth(scene, solver, params, run, cal, cache):
    if solver.name in cal.truth:
        other = cal.truth[solver.name]
        if other not in cache:
            cache[other] = reference_run(scene, adapter.get_solver(other), params)
        return cache[other]
    return reference_run(scene, solver, params, dt=run.settings.get("dt"))


def _plain(v):
    return v.tolist() if isinstance(v, np.ndarray) else v


def _mode_bars(scene, solver, params, run, cal, cache):
    return mode_bars(run, _truth(scene, solver, params, run, cal, cache))


def _time_bars(scene, solver, params, run, cal, cache):
    if not run.errors:
        return {"status": f"no error estimate ({run.stats.get('error_estimate_by')})"}
    return bars(scene, run, _truth(scene, solver, params, run, cal, cache))


def evaluate(scene: Scene, chosen: list, params: dict, first: bool = False) -> dict:
    """One set: every chosen solver's run, their verdicts (ok runs only: a stopped solver is
    never compared) and per ok solver its error bars against its truth (`bars`: status, and
    per channel or mode "estimate" and "true")."""
    cal = scene.calibration or Calibration()
    runs = {s.name: _run(scene, s, params, first) for s in chosen}
    ok = [r for r in runs.values() if r.status == "ok"]
    cache, out = {}, {}
    for s in chosen:
        r = runs[s.name]
        if r.status != "ok":
            continue
        out[s.name] = scene.either(time=_time_bars, modes=_mode_bars)(
            scene, s, params, r, cal, cache)
    comparisons = scene.verdicts(params, ok)
    return {"runs": runs, "comparisons": comparisons, "bars": out,
            "explained": explained(scene, params, comparisons, runs)}


def _rounds_with(scene: Scene, c, params: dict) -> float:
    """The size a comparison's round-off scales with: its scale, or the parameter its channel
    names (`Channel.rounding`: a length the channel is computed from) where that is larger."""
    channel = next((ch for ch in scene.channels if ch == c.channel), c.channel)
    return rounds_with(channel, c.scale, params)


def explained(scene: Scene, params: dict, comparisons: list, runs: dict) -> dict:
    """(a, b, channel) -> why, for each disagreement the scene's `explain_frequencies` verifies
    as a named difference of the two models (the helicopters' rotor-frame assumption: the other
    model with it reproduces the mode, the pair agrees on the differential modes and at rest —
    compare/scenes/mstmm_frames.py); the rest stay disagreements."""
    if not scene.explain_frequencies or not any(c.verdict == Verdict.DISAGREE
                                                for c in comparisons):
        return {}
    rows, _ = scene.explain_frequencies(
        params, comparisons, lambda n, p: runs[n] if p == params and n in runs
        else adapter.modes(scene, adapter.get_solver(n), p), scene.tolerances_for(params))
    return {(r["a"], r["b"], r["mode"]): r["why"] for r in rows if r["frame"]}


def declared(cal: Calibration, solver: str, reason: str | None) -> str | None:
    """Why the scene declares this stop outside the solver's domain (`Calibration.outside`:
    the solver's entry, else "*"'s, whose reason prefix the stop's reason must start with),
    or None: an undeclared stop."""
    entry = cal.outside.get(solver, cal.outside.get("*"))
    if entry is None:
        return None
    why, starts = entry
    return why if (reason or "").startswith(starts) else None


def held_values(scene: Scene, overrides: dict | None) -> dict:
    """`--set` overrides as the values they resolve to (SI; a unit converted, a bad name or
    value refused with one line)."""
    if not overrides:
        return {}
    resolved = scene.resolve(overrides)
    return {name: resolved[name] for name in overrides}


def calibrate(scene_name: str, samples: int, seed: int = 0, solvers=None,
              log=None, held: dict | None = None, spread: float = SPREAD,
              campbell: bool = False) -> CalibrationResult:
    """The study over `samples` sets drawn with `seed` (solvers: the scene's unless named;
    `held`: parameters held at a value in every set, `--set`; `spread`: how far the default
    axes reach, `--spread`; `campbell`: each set's Campbell sweep judged too, `--campbell`)."""
    t0 = time.perf_counter()
    if positive("--spread", spread) <= 1:
        raise BadInput(f"--spread must be greater than 1, got {spread!r}")
    scene = get_scene(scene_name)
    if campbell and scene.campbell is None:
        raise BadInput(f"--campbell: scene {scene.name} has no Campbell sweep")
    cal = scene.calibration or Calibration()
    chosen = adapter.pick(scene, solvers)
    held = held_values(scene, held)
    axes, fixed = region(scene, held, spread)
    defaults = scene.resolve(fixed)
    rows, skipped, disagree, n_cmp, verdicts = [], [], [], 0, {}
    explained_rows = []
    left_out = {s.name: {} for s in chosen}
    widest, windows = None, []
    sweeps = {"sets": 0, "comparisons": 0, "verdicts": {}, "unconfirmed": 0}
    bar = progress.task(f"calibrate {scene.name}", samples, "parameter sets")
    for k, (over, params) in enumerate(sample(scene, samples, seed, held, spread)):
        one = evaluate(scene, chosen, params, first=(k == 0))
        bar.advance()
        changed = {n: _plain(params[n]) for n in over if n not in fixed
                   and not np.array_equal(params[n], defaults[n])}
        stopped = [{"sample": k, "solver": s, "status": r.status, "reason": r.reason,
                    "declared": declared(cal, s, r.reason)}
                   for s, r in one["runs"].items() if r.status != "ok"]
        outside = next((x["declared"] for x in stopped if x["declared"]), None)
        for x in stopped:          # a set outside the region: every stop there is outside
            x["declared"] = x["declared"] or outside
        skipped += stopped
        if log:
            log(f"{scene.name} set {k + 1}/{samples}: "
                + ", ".join(f"{s} {r.status}" for s, r in one["runs"].items()))
        if any(x["declared"] for x in stopped):
            continue      # outside a solver's declared domain: outside the region
        if campbell:
            disagree += _sweep(scene, chosen, params, k, changed, sweeps)
        for c in one["comparisons"]:
            if c.verdict == Verdict.SKIPPED:
                continue
            n_cmp += 1
            verdicts[str(c.verdict)] = verdicts.get(str(c.verdict), 0) + 1
            where = {"sample": k, "params": changed, "a": c.a, "b": c.b, "channel": c.channel}
            why = one["explained"].get((c.a, c.b, c.channel))
            if c.verdict == Verdict.DISAGREE and why:
                explained_rows.append({**where, "ratio": float(c.ratio), "why": why})
            elif c.verdict == Verdict.DISAGREE:
                disagree.append({**where, "ratio": float(c.ratio)})
            bound = c.tolerance * c.scale
            if c.deviation > FLOOR * EPS * _rounds_with(scene, c, params) and bound > 0:
                window = bound / c.deviation
                windows.append((window, f"{c.a}|{c.b}", k, c.channel))
                if widest is None or window > widest["window"]:
                    widest = {**where, "window": float(window), "deviation": float(c.deviation),
                              "bound": float(bound)}
        for s, b in one["bars"].items():
            if b["status"] != "ok":
                left_out[s][b["status"]] = left_out[s].get(b["status"], 0) + 1
                continue
            # a time run's truth also carries its own rounding (`bars`' floor)
            rows += [(s, k, c, b["true"][c], b["estimate"][c],
                      max(FLOOR * EPS * b["scale"][c], b.get("floor", {}).get(c, 0.0)))
                     for c in b["true"]]
    data = {"scene": scene.name, "samples": samples, "comparisons": n_cmp,
            "disagree": disagree, "explained": explained_rows, **_coverage(rows),
            "widest_window": widest["window"] if widest else None,
            "windows": _windows(windows),
            "skipped": skipped, "seed": seed, "solvers": [s.name for s in chosen],
            "verdicts": verdicts, "widest_at": widest,
            **({"campbell": sweeps} if campbell else {}),
            "by_solver": {s.name: {**_coverage([r for r in rows if r[0] == s.name]),
                                   "left_out": left_out[s.name]} for s in chosen},
            "region": {a.name: [a.lo, a.hi, "log" if a.log else "uniform"] for a in axes},
            "spread": float(spread),
            "fixed": {n: _plain(v) for n, v in fixed.items()},
            "floor": f"a deviation below {FLOOR:g}·eps·scale opens no window; a true error "
                     f"below it or the truth's own rounding tests no error bar",
            "wall_s": time.perf_counter() - t0}
    data["summary"] = calibration_summary(data)
    bar.close()
    return CalibrationResult(data)


def _sweep(scene: Scene, chosen: list, params: dict, k: int, changed: dict,
           tally: dict) -> list:
    """Set k's Campbell sweep as `xval modes` judges it (every sampled speed pairwise, the
    critical speeds): its counts added to `tally`, its disagreements returned as rows of
    `disagree` (a false alarm at any speed is one); a critical speed a solver finds but does
    not confirm is counted, not compared."""
    from .modes import campbell_diagram
    obj, _, told, *_ = campbell_diagram(scene, chosen, params, log=lambda *a: None)
    counted = obj["sweep_verdicts"]            # the sweep's own tally (Verdict.tally)
    tally["sets"] += 1
    tally["comparisons"] += counted["comparisons"]
    for v, n in counted["counts"].items():
        tally["verdicts"][str(v)] = tally["verdicts"].get(str(v), 0) + n
    tally["unconfirmed"] += sum(map(len, obj["unconfirmed_critical_speeds"].values()))
    return [{"sample": k, "params": changed, "a": c.a, "b": c.b, "channel": c.channel,
             "ratio": float(c.ratio), "campbell": True}
            for c in told["sweep"] if c.verdict == Verdict.DISAGREE]


# a window past this is a bound that would pass a bug this many times the pair's deviation
WIDE_WINDOW = 100.0


def _windows(windows: list) -> dict:
    """How the windows (window, "a|b", set, channel) the comparisons opened spread: how many,
    how many past WIDE_WINDOW, of which pairs and the ten widest of them, and their median and
    95th percentile — whether the widest is the rule or a few pairs (a deviation that crosses
    zero at a set, two runs sharing an error their bound counts) — and `typical`."""
    w = np.asarray([x[0] for x in windows], float)
    by_pair: dict = {}
    for x, pair, *_ in windows:
        if x > WIDE_WINDOW:
            by_pair[pair] = by_pair.get(pair, 0) + 1
    wide = sorted((x for x in windows if x[0] > WIDE_WINDOW), key=lambda x: -x[0])[:10]
    return {"opened": len(w), "over_100": int(np.sum(w > WIDE_WINDOW)),
            "over_100_by_pair": dict(sorted(by_pair.items(), key=lambda kv: -kv[1])),
            "over_100_at": [{"sample": k, "pair": pair, "channel": c, "window": float(x)}
                            for x, pair, k, c in wide],
            "median": float(np.median(w)) if len(w) else None,
            "p95": float(np.percentile(w, 95)) if len(w) else None,
            "typical": _typical(windows)}


# sets a (pair, channel) must open a window at for its median to say how wide its bound is
TYPICAL_SETS = 5


def _typical(windows: list) -> dict:
    """Each (pair, channel)'s median window over the sets it opened one at (≥ TYPICAL_SETS):
    how wide its bound is as a rule. The widest single window is a statistic of chance: where
    a pair's deviation is an independent error of spread σ under a bound kσ, the window
    exceeds W with probability P(|z| < k/W) ≈ 0.8 k/W, so of n comparisons about 0.8 k n / W
    do, however sharp the bars — while the median over sets is k/0.674, about 1.5 k. A bound
    wide by design (two runs sharing the error it counts) is wide at every set: its median
    says so. {"widest": {"pair", "channel", "median", "sets"} or None, "over_100": how many
    medians pass WIDE_WINDOW, "of": how many (pair, channel) have one}."""
    by: dict = {}
    for x, pair, _, channel in windows:
        by.setdefault((pair, channel), []).append(x)
    medians = {key: float(np.median(v)) for key, v in by.items() if len(v) >= TYPICAL_SETS}
    if not medians:
        return {"widest": None, "over_100": 0, "of": 0}
    (pair, channel), top = max(medians.items(), key=lambda kv: kv[1])
    return {"widest": {"pair": pair, "channel": channel, "median": top,
                       "sets": len(by[pair, channel])},
            "over_100": sum(m > WIDE_WINDOW for m in medians.values()), "of": len(medians)}


def _coverage(rows) -> dict:
    """Coverage, sharpness and the worst misses of (solver, set, channel, true, estimate,
    floor). A true error at or below its floor — FLOOR·eps·scale, or what the truth itself is
    not known better than — is round-off of the runs, not the solver's error: it tests no error
    bar and is counted as `unresolved`."""
    resolved = [r for r in rows if r[3] > r[5]]
    out = {"pairs": len(rows), "unresolved": len(rows) - len(resolved)}
    if not resolved:
        return {**out, "coverage": None, "sharpness": None, "misses": []}
    true = np.array([r[3] for r in resolved])
    est = np.array([r[4] for r in resolved])
    miss = sorted((r for r, t, e in zip(resolved, true, est) if t > e),
                  key=lambda r: -r[3] / max(r[4], 1e-300))[:5]
    return {**out, "coverage": float(np.mean(true <= est)),
            "sharpness": float(np.median(true[est > 0] / est[est > 0])) if np.any(est > 0)
            else None,
            "misses": [{"solver": s, "sample": k, "channel": c, "true": t, "estimate": e}
                       for s, k, c, t, e, _ in miss]}
