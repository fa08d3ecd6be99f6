"""The solver registry — the only place that knows which leaf model serves which scene — and
the adapter that turns a leaf's plain dict into a `Trajectory` or `Modes`.

Leaves follow `reference_models/README.md`. The adapter adds what every solver needs the same
way: settings resolution (`--dt`, `--rtol`, `--integrator`), a separate compile/warm-up call for
compiled leaves, wall time, package versions, the check that no non-finite value hides behind
status "ok", and crash capture (a failing solver never hides the others).
"""
from contextlib import contextmanager
from dataclasses import dataclass, field
import importlib
import importlib.metadata
import signal
import threading
import time
import traceback

import numpy as np

from .errors import BadInput
from .trajectory import Modes, Trajectory


@dataclass(frozen=True)
class Solver:
    name: str
    doc: str
    leaves: dict            # scene name -> leaf module
    engine: str             # the package whose version matters
    compiled: bool = False  # numba leaf: time a warm-up call separately as compile time
    preset: dict = field(default_factory=dict)   # settings that make this solver a variant

    def leaf(self, scene):
        return importlib.import_module(self.leaves[scene])


REGISTRY = {s.name: s for s in (
    Solver("euler-vector", "the paper's axial+transverse Euler-vector formulation with the "
           "Zhilin tensor (seed 000); numba; dop853/dopri5/rk23 adaptive, rk4/midpoint/euler fixed",
           {"rotor-spinup": "custom_models.rotor_euler",
            "rotor-whirl": "custom_models.rotor_whirl"}, "numba", compiled=True),
    Solver("quaternion", "independent formulation: unit quaternion + body-frame Euler equations "
           "(cf. seed 001); numba; same integrators",
           {"rotor-spinup": "custom_models.rotor_quaternion"}, "numba", compiled=True),
    Solver("closed-form", "analytic whirl frequencies I_t w² ∓ I_p Ω w − k_eff = 0",
           {"rotor-whirl": "custom_models.rotor_closed_form"}, "numpy"),
    Solver("lagrange-partial", "the paper's method (seed 003): Lagrange equations with velocity "
           "analogues from 'partial systems' by central differences; linear-acceleration "
           "(Wilson) or RK integration", {"press": "custom_models.press_partial",
                                          "press-cycle": "custom_models.press_partial"},
           "numba", compiled=True),
    Solver("lagrange-exact", "the same Lagrange equations with analytic derivatives",
           {"press": "custom_models.press_exact", "press-cycle": "custom_models.press_exact"},
           "numba", compiled=True),
    Solver("thread-spool", "the paper's spring–mass thread (seed 004) in the rotating frame: "
           "velocity turn at release, stored thread outside J; implicit midpoint or RK4",
           {"sail-deploy": "custom_models.thread_spool"}, "numba", compiled=True,
           preset={"variant": "paper"}),
    Solver("thread-spool-conservative", "thread-spool with the angular-momentum-conserving "
           "release law the engines use (stored thread at L_c in the hub inertia)",
           {"sail-deploy": "custom_models.thread_spool"}, "numba", compiled=True,
           preset={"variant": "conservative"}),
    Solver("exudyn", "Exudyn 1.13 reference model",
           {"rotor-spinup": "reference_models.exudyn.rotor",
            "rotor-whirl": "reference_models.exudyn.rotor",
            "press": "reference_models.exudyn.press",
            "press-cycle": "reference_models.exudyn.press",
            "sail-deploy": "reference_models.exudyn.sail"}, "exudyn"),
    Solver("mujoco", "MuJoCo 4.0 reference model",
           {"rotor-spinup": "reference_models.mujoco.rotor",
            "rotor-whirl": "reference_models.mujoco.rotor",
            "press": "reference_models.mujoco.press",
            "press-cycle": "reference_models.mujoco.press",
            "sail-deploy": "reference_models.mujoco.sail"}, "mujoco"),
)}


def get_solver(name):
    try:
        return REGISTRY[name]
    except KeyError:
        raise BadInput(f"unknown solver {name!r} (known: {', '.join(REGISTRY)})") from None


def solvers_for(scene_name):
    return [s for s in REGISTRY.values() if scene_name in s.leaves]


def pick(scene, names):
    """Solvers named on the command line (all that serve the scene when none are named)."""
    if not names:
        return solvers_for(scene.name)
    chosen = [get_solver(n) for n in names]
    for s in chosen:
        if scene.name not in s.leaves:
            raise BadInput(f"solver {s.name!r} does not support scene {scene.name!r} "
                           f"(it serves: {', '.join(s.leaves)})")
    return chosen


def versions(solver):
    out = {}
    for pkg in ("numpy", "scipy", solver.engine):
        try:
            out[pkg] = importlib.metadata.version(pkg)
        except importlib.metadata.PackageNotFoundError:
            pass
    return out


def settings_for(solver, scene_name, dt=None, rtol=None, integrator=None, extra=None):
    """The settings one solver runs a scene with: its leaf's defaults, its preset, the knobs."""
    return resolve_settings(solver.leaf(scene_name), dt, rtol, integrator,
                            {**solver.preset, **(extra or {})})


