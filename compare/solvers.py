"""The solvers — what each one is — and the adapter that runs a leaf and turns what it returns
into a `Trajectory` or `Modes`. Which leaf serves which scene is the scene's `leaves` (the
scene is the single source); this module names no scene.

Leaves follow `compare/contract.py`. The adapter adds what every solver needs the same way:
settings resolution (`--dt`, `--rtol`, `--integrator`) checked for every solver before any
runs, a separate compile/warm-up call for compiled leaves, wall time, package versions, the
contract check of the result, one energy-divergence rule, and crash capture (a failing solver
is recorded as `error` and never hides the others).
"""
from __future__ import annotations

import functools
import importlib.metadata
import signal
import sys
import threading
import time
import traceback
from contextlib import contextmanager
from dataclasses import dataclass, field
from types import ModuleType

import numpy as np

from .analysis.step_errors import band, shrinks
from .analysis.trajectory import Modes, Trajectory
from .contract import LeafModes, LeafResult, rounds_with
from .errors import BadInput
from .leafinfo import LeafInfo, leaf_info
from .scenes import PLUGIN_SOLVERS, SCENES, Scene, get_scene
from .scenes.base import SpeedRegime


@dataclass(frozen=True)
class Solver:
    name: str
    doc: str
    engine: str             # the package whose version matters
    compiled: bool = False  # numba leaf: time a warm-up call separately as compile time
    preset: dict = field(default_factory=dict)   # settings that make this solver a variant

    def leaf(self, scene: Scene | str) -> ModuleType:
        return self.info(scene).module

    def info(self, scene: Scene | str) -> LeafInfo:
        """The typed view of this solver's leaf for `scene` (built once per leaf module)."""
        sc = get_scene(scene) if isinstance(scene, str) else scene
        return leaf_info(sc.leaves[self.name])

    @property
    def leaves(self) -> dict:
        """scene name -> leaf module, gathered from the scenes."""
        return {sc.name: sc.leaves[self.name] for sc in SCENES.values() if self.name in sc.leaves}


REGISTRY = {s.name: s for s in (
    Solver("euler-vector", "the paper's axial+transverse Euler-vector formulation with the "
           "Zhilin tensor (seed 000); numba; dop853/dopri5/rk23 adaptive, rk4/midpoint/euler fixed",
           "numba", compiled=True),
    Solver("quaternion", "unit quaternion formulations: the rotor's body-frame Euler equations "
           "(cf. seed 001); the bearing rotor in the paper's second-order fixed-frame form; numba",
           "numba", compiled=True),
    Solver("closed-form", "analytic frequencies (whirl: I_t w² ∓ I_p Ω w − k_eff = 0)", "numpy"),
    Solver("lagrange-partial", "the press paper's method (Lagrange equations with velocity "
           "analogues from 'partial systems' by central differences; linear-acceleration "
           "(Wilson) or RK integration), and the same generalised to the benchmark loops",
           "numba", compiled=True),
    Solver("lagrange-exact", "the same Lagrange equations with analytic derivatives", "numba",
           compiled=True),
    Solver("thread-spool", "the paper's spring–mass thread (seed 004) in the rotating frame: "
           "velocity turn at release, stored thread outside J; implicit midpoint or RK4",
           "numba", compiled=True, preset={"variant": "paper"}),
    Solver("thread-spool-conservative", "thread-spool with the angular-momentum-conserving "
           "release law the engines use (stored thread at L_c in the hub inertia)", "numba",
           compiled=True, preset={"variant": "conservative"}),
    Solver("mstmm", "transfer matrix method for multibody systems (seed 002): element transfer "
           "matrices, tree assembly, root search on the characteristic function", "numba",
           compiled=True),
    Solver("fem", "Hermite beam finite elements with centrifugal stiffening, gyroscopic terms "
           "and lumped rigid bodies (independent check of mstmm)", "scipy"),
    Solver("meijaard", "bicycle: Meijaard et al. 2007's linear equations (App. A)", "numpy"),
    Solver("exudyn", "Exudyn 1.13 reference model", "exudyn"),
    Solver("mujoco", "MuJoCo 4.0 reference model", "mujoco"),
)}
for _s in PLUGIN_SOLVERS:             # solvers that plug-in packages add (compare.scenes)
    if _s["name"] in REGISTRY:
        print(f"xval: warning: plug-in solver {_s['name']!r} left out: the name is taken",
              file=sys.stderr)
    else:
        REGISTRY[_s["name"]] = Solver(**_s)


def get_solver(name: str) -> Solver:
    try:
        return REGISTRY[name]
    except KeyError:
        raise BadInput(f"unknown solver {name!r} (known: {', '.join(REGISTRY)})") from None


