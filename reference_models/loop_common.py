"""The engine pieces the closed-loop mechanisms (`andrews-squeezer`, `bricard`; the soft-loop
settings also `press`) share: the checked settings, Exudyn's generalized-α settings and its
solve output interval by output interval, and MuJoCo's soft-constraint strings and fixed-step
run with the divergence check. The models themselves stay in exudyn/*.py and mujoco/*.py.
"""
from __future__ import annotations

import math

import numpy as np

from .press_common import fixed_step_settings


def check_soft_constraint(s: dict) -> dict:
    """solref_factor > 0 and five solimp numbers, as floats, in s (ValueError with one line)."""
    s["solref_factor"] = float(s["solref_factor"])
    if not s["solref_factor"] > 0:
        raise ValueError("solref_factor must be > 0")
    s["solimp"] = tuple(float(x) for x in s["solimp"])
    if len(s["solimp"]) != 5:
        raise ValueError("solimp must have 5 numbers")
    return s


def mujoco_settings(settings: dict | None, defaults: dict, integrators: tuple) -> dict:
    """A MuJoCo soft-loop leaf's settings: a positive fixed step and the soft constraint."""
    return check_soft_constraint(fixed_step_settings(settings, defaults, integrators))


def exudyn_settings(settings: dict | None, defaults: dict, integrators: tuple) -> dict:
    """An Exudyn generalized-α leaf's settings: a positive fixed step, spectral radius in [0, 1]."""
    s = fixed_step_settings(settings, defaults, integrators)
    rho = float(s["spectral_radius"])
    if not 0.0 <= rho <= 1.0:
        raise ValueError(f"spectral_radius must be in [0, 1], got {rho!r}")
    s["spectral_radius"] = rho
    return s


def _steps(t0: float, t1: float, dt: float) -> int:
    """Fixed steps of at most dt over [t0, t1] (at least one)."""
    return max(1, int(math.ceil((t1 - t0) / dt - 1e-9)))


# ---------------------------------------------------------------- Exudyn (imported lazily)

def ga_simulation_settings(s: dict):
    """Exudyn's settings for a fixed-step generalized-α run: full Newton with the checked
    tolerances, dense solver; `trapezoidal` = Newmark with index-2 constraints at ρ∞ = 1."""
    import exudyn as exu
    ss = exu.SimulationSettings()
    ss.solution.file.write = False
    ss.timeIntegration.verboseMode = 0
    ss.timeIntegration.adaptiveStep = False
    ss.timeIntegration.newton.relativeTolerance = float(s["newton_tol"])
    ss.timeIntegration.newton.absoluteTolerance = float(s["newton_abs_tol"])
    ss.timeIntegration.newton.useModifiedNewton = False
    ss.linearSolver.solverType = exu.LinearSolverType.EXUdense
    ga = ss.timeIntegration.generalizedAlpha
    if s["integrator"] == "generalized_alpha":
        ga.spectralRadius, ga.useIndex2Constraints, ga.useNewmark = s["spectral_radius"], False, \
            False
    else:
        ga.spectralRadius, ga.useIndex2Constraints, ga.useNewmark = 1.0, True, True
    return ss


# An output interval whose Newton iteration fails is solved again from its start on finer grids
# none of whose inner points is the run's, nst + 1, 2·nst + 1, … 2^(MAX_CUTS−1)·nst + 1 steps
# (the time-step cutback of implicit finite-element codes; the custom models' `la_step` cuts
# per step). Near a singular position the iteration matrix is near-singular and Newton fails
# on the step that lands there, whatever its length: at `xval calibrate n-four-bar --seed
# 3141` set 10, dt 1e-3 s stops at t = 0.635 s, φ 5e-6 rad from π, and so do 20, 40 … 1000
# steps over the interval (all land on 0.635), while 11, 13, 21 and 41 pass. A failure every
# grid shares is reported.
MAX_CUTS = 4