def resolve_settings(leaf, dt=None, rtol=None, integrator=None, extra=None):
    """The leaf's accurate defaults with the user's knobs applied.

    `dt` moves an adaptive default to the leaf's fixed-step method, `rtol` moves a fixed-step
    default to its adaptive one; a leaf without the requested kind keeps its own (and the
    settings actually used say so)."""
    s = dict(leaf.DEFAULT_SETTINGS)
    adaptive = tuple(getattr(leaf, "ADAPTIVE", ()))
    fixed = [i for i in leaf.INTEGRATORS if i not in adaptive]
    if integrator is not None:
        if integrator not in leaf.INTEGRATORS:
            raise BadInput(f"integrator: {integrator!r} is not offered by this solver "
                           f"(choose: {', '.join(leaf.INTEGRATORS)})")
        s["integrator"] = integrator
    if dt is not None:
        s["dt"] = dt
        if s.get("integrator") in adaptive and integrator is None and fixed:
            s["integrator"] = "rk4" if "rk4" in fixed else fixed[0]
    if rtol is not None:
        if adaptive:
            s["rtol"] = rtol
            if s.get("integrator") not in adaptive and integrator is None:
                s["integrator"] = adaptive[0]
        # else: no error-controlled integrator; its fixed step stays (the CLI says so)
    s.update(extra or {})
    return s


def _first_bad_time(t, channels):
    bad = np.zeros(len(t), bool)
    for v in channels.values():
        bad |= ~np.isfinite(v)
    return float(t[np.argmax(bad)]) if bad.any() else None


def _energy_jump(t, channels, scene):
    """First time the energy balance leaves E(0) by more than `scene.energy_bound` of the
    energy scale (the largest |value| of the energy balance and of its kinetic, potential and
    work terms where the scene has them)."""
    e = channels[scene.energy_channel]
    scale = max(float(np.max(np.abs(channels[c]))) for c in
                (scene.energy_channel, "kinetic", "potential", "work") if c in channels)
    drift = np.abs(e - e[0])
    bad = np.nonzero(drift > scene.energy_bound * scale)[0]
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
    there at every output step, the compiled kernels only at the end of the run."""
    if not seconds or threading.current_thread() is not threading.main_thread() \
            or not hasattr(signal, "SIGALRM"):
        yield
        return

    def on_alarm(signum, frame):
        raise _Timeout()
    old = signal.signal(signal.SIGALRM, on_alarm)
    signal.setitimer(signal.ITIMER_REAL, float(seconds))
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, old)


def simulate(scene, solver, params, settings, timeout_s=None):
    """Run one solver on one scene; always returns a Trajectory (status tells what happened).
    `timeout_s` bounds the wall time of the run (compile included): status "timeout"."""
    t_out = scene.output_grid(params)
    nan = {c: np.full(len(t_out), np.nan) for c in scene.channels}
    base = dict(scene=scene.name, solver=solver.name, t=t_out, versions=versions(solver),
                settings=dict(settings))
    t_start = time.perf_counter()
    try:
        leaf = solver.leaf(scene.name)
        stats = {}
        with _time_limit(timeout_s):
            if solver.compiled:        # compile once on a two-point grid, timed on its own
                t0 = time.perf_counter()
                leaf.simulate(params, t_out[:2], settings)
                stats["compile_s"] = time.perf_counter() - t0
            t0 = time.perf_counter()
            res = leaf.simulate(params, t_out, settings)
            wall = time.perf_counter() - t0
    except ValueError as e:            # the leaf contract: bad settings
        raise BadInput(f"{solver.name}: {e}") from None
    except _Timeout:
        return Trajectory(channels=nan, status="timeout",
                          wall_s=time.perf_counter() - t_start,
                          reason=f"stopped at the wall-clock limit of {timeout_s:g} s", **base)
    except Exception as e:             # a crash is recorded, never propagated
        return Trajectory(channels=nan, status="error", wall_s=0.0,
                          reason=f"{type(e).__name__}: {e}".splitlines()[0],
                          stats={"traceback": traceback.format_exc(limit=4)}, **base)
    missing = [c for c in scene.channels if c not in res["channels"]]
    if missing:
        return Trajectory(channels=nan, status="error", wall_s=wall,
                          reason=f"leaf did not return channels {missing}", **base)
    channels = {c: np.asarray(res["channels"][c], float) for c in scene.channels}
    status, t_fail, reason = res.get("status", "ok"), res.get("t_fail"), res.get("reason")
    if status == "ok":                 # silent garbage is the one forbidden outcome
        t_bad = _first_bad_time(t_out, channels)
        if t_bad is not None:
            status, t_fail, reason = "diverged", t_bad, "non-finite output behind status ok"
    if status == "ok" and scene.energy_channel:
        t_bad, why = _energy_jump(t_out, channels, scene)
        if t_bad is not None:
            status, t_fail, reason = "diverged", t_bad, why
    invariants = dict(res.get("invariants", {}))
    for c in scene.invariant_channels:
        x = channels[c][np.isfinite(channels[c])]
        if len(x):
            invariants[c] = float(np.max(np.abs(x - x[0])) / max(abs(x[0]), 1e-300))
    base["settings"] = res.get("settings", settings)
    return Trajectory(channels=channels, status=status, t_fail=t_fail, reason=reason,
                      stats={**stats, **res.get("stats", {})}, wall_s=wall,
                      invariants=invariants, extra=res.get("extra", {}), **base)


def modes(scene, solver, params, settings=None):
    """Natural frequencies from one solver; always returns a Modes (status tells)."""
    base = dict(scene=scene.name, solver=solver.name, versions=versions(solver))
    try:
        leaf = solver.leaf(scene.name)
        s = dict(getattr(leaf, "MODES_SETTINGS", {}), **(settings or {}))
        t0 = time.perf_counter()
        res = leaf.modes(params, s)
        wall = time.perf_counter() - t0
    except ValueError as e:
        raise BadInput(f"{solver.name}: {e}") from None
    except Exception as e:
        return Modes(frequencies_hz=np.array([]), labels=[], status="error",
                     reason=f"{type(e).__name__}: {e}".splitlines()[0], **base)
    return Modes(frequencies_hz=np.asarray(res["frequencies_hz"], float),
                 labels=list(res["labels"]), damping=res.get("damping"),
                 settings=res.get("settings", s), wall_s=wall, **base)