def solvers_for(scene_name: str) -> list[Solver]:
    return [REGISTRY[n] for n in get_scene(scene_name).leaves]


def pick(scene: Scene, names: list[str] | None) -> list[Solver]:
    """Solvers named on the command line (all that serve the scene when none are named)."""
    if not names:
        return [REGISTRY[n] for n in scene.leaves]
    chosen = [get_solver(n) for n in names]
    for s in chosen:
        if s.name not in scene.leaves:
            raise BadInput(f"solver {s.name!r} does not support scene {scene.name!r} "
                           f"(it serves: {', '.join(s.leaves)})")
    return chosen


def versions(solver):
    return dict(_versions(solver.engine))


@functools.cache
def _versions(engine):
    """Package versions behind a run (reading the metadata costs ~10 ms a package: once)."""
    out = {}
    for pkg in ("numpy", "scipy", engine):
        try:
            out[pkg] = importlib.metadata.version(pkg)
        except importlib.metadata.PackageNotFoundError:
            pass
    return out


def settings_for(solver: Solver, scene_name: Scene | str, dt: float | None = None,
                 rtol: float | None = None, integrator: str | None = None,
                 extra: dict | None = None, t_out: np.ndarray | None = None) -> dict:
    """The settings one solver runs a scene with — its leaf's defaults, its preset, the knobs —
    checked by the leaf (`check_settings(settings, t_out)` where it has one, else the shared
    merge) before anything runs, and returned as checked (the leaf does not check them again):
    bad settings raise BadInput naming the solver."""
    info = solver.info(scene_name)
    try:
        return info.check(info.resolve(dt, rtol, integrator, {**solver.preset, **(extra or {})}),
                          t_out)
    except ValueError as e:
        raise BadInput(f"{solver.name}: {str(e).splitlines()[0]}") from None


def check_settings(leaf: ModuleType, settings: dict, t_out: np.ndarray | None) -> dict:
    """The leaf's own check where it has one, else the shared merge (`LeafInfo.check`)."""
    return leaf_info(leaf.__name__).check(settings, t_out)


def resolve_settings(leaf: ModuleType, dt=None, rtol=None, integrator=None, extra=None):
    """The leaf's accurate defaults with the user's knobs applied (`LeafInfo.resolve`)."""
    return leaf_info(leaf.__name__).resolve(dt, rtol, integrator, extra)


def _first_bad_time(t, channels):
    bad = np.zeros(len(t), bool)
    for v in channels.values():
        bad |= ~np.isfinite(v)
    return float(t[np.argmax(bad)]) if bad.any() else None


def energy_scale(scene, largest):
    """The energy an energy balance weighs against: the largest |value| of the balance and of
    the scene's `energy_scale_channels` (`largest`: channel -> its largest |value|, a number or
    one per run)."""
    names = (scene.energy_channel, *scene.energy_scale_channels)
    return np.max([np.asarray(largest[c], float) for c in names], axis=0)


def energy_limit(scene, largest):
    """The drift the energy rule allows: `scene.energy_bound` × the energy scale."""
    return scene.energy_bound * energy_scale(scene, largest)


def _energy_jump(t, channels, scene):
    """The one energy-divergence rule: first time the energy balance leaves E(0) by more than
    `scene.energy_bound` of the energy scale (the largest |value| of the energy balance and of
    the scene's `energy_scale_channels`)."""
    e = channels[scene.energy_channel]
    scale = energy_scale(scene, {c: np.max(np.abs(channels[c]))
                                 for c in (scene.energy_channel, *scene.energy_scale_channels)})
    limit = scene.energy_bound * scale
    drift = np.abs(e - e[0])
    bad = np.nonzero(drift > limit)[0]
    if not len(bad):
        return None, None
    return float(t[bad[0]]), (f"unstable or too coarse: energy balance drifted by "
                              f"{np.max(drift):.3g} J ({np.max(drift) / scale:.0%} of the energy "
                              f"scale {scale:.3g} J)")


class _Timeout(BaseException):
    """Raised by the wall-clock alarm inside a leaf (a BaseException, so that no leaf's
    exception handling and not the crash capture below can swallow it)."""


@contextmanager
def _time_limit(seconds):
    """Stop the enclosed call after `seconds` of wall time with _Timeout. Needs SIGALRM and the
    main thread (true for the CLI and the process-pool workers; Dask runs tasks in threads, where
    no limit is applied). The alarm is seen when control is back in Python: engine leaves return
    there at every output step, the compiled kernels only at the end of the run. An engine that
    turns the exception raised in its user function into its own failure (Exudyn does) still
    ends `timeout`: the alarm's firing is remembered and raised again on the way out."""
    if not seconds or threading.current_thread() is not threading.main_thread() \
            or not hasattr(signal, "SIGALRM"):
        yield
        return
    fired = []

    def on_alarm(signum, frame):
        fired.append(True)
        raise _Timeout()
    old = signal.signal(signal.SIGALRM, on_alarm)
    signal.setitimer(signal.ITIMER_REAL, float(seconds))
    try:
        try:
            yield
        except Exception:
            if fired:                  # the engine wrapped the alarm into its own error
                raise _Timeout() from None
            raise
        if fired:                      # swallowed inside the engine: the limit still counts
            raise _Timeout()
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, old)