def _solve_interval(mbs, ss, t0: float, t1: float, dt: float) -> tuple:
    """Solve [t0, t1] from the system's initial state (updated to t1 on success), on the
    grids above in turn. Returns (steps taken, why it failed or None)."""
    import exudyn as exu
    start = mbs.systemData.GetSystemState(exu.ConfigurationType.Initial)
    nst = _steps(t0, t1, dt)
    for grid in [nst] + [(nst << k) + 1 for k in range(MAX_CUTS)]:
        ss.timeIntegration.startTime, ss.timeIntegration.endTime = t0, t1
        ss.timeIntegration.numberOfSteps = grid
        try:
            ok, why = mbs.SolveDynamic(ss, solverType=exu.DynamicSolverType.GeneralizedAlpha,
                                       updateInitialValues=True), None
        except Exception as exc:      # exudyn.SolverError, RuntimeError
            ok, why = False, str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        if ok:
            return grid, None
        mbs.systemData.SetSystemState(start, exu.ConfigurationType.Initial)
    return 0, why or "SolveDynamic returned False"


def exudyn_solve(build, state, t_out: np.ndarray, s: dict, n_q: int) -> tuple:
    """Solve the model `build()` = (SystemContainer, mbs, nodes, simulation settings) output
    interval by output interval (`SolveDynamic` with `updateInitialValues=True`, an interval
    that fails cut as above), reading `state(mbs, nodes)` = (q, q') of n_q coordinates at each
    output time. Returns (Q, QD, steps, status, t_fail, reason, used dt); rows after a failure
    stay NaN. Exudyn's console output is off for the run."""
    import exudyn as exu
    prev = exu.config.printToConsole
    exu.config.printToConsole = False
    n = len(t_out)
    Q, QD = np.full((n, n_q), np.nan), np.full((n, n_q), np.nan)
    steps, status, t_fail, reason = 0, "ok", None, None
    try:
        SC, mbs, nodes, ss = build()          # SC held: it owns mbs
        Q[0], QD[0] = state(mbs, nodes)
        for i in range(1, n):
            t0, t1 = float(t_out[i - 1]), float(t_out[i])
            taken, why = _solve_interval(mbs, ss, t0, t1, s["dt"])
            if why:
                status, t_fail = "diverged", t0
                reason = f"exudyn solver failed in [{t0:.6g}, {t1:.6g}]: {why}"
                break
            steps += taken
            Q[i], QD[i] = state(mbs, nodes)
            if not (np.all(np.isfinite(Q[i])) and np.all(np.isfinite(QD[i]))):
                status, t_fail, reason = "diverged", t1, "non-finite state"
                Q[i], QD[i] = np.nan, np.nan
                break
    finally:
        exu.config.printToConsole = prev
    dt = float((t_out[1] - t_out[0]) / _steps(t_out[0], t_out[1], s["dt"]))
    return Q, QD, steps, status, t_fail, reason, dt


# ---------------------------------------------------------------- MuJoCo (imported lazily)

MJ_INTEGRATORS = {"rk4": "RK4", "euler": "Euler", "implicitfast": "implicitfast",
                  "implicit": "implicit"}


def fmt(x) -> str:
    """A number as MuJoCo XML takes it, round-trip exact."""
    return f"{float(x):.17g}"


def soft_strings(s: dict) -> tuple[str, str]:
    """(solref, solimp) attribute values: time constant solref_factor·dt, damping ratio 1."""
    return f"{fmt(s['solref_factor'] * s['dt'])} 1", " ".join(fmt(x) for x in s["solimp"])


def mujoco_model(xml: str):
    """(MjModel, MjData) of an XML model."""
    import mujoco
    m = mujoco.MjModel.from_xml_string(xml)
    return m, mujoco.MjData(m)


def mujoco_run(m, d, t_out: np.ndarray, s: dict, record) -> tuple:
    """Step MjModel m / MjData d over the output grid with the step that divides its first
    interval, calling record(i) after each output step; stops at a non-finite state or MuJoCo's
    bad-qacc warning. Returns (steps, status, t_fail, reason, rhs_evals, used dt)."""
    import mujoco
    n_sub = _steps(t_out[0], t_out[1], s["dt"])
    h = (t_out[1] - t_out[0]) / n_sub
    m.opt.timestep = h
    steps, status, t_fail, reason = 0, "ok", None, None
    for i in range(1, len(t_out)):
        mujoco.mj_step(m, d, nstep=n_sub)
        steps += n_sub
        if (not np.all(np.isfinite(d.qpos)) or not np.all(np.isfinite(d.qvel))
                or d.warning[mujoco.mjtWarning.mjWARN_BADQACC].number > 0):
            status, t_fail, reason = "diverged", float(t_out[i]), "non-finite state (bad qacc)"
            break
        record(i)
    evals = 4 * steps if s["integrator"] == "rk4" else steps
    return steps, status, t_fail, reason, evals, float(h)
