"""`xval response`: the steady unbalance response vs spin through the first critical speed —
in the frequency domain from every leaf that takes the unbalance as an input of its own linear
model (`unbalance_response`), in the time domain from the scene's time solvers run at
constant spin to steady state and fitted at 1× — judged speed by speed on amplitude and phase
against the error bars, with each curve's peak, amplification factor and half-power damping
set against the modal damping ratio there. Nothing here names a scene; nothing is written.
"""
from __future__ import annotations

import math
import time

import numpy as np

from .. import solvers
from ..analysis import response as resp
from ..analysis.verdict import Verdict
from ..errors import BadInput
from ..output import progress
from ..results.response import ResponseResult, time_label
from ..scenes import SCENES, get_scene
from .executors import execute_many, worker_pool
from .plan import plan

SETTLE = 1e-12       # the transient left when the fit windows start (of its initial size)
WINDOW_S = 1.0       # each fit window: the fewest whole revolutions lasting this long
SAMPLES = 40         # output samples per revolution at least
MIN_SPEEDS = 5


def _split(scene, names):
    """(frequency-domain solver names, time-domain ones) among `names` (default: all)."""
    spec = scene.response
    freq = [s for s in scene.leaves if solvers.get_solver(s).info(scene).unbalance_response]
    known = list(dict.fromkeys(freq + list(spec.time_solvers)))
    for n in names:
        if n not in known:
            raise BadInput(f"--solver {n}: no unbalance response in scene {scene.name} "
                           f"(choose: {', '.join(known)})")
    pick = names or known
    return [s for s in freq if s in pick], [s for s in spec.time_solvers if s in pick]


def _horizon(spec, params, spin):
    """(t_end, output_dt, fit windows): whole revolutions, the transient decayed to SETTLE
    (by the slowest free decay rate at this spin) before the last two windows."""
    rev = 2 * math.pi / abs(spin)
    per_window = math.ceil(WINDOW_S / rev)
    window = per_window * rev
    settle = -math.log(SETTLE) / spec.decay(params, spin)
    n = math.ceil(settle / window) + 2
    t_end = n * window
    return t_end, rev / SAMPLES, [((n - 2) * window, (n - 1) * window),
                                  ((n - 1) * window, t_end)]


def time_runs(spec, over: dict, extra: dict, solver: str):
    """The time solver's run of `spec.time_scene` at `over` (its accurate settings) and its
    rerun at the settings of its own error estimate: (params, runs, factor, how), the runs
    stopping at the first that is not ok; factor·|y − y_tight| is the run's error."""
    pl = plan(spec.time_scene, over, [solver])
    tight, how = pl.tighter()
    (s,) = pl.solvers
    runs = []
    for p_ in (pl, tight):
        if not p_.solvers:
            break
        runs.append(solvers.simulate(p_.scene, s, {**p_.params, **extra},
                                     p_.settings[s.name], t_out=p_.t_out))
        if runs[-1].status != "ok":
            break
    return pl.params, runs, *how[s.name]


def _time_point(scene, spec, params, solver, spin) -> dict:
    """One time solver at one spin: run to steady state at its accurate settings and again at
    its tighter ones (its own error), fit the last two windows at 1×. Error bar: the change
    between the two windows (what is left of the transient) plus the solver's own error."""
    t_end, dt_out, windows = _horizon(spec, params, spin)
    over, extra = spec.time_params(params, spin, t_end, dt_out)
    p_, runs, factor, tighter = time_runs(spec, over, extra, solver)
    out = {"speed_rad_s": spin, "t_end_s": t_end}
    bad = next((tr for tr in runs if tr.status != "ok"), None)
    if bad is not None:
        return {**out, "status": bad.status, "reason": bad.reason}
    fits = [[resp.synchronous_fit(tr.t, *spec.observe(p_, tr), *w) for w in windows]
            for tr in runs]
    out["settings"], wall = runs[0].settings, sum(tr.wall_s for tr in runs)
    (a1, _), (a, spin_meas) = fits[0]
    change = abs(a - a1)
    own = factor * abs(a - fits[1][1][0]) if len(fits) > 1 else 0.0
    return {**out, "status": "ok", "spin_rad_s": spin_meas, "re": a.real, "im": a.imag,
            "window_change": change, "solver_error": own, "error": change + own,
            "error_by": tighter, "wall_s": wall}