def tighter_settings(info: LeafInfo, settings: dict) -> tuple[dict | None, float, str]:
    """Settings for a solver's own error estimate and the factor that turns |y − y_tight| into
    the error of the run: a tolerance 100× tighter (factor 10/9: the tight run keeps up to a
    tenth of the run's error), else half the step (factor 2: an order-p method's error is
    2^p/(2^p − 1) ≤ 2 times that difference). None where neither knob exists (a
    stability-bound explicit step). See `compare.leafinfo.Fixed` / `Adaptive`."""
    return info.tighter(settings)


def simulate(scene: Scene, solver: Solver, params: dict, settings: dict,
             timeout_s: float | None = None, estimate_error: bool = False,
             warm_up: bool = True, t_out: np.ndarray | None = None) -> Trajectory:
    """Run one solver on one scene; always returns a Trajectory (status tells what happened).
    `timeout_s` bounds the wall time of the run (compile included): status "timeout". Settings
    were checked before (`settings_for`); anything a leaf raises now is recorded as `error`.
    `estimate_error`: the run's own numerical error per channel (`Trajectory.errors`), which the
    verdicts weigh: factor·|Δ| against a tighter rerun, plus what that rerun cannot see
    (`_unseen_error`), or coarser members where the leaf declares them (`_coarser_error`),
    plus each discretisation knob's own (`_knob_errors`). `warm_up=False`
    skips the separate compile call (a batch of points warms up once; the tighter rerun never
    needs one). `t_out`: the output grid where the caller has built it (a Plan)."""
    tr = _simulate(scene, solver, params, settings, timeout_s, warm_up, t_out)
    if estimate_error and tr.status == "ok":
        if settings.get("dt") == "auto" and isinstance(tr.settings.get("dt"), (int, float)):
            settings = {**settings, "dt": tr.settings["dt"]}   # the step "auto" chose
        tight, at_tight = None, None
        if not _coarser_error(scene, solver, params, settings, tr, timeout_s):
            tight, factor, how = tighter_settings(solver.info(scene), settings)
            tr.stats["error_estimate_by"] = how
        if tight is not None:
            ref = _simulate(scene, solver, params, tight, timeout_s, False, tr.t)
            _cost(tr, ref)
            unseen = None
            if ref.status != "ok":
                tr.stats["error_estimate_by"] = ""
                _no_estimate(tr, f"{how}: {ref.status} ({ref.reason})")
            else:
                unseen = _unseen_error(scene, solver, params, settings, tr, ref, tight,
                                       timeout_s)
                at_tight = (ref, tight, unseen) if "rtol" in how else None
            if unseen is not None:
                seen = (_halving_error(scene, solver, params, tr, ref, tight, unseen, timeout_s)
                        if "rtol" not in how else
                        {c: factor * np.abs(tr.channels[c] - ref.channels[c])
                         for c in scene.channels})
                tr.errors = {c: seen[c] + unseen[c] for c in scene.channels}
        if tr.errors or tight is None:   # the step's own estimate held, or there is none
            _knob_errors(scene, solver, params, settings, tr, timeout_s, at_tight)
    return tr


def _no_estimate(tr, why: str):
    """The run's error estimate failed (a rerun it needs stopped): no error bar, and the run
    says why (`stats["error_estimate_failed"]`): its verdicts beyond the allowance are then
    `incomplete`, not `disagree` (`analysis.metrics.deviation`)."""
    tr.errors = {}
    tr.stats["error_estimate_failed"] = why
    tr.stats["error_estimate_by"] = ", ".join(filter(None, (tr.stats.get("error_estimate_by"),
                                                           why)))


def _cost(tr, *runs):
    """Count the error estimate's runs and their seconds in the run's stats (`xval bench`: the
    cost of an error bar)."""
    tr.stats["error_estimate_s"] = tr.stats.get("error_estimate_s", 0.0) + sum(
        r.wall_s for r in runs)
    tr.stats["error_estimate_runs"] = tr.stats.get("error_estimate_runs", 0) + len(runs)


# Richardson's extrapolation is exact only asymptotically: its estimate × this margin (the
# halving's factor 2 is 1.5 × its order-2 Richardson factor 4/3)
RICHARDSON_SAFETY = 1.5


def _coarser_error(scene, solver, params, settings, tr, timeout_s) -> bool:
    """A fixed step's error from coarser members where its leaf declares them (`COARSER_DT`:
    steps q·dt, 1 < q, still inside the explicit stability bound), the run itself the finest
    member — a fraction of the run's cost where halving costs twice it. Per channel the larger
    of Richardson's |y_q − y|/(q^p − 1) × RICHARDSON_SAFETY at the coarsest q (an order-p
    method, asymptotic) and the band's 2 × running maximum of the members' spread (a mode the
    step does not resolve in phase: sail-deploy's thread spring, whose runs at any step each
    sit at their own phase of it, as in `_halving_error`; three members, since two can agree
    by aliasing), plus the round-off floor. False — the caller halves the step — where the
    leaf declares no member or one did not complete (a step past the stability limit)."""
    info = solver.info(scene)
    members = info.coarser_members(settings)
    if not members:
        return False
    runs = [_simulate(scene, solver, params, s, timeout_s, False, tr.t) for s in members]
    _cost(tr, *runs)
    if any(r.status != "ok" for r in runs):
        return False
    q, p = members[-1]["dt"] / settings["dt"], info.order(settings.get("integrator")) or 1
    unseen = _unseen_error(scene, solver, params, settings, tr, runs[-1], members[-1],
                           timeout_s)
    tr.errors = {}
    if unseen is None:
        return True
    for c in scene.channels:
        y = tr.channels[c]
        rich = RICHARDSON_SAFETY * np.abs(runs[-1].channels[c] - y) / (q ** p - 1)
        wander = band(y, *(r.channels[c] for r in runs))
        tr.errors[c] = np.maximum(rich, wander) + unseen[c]
    tr.stats["error_estimate_by"] = "dt " + ", ".join(f"{s['dt']:g}" for s in members) + \
        " (coarser: Richardson and the members' band)"
    return True


def _knob_errors(scene, solver, params, settings, tr, timeout_s, at_tight=None):
    """Add each discretisation knob's error to the run's estimate — a knob the estimate does not
    vary would hide its error (lagrange-partial's 0.1° central differences: 14–1500 × the
    step's error on the press). Each knob alone one step tighter and one coarser (a factor 2
    each way, `Knob.tighter`): the change d1 = |y − y_tight| and its ratio r = max d1 /
    max |y_coarse − y| per channel give the geometric tail d1/(1 − r) of the changes still to
    come, r taken no smaller than the declared order's 2^-|p|, plus one more change r·d1 for
    the tail's own uncertainty (p = 2: 1.58 · d1; the tail alone, 4/3 · d1, met the press's
    partial to 0.2–2 % against lagrange-exact, leaving its verdicts at Δ/bound 0.996–0.998),
    and no less than Richardson's coarse change |y_coarse − y|/(2^|p| − 1): a change that fell
    by more than the order allows met a floor under the tighter run, not the limit
    (lagrange-partial's Δβ on andrews-squeezer, `xval calibrate --seed 5150` set 6: β moved
    1.43e-8 rad from 2Δβ to Δβ, then 5e-10 to Δβ/2, whose central differences round as δ/Δβ²;
    the run was 5.7e-9 off the engines' far tighter runs and its bar said 3.9e-9); in the
    asymptotic range it is the tail's first term, no more;
    changes that do not shrink (r ≥ 1, or the coarse run failed): 2 × the running maximum of
    the three runs' spread.
    An error-controlled run's knobs are varied about its tight rerun (`at_tight`: that run, its
    settings and what it cannot see of itself): a knob moves the steps, and at the run's own
    tolerance the tolerance's error, which the tight rerun already bounds, moved with them as
    scatter (Exudyn's cap on the step on bearing-rotor, `xval calibrate --seed 2026` set 0: its
    halving and doubling each moved spin_rate by ~2.3e-7 rad/s, the run's own tolerance error
    at one output time, r = 0.997, and the tail said 7.7e-5); about the tight rerun that
    scatter is 100× smaller, the knob's own error (an interpolant's, not the tolerance's) as
    large. Changes that shrink by less than half (r ≥ 1/2, where a knob of order ≥ 1 shrinks
    them by 2^-p) and lie within the tight rerun's own scatter (its tolerance's, measured at
    rtol/2 and rtol/4, plus its rounding) are that scatter, no tail of a convergence: the band
    too — the tail 1/(1 − r) of two changes equal by chance is unbounded (the same cap,
    `--seed 7373` set 13: both changes 7.87e-10 J of kinetic energy, r = 0.9995, within a
    scatter of 1.55e-9, and the tail said 1.7e-6 against a true error of 1.0e-8; `--seed 2468`
    set 0: motor_work 1.0e-9 J each way, r = 0.97, within 3.0e-9, the tail 3.9e-8 against
    8.6e-11)."""
    centre, base, scatter = at_tight or (tr, settings, None)
    for knob, finer in solver.info(scene).knob_reruns(base):
        runs = [_simulate(scene, solver, params, s, timeout_s, False, tr.t)
                for s in (finer, knob.tighter(base, -1))]
        _cost(tr, *runs)
        half, double = runs               # tighter, coarser
        by = f"{knob.name} {knob.value(finer):g}" + \
            (f" ({knob.holds} {finer[knob.holds]:g})" if knob.holds else "")
        if half.status != "ok":          # an estimate blind to a knob is no estimate
            _no_estimate(tr, f"{by}: {half.status} ({half.reason})")
            return
        tr.stats["error_estimate_by"] += f", {by}"
        coarse_ok = double.status == "ok"
        for c in scene.channels:
            y = centre.channels[c]
            d1 = np.abs(y - half.channels[c])
            d0 = np.abs(double.channels[c] - y) if coarse_ok else None
            r = max(np.max(d1) / max(np.max(d0), 1e-300) if coarse_ok else np.inf,
                    2.0 ** -abs(knob.order))
            noise = coarse_ok and r >= 0.5 and scatter is not None and \
                max(np.max(d1), np.max(d0)) <= np.max(scatter[c])
            if r < 1 and not noise:   # the tail, no less than the coarse change at the order
                err = np.maximum(d1 * (1 / (1 - r) + r), d0 / (2.0 ** abs(knob.order) - 1))
            else:
                err = band(y, half.channels[c], *([double.channels[c]] if coarse_ok else []))
            tr.errors[c] = tr.errors.get(c, 0.0) + err