def time_point(scene_name: str, params: dict, solver: str, spin: float) -> dict:
    """`_time_point` in a worker (a scene travels by name)."""
    scene = get_scene(scene_name)
    return _time_point(scene, scene.response, params, solver, spin)


def _time_points(scene, params, timed, spins, log) -> dict:
    """Every time solver at every speed, the points spread over the study's workers (each
    point is independent: its own run to steady state and its tighter rerun); a point whose
    worker failed is an `error` row, never dropped."""
    calls = {(name, i): (time_point, (scene.name, params, name, float(w)))
             for name in timed for i, w in enumerate(spins)}
    rows = {}
    log(f"{scene.name}: {', '.join(timed)} at {len(spins)} speeds in the time domain …")
    with progress.task(f"response {', '.join(timed)} (time)", len(calls), "speeds") as bar, \
            worker_pool(in_process_if_unguarded=True) as ex:
        for o in execute_many(calls, ex):
            name, i = o.key
            rows[o.key] = o.value if o.error is None else {
                "speed_rad_s": float(spins[i]), "status": "error",
                "reason": f"{type(o.error).__name__}: {o.error}".splitlines()[0]}
            bar.advance()
    return {name: [rows[(name, i)] for i in range(len(spins))] for name in timed}


def _frequency(scene, name, params, spins) -> dict:
    fn = solvers.get_solver(name).info(scene).unbalance_response
    t0 = time.perf_counter()
    a, err = fn(params, np.asarray(spins, float))
    return {"re": np.real(a).tolist(), "im": np.imag(a).tolist(),
            "error": np.asarray(err, float).tolist(), "wall_s": time.perf_counter() - t0}


def _complex(d, i=None):
    return complex(d["re"], d["im"]) if i is None else complex(d["re"][i], d["im"][i])


def _modal_zeta(scene, name, params, spin):
    """The forward whirl's damping ratio from the solver's own modes at `spin` (None where it
    has none)."""
    m = solvers.modes(scene, solvers.get_solver(name), {**params, "spin": spin})
    if m.status != "ok" or m.damping is None or not m.whirl or "forward" not in m.whirl:
        return None
    return float(m.damping[list(m.whirl).index("forward")])


def run_response(scene_name: str, solver_names=None, overrides: dict | None = None,
                 n_speeds: int = 24, log=None) -> ResponseResult:
    scene = get_scene(scene_name)
    spec = scene.response
    if spec is None:
        raise BadInput(f"scene {scene_name!r} has no unbalance response (scenes with one: "
                       f"{', '.join(n for n, s in SCENES.items() if s.response)})")
    if n_speeds < MIN_SPEEDS:
        raise BadInput(f"--speeds: at least {MIN_SPEEDS} speeds, got {n_speeds}")
    freq, timed = _split(scene, list(solver_names or []))
    params = plan(scene, {**spec.set, **(overrides or {})}).params
    critical, zeta = spec.critical(params)
    if not (math.isfinite(critical) and critical > 0):
        raise BadInput("no first critical speed: the rotor has no positive stiffness")
    if timed and zeta <= 0:
        raise BadInput("the time domain needs external damping > 0 (no steady state without "
                       "it): --set c_ext=…")
    if not params.get("eccentricity"):
        raise BadInput("eccentricity 0: no unbalance, no response (--set eccentricity=…)")
    log = log or (lambda *a: None)
    spins = resp.speeds(critical, zeta, n_speeds)
    data = {"scene": scene.name, "params": params, "speeds_rad_s": spins.tolist(),
            "critical_rad_s": critical, "zeta_synchronous": zeta,
            "amplitude": spec.amplitude, "drive": spec.drive, "high_spot": spec.high_spot,
            "frequency": {}, "time": {}, "verdicts": [], "peaks": {}}
    for name in freq:
        log(f"{scene.name}: {name} frequency response at {len(spins)} speeds …")
        data["frequency"][name] = _frequency(scene, name, params, spins)
    if timed:
        data["time"] = _time_points(scene, params, timed, spins, log)
    _judge(scene, data, params, freq, timed)
    _peaks(scene, data, params, freq, timed)
    return ResponseResult(data)