def _halving_error(scene, solver, params, tr, half, tight, unseen, timeout_s):
    """A fixed step's error per channel (over t) from the halving's changes |y − y_half|:
    - asymptotic (the change at least halves from 2·dt to dt at every output time where the
      coarse change stands out: a zero crossing of the error leaves both small): 2 |y − y_half|
      (an order-p method's error is 2^p/(2^p − 1) ≤ 2 times it);
    - shrinking by less than half (MuJoCo's press: its soft-constraint time constant is tied to
      the step, the change from 2·dt to dt to dt/2 shrinks by 0.9–1.05, from dt/2 to dt/4 by
      0.72–0.75, then 0.5; its true error was 2.3 × |y − y_half| against a factor 2): the ratio
      r measured at the run's own step, one more run at dt/4, and the geometric tail
      1/(1 − r) of the changes still to come (the ratio falls toward the asymptotic one);
    - where the scene's forces kink (`Scene.kinks`), the larger of 2 |y − y_half| and the band
      below, always: the error's size and sign jump between halvings (bearing-rotor's bump);
    - not shrinking (r ≥ 1, seen on any channel once the dt/4 run exists) while the change
      from 2·dt to dt/4 fell by less than 4 (an order-p ≥ 1 method's falls by 4^p): the runs
      are not converging but wander in a band — a mode the step does not resolve (sail-deploy's
      thread spring, ~1.2e5 rad/s: Verlet's phase error (ωh)²/24 a radian is 170 rad over 0.2 s
      at the auto step, still 0.7 rad at 1/16 of it, so every run, the reference too, sits at
      its own phase of it; the run and its half step can even agree at every output time by
      aliasing). Any two members of the band, the run and the truth included, differ by up to
      its width: 2 × the running maximum of the spread of the run and its refinements (dt,
      dt/2, dt/4). Sail-deploy's engines, 100 points: contained 0.998 (Exudyn; 0.93 at 20
      points with 2 |y − y_half|) and 1.000 (MuJoCo), median true/estimate 0.30 and 0.45.
      A change that fell by more than 4 before growing has met a noise floor under a
      converged run (Exudyn's press crank_accel, its index-3 accelerations' Newton jitter:
      0.157, 1.5e-3, 2.7e-3 from 2·dt down): 2 |y − y_half| plus the measured jitter holds it
      (`_unseen_error`).
    Costs a run at 2·dt (half the run), and the dt/4 run only where a channel is not
    asymptotic. The run keeps its members' offsets y_member − y (`Trajectory.members`: 2·dt
    and dt/2), each channel's estimator and its `scheme` (leaf, integrator, step): a run of
    the same scheme bounds their difference by them (`analysis.step_errors.pair_error`)."""
    d1 = {c: np.abs(tr.channels[c] - half.channels[c]) for c in scene.channels}
    err = {c: 2 * d1[c] for c in scene.channels}
    coarse = _simulate(scene, solver, params, {**tight, "dt": 4 * tight["dt"]}, timeout_s,
                       False, tr.t)
    _cost(tr, coarse)
    if coarse.status != "ok":          # 2·dt past a stability limit: no ratio to read
        return err
    seen = [c for c in scene.channels if np.max(d1[c]) > 10 * float(np.max(unseen[c]))]
    d0 = {c: np.abs(coarse.channels[c] - tr.channels[c]) for c in seen}
    slow = [c for c in seen if scene.kinks or not shrinks(d0[c], d1[c])]
    tr.scheme = f"{solver.info(scene).name} {tight.get('integrator')} dt {2 * tight['dt']:.17g}"
    tr.members = {c: np.stack([coarse.channels[c], half.channels[c]]) - tr.channels[c]
                  for c in scene.channels}
    tr.estimators = dict.fromkeys(scene.channels, "halving")
    if not slow:
        return err
    quarter = _simulate(scene, solver, params, {**tight, "dt": tight["dt"] / 2}, timeout_s,
                        False, tr.t)
    _cost(tr, quarter)
    tr.stats["error_estimate_by"] += (f", dt {tight['dt'] / 2:g} "
                                      + (f"(the forces' kinks: {scene.kinks})" if scene.kinks
                                         else f"(not asymptotic: {slow[0]})"))
    if quarter.status != "ok":
        return err
    for c in seen:
        d2 = float(np.max(np.abs(half.channels[c] - quarter.channels[c])))
        r = d2 / np.max(d1[c])
        if scene.kinks:
            err[c] = np.maximum(err[c], band(tr.channels[c], half.channels[c],
                                             quarter.channels[c]))
            tr.estimators[c] = "band"
        elif r >= 1 and d2 >= np.max(d0[c]) / 4:
            err[c] = band(tr.channels[c], half.channels[c], quarter.channels[c])
            tr.estimators[c] = "band"
        elif 0.5 < r < 1 and c in slow:
            err[c] = d1[c] / (1 - r)
            tr.estimators[c] = "tail"
    return err


EPS = float(np.finfo(float).eps)
# the tight run's error over its change on halving the tolerance (`_unseen_error`)
TIGHT_TAIL = 1 / (1 - 2 ** -0.5)
# a fixed step's error over its jitter probe's largest change, beyond 2·|y − y_half|: 4/3 of
# the half step's jitter and 7/3 of the run's (`_unseen_error`), rounded up
JITTER_SAFETY = 4.0


def _steps(tr: Trajectory) -> float:
    """The steps a run took: its leaf's count, else the horizon over the fixed step."""
    n = tr.stats.get("steps")
    dt = tr.settings.get("dt")
    if not n and isinstance(dt, (int, float)) and dt > 0:
        n = (tr.t[-1] - tr.t[0]) / dt
    return float(n or len(tr.t))


def rounding_scale(channel, tr, params) -> float:
    """What a channel's rounding scales with: its largest |value|, or the parameter it names
    (`Channel.rounding`) where that is larger (a loop residual's lengths)."""
    return rounds_with(channel, float(np.max(np.abs(tr.channels[channel]))), params)


def rounding_model(channel, tr, params):
    """The channel's own rounding at each output time where it declares a model of it
    (`Channel.rounding` a function), else 0."""
    model = getattr(channel, "rounding", None)
    return np.abs(model(tr.channels, params)) if callable(model) else 0.0