def _judge(scene, data, params, freq, timed):
    """Frequency vs frequency at the planned speeds; every frequency solver against every
    time run at the spin that run measured. A run's steady spin is not quite the one it
    started at: the whirl takes angular momentum (∝ e²: 2.9e-7 rad/s at e = 1e-6 m near the
    critical, which moved |a| by 1.3e-7 relative, 100× the solvers' errors) and a fixed step
    drifts (Exudyn RK67 at 82 rad/s: 2.7e-7 rad/s). Time runs are not judged against each
    other: their spins differ."""
    spins = data["speeds_rad_s"]
    for i, w in enumerate(spins):
        for j, a in enumerate(freq):
            for b in freq[j + 1:]:
                fa, fb = data["frequency"][a], data["frequency"][b]
                data["verdicts"].append({"speed_rad_s": w, "a": a, "b": b, "kind": "frequency",
                                         **resp.judge(_complex(fa, i), fa["error"][i],
                                                      _complex(fb, i), fb["error"][i])})
    for name in timed:
        ok = [r for r in data["time"][name] if r["status"] == "ok"]
        at = [r["spin_rad_s"] for r in ok]
        for f in freq:
            if not ok:
                break
            fa = _frequency(scene, f, params, at)
            for k, r in enumerate(ok):
                data["verdicts"].append({"speed_rad_s": r["speed_rad_s"], "a": f,
                                         "b": time_label(name), "kind": "frequency-time",
                                         "spin_rad_s": r["spin_rad_s"],
                                         **resp.judge(_complex(fa, k), fa["error"][k],
                                                      _complex(r), r["error"])})
        for r in data["time"][name]:
            if r["status"] != "ok":
                data["verdicts"].append({"speed_rad_s": r["speed_rad_s"],
                                         "a": time_label(name), "b": None, "kind": "time",
                                         "verdict": Verdict.INCOMPLETE,
                                         "why": f"{r['status']}: {r.get('reason')}"})


def _peaks(scene, data, params, freq, timed):
    """Per curve: peak speed and amplitude, half-power band, Q, ζ ≈ Δω/(2ω_c) — and the
    modal ζ of the forward whirl at the peak speed from each frequency solver's own modes.
    A frequency solver's peak is located on its own response (any speed), a time-domain
    curve's on a spline through its samples."""
    spins = np.array(data["speeds_rad_s"])
    curves = {n: np.array(data["frequency"][n]["re"]) + 1j * np.array(data["frequency"][n]["im"])
              for n in freq}
    for n in timed:
        ok = [r for r in data["time"][n] if r["status"] == "ok"]
        if len(ok) == len(spins):
            curves[time_label(n)] = np.array([_complex(r) for r in ok])
    for n, a in curves.items():
        if n in freq:
            fn = solvers.get_solver(n).info(scene).unbalance_response
            pk = resp.peak_on_model(lambda x, fn=fn: fn(params, x)[0], spins, a)
        else:
            pk = resp.peak(spins, a)
        if pk is not None and n in freq:
            pk["zeta_modal_forward"] = _modal_zeta(scene, n, params, pk["peak_rad_s"])
        data["peaks"][n] = pk