def _unseen_error(scene, solver, params, settings, tr, ref, tight, timeout_s) -> dict | None:
    """What the tighter rerun cannot see, per channel (a running maximum over t):
    - round-off: √(steps of both runs) × machine epsilon × the channel's scale (its largest
      |value|, or the length it is computed from: `rounding_scale`): each step rounds the
      state once, independently, so the rounding errors add like a random walk (n × eps was
      20× the quaternion rotor's whole error at rtol 1e-11: `tests/verdicts/test_coverage.py`
      measures the floor's sharpness);
    - an error-controlled rerun's own error: the step-size controller makes the solution jump
      by about its tolerance under any tiny change (rotor-spinup at 3.2 N·m: a 1e-15 change of
      the torque moves `potential` by 2.5e-9 J at rtol 1e-11, the size of the rtol-1e-13
      rerun's own error, which factor 1 took for zero). Measured by one more run at half that
      tolerance: an error-controlled method's error goes as tol^a, a = p/(p + 1) ≥ 1/2 (the
      worst case `Adaptive.error_factor` takes), so halving the tolerance removes at least
      1 − 2^-a of it and the tight run's error is at most |y_tight − y_tight/2| / (1 − 2^-½)
      = 3.41 × the change (`TIGHT_TAIL`; 1 × it left euler-vector's rotor-spinup work 1.03 ×
      past its pair's bound at a calibration set, its rtol-1e-13 run 1.4e-12 J off rtol 1e-14
      while the halving moved it 5.2e-13). Where the tolerance no longer governs (the
      controller at a formulation's rounding floor) the changes are samples of the runs'
      scatter, and one can fall far short: euler-vector at 3.19999 N·m, 5 s, eight rtol-1e-13
      runs 4 ulp of rtol apart scatter by 4.6e-9 J of work and one halving's change was up to
      6.1 × short of that run's own error; so a second run at a quarter of the tolerance, and the
      larger change counts. A fixed step's error is smooth in the step, and halving it sees
      it: no further run;
    - a fixed step's Newton jitter, where its leaf declares a probe (`JITTER_PROBE`: the tight
      run again with its Newton tolerance scaled by the first factor at which it completes,
      tightest first: the half step's Newton error against the same step converged as far as
      Newton gets). An index-3 integrator's accelerations carry the positions' Newton error
      over β·dt²: Exudyn's press crank_accel, rerun at Newton tolerances 1e-10 … 1e-13,
      scattered by 1e-17–1.3e-16 s² × its scale / dt² at six sets and four steps (2e-5: up to
      2.4e-4 rad/s²), so the halving's half-step member is the noisier one and its change can
      cancel the run's own error (`xval calibrate press-cycle --seed 90210` set 14:
      2·|y − y_half| 2.6e-4 against a true 3.7e-4). Newton's error moves in whole iterations:
      10× tighter left the iterate as it was at `--seed 31337` set 9 (1e-12 moved it by
      7e-4), and through a lock Newton may not converge below 1e-10. With the run's jitter at
      most the half step's (it goes as 1/dt²), its error is
      within 2·|y − y_half| + (4/3 + 7/3)·jitter: JITTER_SAFETY × the largest change the probe
      makes anywhere on the run (the jitter is not a running error: it is as large at the first
      output time as at the last)."""
    floor = {c: np.maximum(np.sqrt(_steps(tr) + _steps(ref)) * EPS
                           * rounding_scale(c, tr, params), rounding_model(c, tr, params))
             for c in scene.channels}
    jitter = {c: 0.0 for c in scene.channels}
    if isinstance(tight.get("rtol"), float) and tight["rtol"] != settings.get("rtol"):
        for cut in (2, 4):
            finer = {**tight, "rtol": tight["rtol"] / cut}
            if isinstance(tight.get("atol"), (int, float)):
                finer["atol"] = tight["atol"] / cut
            ref2 = _simulate(scene, solver, params, finer, timeout_s, False, tr.t)
            _cost(tr, ref2)
            if ref2.status == "ok":
                jitter = {c: np.maximum(jitter[c], TIGHT_TAIL * np.maximum.accumulate(
                    np.abs(ref.channels[c] - ref2.channels[c]))) for c in scene.channels}
    probe = solver.info(scene).jitter_probe
    if probe and all(isinstance(tight.get(k), float) for k in probe):
        for factors in zip(*probe.values()):        # the first that completes, tightest first
            scaled = {k: tight[k] * f for k, f in zip(probe, factors)}
            ref2 = _simulate(scene, solver, params, {**tight, **scaled}, timeout_s, False, tr.t)
            _cost(tr, ref2)
            if ref2.status == "ok":
                break
        by = ", ".join(f"{k} ×{f:g}" for k, f in zip(probe, factors))
        if ref2.status != "ok":         # a jitter not measured is no estimate
            _no_estimate(tr, f"Newton jitter: {ref2.status} ({ref2.reason})")
            return None
        tr.stats["error_estimate_by"] = tr.stats.get("error_estimate_by", "") + \
            f", Newton jitter ({by})"
        jitter = {c: jitter[c] + JITTER_SAFETY * np.max(np.abs(ref.channels[c]
                                                               - ref2.channels[c]))
                  for c in scene.channels}
    return {c: floor[c] + jitter[c] for c in scene.channels}


def _simulate(scene, solver, params, settings, timeout_s, warm_up=True, t_out=None):
    t_out = scene.output_grid(params) if t_out is None else t_out
    nan = {c: np.full(len(t_out), np.nan) for c in scene.channels}
    base = dict(scene=scene.name, solver=solver.name, t=t_out, versions=versions(solver),
                settings=dict(settings))
    t_start = time.perf_counter()
    try:
        leaf = solver.leaf(scene)
        stats = {}
        with _time_limit(timeout_s):
            if solver.compiled and warm_up:   # compile on a two-point grid, timed on its own
                t0 = time.perf_counter()
                leaf.simulate(params, t_out[:2], settings)
                stats["compile_s"] = time.perf_counter() - t0
            t0 = time.perf_counter()
            res = LeafResult.coerce(leaf.simulate(params, t_out, settings))
            wall = time.perf_counter() - t0
        broken = res.validate(scene.channels, len(t_out))
    except _Timeout:
        return Trajectory(channels=nan, status="timeout",
                          wall_s=time.perf_counter() - t_start,
                          reason=f"stopped at the wall-clock limit of {timeout_s:g} s", **base)
    except Exception as e:             # a crash is recorded, never propagated
        return Trajectory(channels=nan, status="error", wall_s=0.0,
                          reason=f"{type(e).__name__}: {e}".splitlines()[0],
                          stats={"traceback": traceback.format_exc(limit=4)}, **base)
    if broken:
        return Trajectory(channels=nan, status="error", wall_s=wall,
                          reason=f"leaf broke the contract: {broken}", **base)
    channels = {c: np.asarray(res.channels[c], float) for c in scene.channels}
    status, t_fail, reason = res.status, res.t_fail, res.reason
    if status == "ok":                 # silent garbage is the one forbidden outcome
        t_bad = _first_bad_time(t_out, channels)
        if t_bad is not None:
            status, t_fail, reason = "diverged", t_bad, "non-finite output behind status ok"
    if status == "ok" and scene.energy_channel:
        t_bad, why = _energy_jump(t_out, channels, scene)
        if t_bad is not None:
            status, t_fail, reason = "diverged", t_bad, why
            for v in channels.values():          # nothing after a failure is a result
                v[t_out > t_fail] = np.nan
    invariants = dict(res.invariants)
    for c in scene.invariant_channels:
        x = channels[c][np.isfinite(channels[c])]
        if len(x):
            invariants[c] = float(np.max(np.abs(x - x[0])) / max(abs(x[0]), 1e-300))
    base["settings"] = res.settings or settings
    return Trajectory(channels=channels, status=status, t_fail=t_fail, reason=reason,
                      stats={**stats, **res.stats}, wall_s=wall, invariants=invariants,
                      extra=res.extra, **base)


def regimes(scene: Scene, solver: Solver, params_list: list[dict], settings: dict):
    """The regimes of many runs in one batch call, where the leaf offers one (`regimes`) for
    the scene's SpeedRegime on one output grid: (labels, seconds per run), a label None where
    the run did not end ok by `simulate`'s rules (leaf status, finite output, the one energy
    rule: the caller runs that point alone to report why). None where no batch applies or it
    raised (the caller runs every point alone)."""
    info, reg = solver.info(scene), scene.regime
    leaf = info.module
    if not (isinstance(reg, SpeedRegime) and info.batch_regimes and params_list) or \
            len({(p["t_end"], p["output_dt"]) for p in params_list}) > 1:
        return None
    t_out = scene.output_grid(params_list[0])
    levels = np.array([reg.levels(p) for p in params_list], float)
    try:
        if solver.compiled:              # compile / load apart from the timed call
            leaf.regimes(params_list[:1], t_out[:2], settings, reg.channel, levels[:1], 0.5)
        t0 = time.perf_counter()
        res = leaf.regimes(params_list, t_out, settings, reg.channel, levels, reg.window)
        wall = time.perf_counter() - t0
    except Exception:
        return None
    if res is None:
        return None
    ok = (res["code"] == 0) & res["finite"]
    if scene.energy_channel:
        if not {scene.energy_channel, *scene.energy_scale_channels} <= set(res["max_abs"]):
            return None
        ok &= ~(res["drift"] > energy_limit(scene, res["max_abs"]))
    return ([reg.labels[r] if good else None for r, good in zip(res["regime"], ok)],
            wall / len(params_list))


def modes(scene: Scene, solver: Solver, params: dict, settings: dict | None = None) -> Modes:
    """Natural frequencies from one solver; always returns a Modes (status tells). A leaf that
    cannot linearise here raises; that is recorded as `error` with its message."""
    base = dict(scene=scene.name, solver=solver.name, versions=versions(solver))
    try:
        leaf = solver.leaf(scene)
        s = {**solver.preset, **(settings or {})}
        t0 = time.perf_counter()
        res = LeafModes.coerce(leaf.modes(params, s))
        wall = time.perf_counter() - t0
        broken = res.validate()
    except Exception as e:
        return Modes(frequencies_hz=np.array([]), labels=[], status="error",
                     reason=f"{type(e).__name__}: {e}".splitlines()[0], **base)
    if broken:
        return Modes(frequencies_hz=np.array([]), labels=[], status="error",
                     reason=f"leaf broke the contract: {broken}", **base)
    return Modes(frequencies_hz=np.asarray(res.frequencies_hz, float), labels=list(res.labels),
                 damping=None if res.damping is None else np.asarray(res.damping, float),
                 shapes=res.shapes, whirl=res.whirl, notes=list(res.notes),
                 extra=res.extra, settings=res.settings or s, wall_s=wall, **base)
