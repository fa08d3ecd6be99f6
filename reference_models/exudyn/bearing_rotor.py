"""Exudyn model of the two-bearing rotor with a bearing defect (scene `bearing-rotor`).

The shaft is an `ObjectRigidBody` on a `NodeRigidBodyRxyz` (six coordinates: centre of mass
x, y, z and Tait–Bryan angles α, β, γ with R = Rx(α)·Ry(β)·Rz(γ)); mass m, central inertia
diag(J_t, J_t, J_p), axis body z; gravity is a `LoadMassProportional`. Exudyn supplies the mass
matrix, the gyroscopic terms and the integration. The chart is singular only at β = ±90°; the
shaft tilts by micro-radians in its bearings, and the spin γ is the last angle, unbounded.

All other loads come from ONE `ObjectGenericODE2` whose `forceUserFunction` evaluates the
scene's `compare.physics.bearing_rotor.body_loads` (bearing spring–dampers with the defect lift,
axial spring, motor and friction moments) at every force evaluation and returns the generalised
forces: the force on x, y, z and Gᵀ·M on α, β, γ, where ω = G·(α̇, β̇, γ̇) with the columns e_x,
Rx e_y, Rx Ry e_z. The same object carries a two-coordinate `NodeGenericODE2` whose mass matrix
is the identity and whose generalised forces are the motor power Ẇ and the dissipation power Ḋ:
its velocities are then W and D, integrated by the same Runge–Kutta stages as the mechanics from
the same stage states (one Python call per stage for everything; the energy balance closes at
the integrator's accuracy, not the output grid's).

Output: node sensors at every output step (fixed step: the step divides output_dt) or at every
step (adaptive DOPRI5 and ODE23, here `rk23`: their steps do not land on the grid; the
coordinates are put onto it by cubic Hermite interpolation with the sensors' velocities and
accelerations; the step is capped at `max_step_ratio` × the output step).

Divergence: the user function stops the run on a non-finite state or a bound (a journal farther
than l/4 from its bearing, which also keeps the chart 60° from its lock; |ω| > 1e5 rad/s); an
Exudyn solver exception (Newton failure, step size below the minimum) ends it too; the energy
balance is checked on the grid. Each gives `diverged` with t_fail and the reason.
"""
from __future__ import annotations

import math
import signal
import threading
import time
from contextlib import contextmanager

import exudyn as exu
import numpy as np
from exudyn.itemInterface import (
    LoadMassProportional,
    MarkerBodyMass,
    NodeGenericODE2,
    NodeRigidBodyRxyz,
    ObjectGenericODE2,
    ObjectRigidBody,
    SensorNode,
)
from numba import njit

from compare.contract import LeafResult, merge_settings
from compare.physics import bearing_rotor as br
from reference_models import bearing_common as bc

# Accurate default (measured against MuJoCo RK4 at 5 µs over the default 3 s run): DOPRI5 at
# rtol 1e-10 — journals within 4e-11 m, spin rate within 2e-7 rad/s, energy balance 1.3e-8 of
# the motor work; it adapts its step to stiff bearings (k_b = 1e9) where a fixed step diverges.
DEFAULT_SETTINGS = {"integrator": "dopri5", "dt": 1e-4, "rtol": 1e-10, "max_step_ratio": 1.0}
INTEGRATORS = ("rk4", "rk67", "dopri5", "rk23", "generalized_alpha")   # rk23: Exudyn's ODE23
ADAPTIVE = ("dopri5", "rk23")
# The adaptive output's cubic Hermite between step ends errs by h⁴·|y⁗|/384, which the tolerance
# does not control: the step, once grown to its cap (the output step × max_step_ratio), resolves
# the journals' bounce on the bearings (√(2 k_b/m): 450 rad/s at `xval calibrate bearing-rotor
# --seed 6060` set 13) well enough for DOPRI5 but not for the interpolant: motor_work 3.85e-11 J
# off between step ends (1e-13 at them), at rtol 1e-10 and 1e-12 alike, so the rtol/100 rerun
# saw none of it; a cap of 1/2, 1/4, 1/8 left 5.8e-12, 3.5e-12, 9e-13. The cap is therefore a
# knob of the error estimate, order 4 (the interpolant's).
KNOBS = {"max_step_ratio": 4}
KNOB_INTEGRATORS = {"max_step_ratio": ADAPTIVE}
_SOLVERS = {"rk4": exu.DynamicSolverType.RK44, "rk67": exu.DynamicSolverType.RK67,
            "dopri5": exu.DynamicSolverType.DOPRI5, "rk23": exu.DynamicSolverType.ODE23,
            "generalized_alpha": exu.DynamicSolverType.GeneralizedAlpha}


class _Stop(Exception):
    """Raised in the user function to end the run (non-finite state or bound)."""


@njit(cache=True)
def rxyz_kinematics(q, qt):
    """(quaternion w,x,y,z, G (3,3), ω fixed frame) of R = Rx(q3)·Ry(q4)·Rz(q5)."""
    a, b, c = q[3], q[4], q[5]
    ca, sa, cb, sb = math.cos(a), math.sin(a), math.cos(b), math.sin(b)
    wa, xa = math.cos(0.5 * a), math.sin(0.5 * a)
    wb, yb = math.cos(0.5 * b), math.sin(0.5 * b)
    wc, zc = math.cos(0.5 * c), math.sin(0.5 * c)
    # qx(a) ⊗ qy(b) = (wa wb, xa wb, wa yb, xa yb); then ⊗ qz(c)
    w1, x1, y1, z1 = wa * wb, xa * wb, wa * yb, xa * yb
    quat = np.array([w1 * wc - z1 * zc, x1 * wc + y1 * zc, y1 * wc - x1 * zc, w1 * zc + z1 * wc])
    G = np.array([[1.0, 0.0, sb], [0.0, ca, -sa * cb], [0.0, sa, ca * cb]])
    return quat, G, G @ qt[3:6]


@njit(cache=True)
def generalised_forces(q, qt, p, r_bound, w_bound):
    """Generalised forces on (x, y, z, α, β, γ, W, D) and a flag (0 fine, 1 non-finite,
    2 journal bound, 3 ω bound)."""
    out = np.zeros(8)
    s = 0.0
    for i in range(6):
        s += q[i] + qt[i]
    if not math.isfinite(s):
        return out, 1.0
    quat, G, omega = rxyz_kinematics(q, qt)
    # |r_xy| + (l/2)|n_xy| bounds both journals' radial offsets (n = G[:, 2], the shaft axis)
    if math.hypot(q[0], q[1]) + 0.5 * p[br.I_L] * math.hypot(G[0, 2], G[1, 2]) > r_bound:
        return out, 2.0
    if omega @ omega > w_bound * w_bound:
        return out, 3.0
    force, moment, p_motor, p_diss = br.body_loads(q[0:3].copy(), quat, qt[0:3].copy(), omega, p)
    out[0:3] = force
    out[3:6] = G.T @ moment
    out[6] = p_motor
    out[7] = p_diss
    return out, 0.0


_REASONS = {1.0: "non-finite state", 2.0: "journal left its bearing by more than l/4",
            3.0: "angular velocity bound exceeded"}


def _build(params: dict, adaptive: bool):
    """The rigid shaft, gravity, the load object and the sensors, at the common start."""
    p = br.pack(params)
    r_bound = bc.JOURNAL_BOUND * float(params["l"])
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    r0, q0, v0, w0 = br.initial_state(params)
    # the common start turns the shaft about the fixed x axis only: Rx(α), α = 2 atan2(x, w)
    assert q0[2] == q0[3] == 0.0, "the start is a turn about the fixed x axis"
    angles = np.array([2.0 * math.atan2(q0[1], q0[0]), 0.0, 0.0])
    _, G, _ = rxyz_kinematics(np.r_[r0, angles], np.zeros(6))
    rates = np.linalg.solve(G, w0)                     # ω = G·(α̇, β̇, γ̇)
    nb = mbs.AddNode(NodeRigidBodyRxyz(referenceCoordinates=[0.0] * 6,
                                       initialCoordinates=[*map(float, r0), *map(float, angles)],
                                       initialVelocities=[*map(float, v0), *map(float, rates)]))
    jt, jp = float(params["J_t"]), float(params["J_p"])
    body = mbs.AddObject(ObjectRigidBody(nodeNumber=nb, mass=float(params["m"]),
                                         inertia=[jt, jt, jp, 0.0, 0.0, 0.0]))
    mbs.AddLoad(LoadMassProportional(markerNumber=mbs.AddMarker(MarkerBodyMass(bodyNumber=body)),
                                     loadVector=[float(x) for x in params["gravity"]]))
    nw = mbs.AddNode(NodeGenericODE2(referenceCoordinates=[0.0, 0.0],
                                     initialCoordinates=[0.0, 0.0],
                                     initialCoordinates_t=[0.0, 0.0], numberOfODE2Coordinates=2))
    mass = np.zeros((8, 8))
    mass[6, 6] = mass[7, 7] = 1.0            # W'' = Ẇ: the work node's velocities are W and D
    fail = {"flag": 0.0, "t": None, "calls": 0}

    def loads(mbs_, t, item, q, q_t):
        fail["calls"] += 1
        out, flag = generalised_forces(np.asarray(q), np.asarray(q_t), p, r_bound,
                                       bc.OMEGA_BOUND)
        if flag != 0.0:
            fail["flag"], fail["t"] = flag, t
            raise _Stop(_REASONS[flag])
        return out

    mbs.AddObject(ObjectGenericODE2(nodeNumbers=[nb, nw], massMatrix=mass,
                                    forceUserFunction=loads))
    ov = exu.OutputVariableType
    sensors = {(node, kind): mbs.AddSensor(SensorNode(nodeNumber=node, storeInternal=True,
                                                      writeToFile=False,
                                                      outputVariableType=getattr(ov, kind)))
               for node in (nb, nw)
               for kind in ("Coordinates", "Coordinates_t") + ("Coordinates_tt",) * adaptive}
    mbs.Assemble()
    return mbs, nb, nw, sensors, fail


@contextmanager
def _signals_kept(box: dict):
    """Exudyn wraps whatever a user function raises into its own error, so an exception that a
    signal handler raises there (the adapter's wall-clock alarm, Ctrl-C) would read as a solver
    failure. Wrap the handlers so the exception is kept in box["interrupt"] to raise again."""
    saved = {}
    if threading.current_thread() is threading.main_thread():
        for sig in (getattr(signal, "SIGALRM", None), signal.SIGINT):
            handler = signal.getsignal(sig) if sig is not None else None
            if callable(handler):
                def kept(signum, frame, _handler=handler):
                    try:
                        _handler(signum, frame)
                    except BaseException as exc:
                        box["interrupt"] = exc
                        raise
                saved[sig] = handler
                signal.signal(sig, kept)
    try:
        yield
    finally:
        for sig, handler in saved.items():
            signal.signal(sig, handler)


def _settings(s: dict, t_end: float, h: float, adaptive: bool, output_dt: float):
    ss = exu.SimulationSettings()
    ti = ss.timeIntegration
    ti.endTime = float(t_end)
    ti.numberOfSteps = max(1, int(round(t_end / h)))
    ti.verboseMode = 0
    ti.explicit.useLieGroupIntegration = False      # Rxyz node: plain RK on the coordinates
    ti.explicit.eliminateConstraints = False
    # accelerations at step ends only for the Hermite interpolation of adaptive steps
    ti.explicit.computeEndOfStepAccelerations = adaptive
    ti.automaticStepSize = adaptive
    if adaptive:
        ti.relativeTolerance = ti.absoluteTolerance = float(s["rtol"])
        ti.minimumStepSize = 1e-12
        ti.initialStepSize = 1e-6
    if s["integrator"] == "generalized_alpha":
        ti.generalizedAlpha.spectralRadius = 1.0
        ti.adaptiveStep = False
        ti.newton.relativeTolerance = 1e-10
        ti.newton.absoluteTolerance = 1e-12
    ss.solution.file.write = False
    ss.solution.sensors.writePeriod = 0.0 if adaptive else float(output_dt)
    ss.show.computationTime = False
    ss.show.statistics = False
    return ss


def _hermite(t, y, dy, t_out):
    """Cubic Hermite interpolation of samples (t, y, dy) (columns) onto t_out."""
    j = np.clip(np.searchsorted(t, t_out, side="right") - 1, 0, len(t) - 2)
    h = (t[j + 1] - t[j])[:, None]
    s = ((t_out - t[j])[:, None] / h)
    h00, h10 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s
    h01, h11 = -2 * s**3 + 3 * s**2, s**3 - s**2
    return h00 * y[j] + h10 * h * dy[j] + h01 * y[j + 1] + h11 * h * dy[j + 1]


def simulate(params: dict, t_out: np.ndarray, settings: dict) -> LeafResult:
    """Spin-up on the output grid t_out (uniform, from 0); see the module docstring."""
    s = merge_settings(settings, DEFAULT_SETTINGS, INTEGRATORS)
    adaptive = s["integrator"] in ADAPTIVE
    key = "rtol" if adaptive else "dt"
    try:
        val = float(s[key])
    except (TypeError, ValueError):
        raise ValueError(f"{key} must be a positive number, got {s[key]!r}") from None
    if not (math.isfinite(val) and val > 0 and (key == "dt" or val < 1)):
        raise ValueError(f"{key} must be a positive number{' below 1' * adaptive}, "
                         f"got {s[key]!r}")
    cap = s["max_step_ratio"]
    if not (isinstance(cap, (int, float)) and math.isfinite(cap) and cap > 0):
        raise ValueError(f"max_step_ratio must be a positive number, got {cap!r}")
    t_out = np.asarray(t_out, float)
    n = len(t_out)
    dto = float(t_out[1] - t_out[0]) if n > 1 else 1.0
    if adaptive:
        h = dto * float(cap)
        used = {"integrator": s["integrator"], "rtol": val, "max_step_ratio": float(cap)}
    else:
        _, h = bc.step_plan(t_out, val)
        used = {"integrator": s["integrator"], "dt": h}
        if abs(h - val) > 1e-12 * val:
            used["dt_requested"] = val
    mbs, nb, nw, sensors, fail = _build(params, adaptive)
    ss = _settings(s, t_out[-1], h, adaptive, dto)
    status, t_fail, reason = "ok", None, None
    previous = exu.config.printToConsole
    exu.config.printToConsole = False
    solver = _SOLVERS[s["integrator"]]
    wall0 = time.perf_counter()
    try:
        with _signals_kept(fail):
            mbs.SolveDynamic(ss, solverType=solver, storeSolver=True)
    except Exception as exc:  # noqa: BLE001 - _Stop (via ModelError), SolverError, ...
        if fail.get("interrupt") is not None:
            raise fail["interrupt"] from None
        status = "diverged"
        if fail["flag"]:
            t_fail, reason = float(fail["t"]), _REASONS[fail["flag"]]
        else:
            reason = "Exudyn solver error: " + str(exc).strip().splitlines()[0][:200]
    finally:
        exu.config.printToConsole = previous
    wall = time.perf_counter() - wall0

    data = {k: mbs.GetSensorStoredData(v) for k, v in sensors.items()}
    if data[(nb, "Coordinates")].size == 0:        # stopped before the first sensor write
        data = {k: np.zeros((0, 1 + (6 if k[0] == nb else 2))) for k in data}
    t_rec = data[(nb, "Coordinates")][:, 0]
    rec = {k: v[:, 1:] for k, v in data.items()}
    if status != "ok" and t_fail is None:
        t_fail = float(t_rec[-1]) if len(t_rec) else 0.0
    if status != "ok" and not adaptive:
        reason += bc.stability_note(params, h)
    q = np.full((n, 6), np.nan)
    qt = np.full((n, 6), np.nan)
    wd = np.full((n, 2), np.nan)
    if adaptive:
        keep = t_out <= t_rec[-1] + 1e-12 if len(t_rec) > 1 else t_out <= 0.0
        if len(t_rec) > 1:
            # drop repeated times (a step cut to land on t_end can repeat the last sample)
            u = np.concatenate([[True], np.diff(t_rec) > 0])
            tr = t_rec[u]
            q[keep] = _hermite(tr, rec[(nb, "Coordinates")][u], rec[(nb, "Coordinates_t")][u],
                               t_out[keep])
            qt[keep] = _hermite(tr, rec[(nb, "Coordinates_t")][u],
                                rec[(nb, "Coordinates_tt")][u], t_out[keep])
            wd[keep] = _hermite(tr, rec[(nw, "Coordinates_t")][u],
                                rec[(nw, "Coordinates_tt")][u], t_out[keep])
        elif len(t_rec):
            q[0], qt[0], wd[0] = rec[(nb, "Coordinates")][0], rec[(nb, "Coordinates_t")][0], 0.0
        steps = max(len(t_rec) - 1, 0)
    else:
        idx = np.rint(t_rec / dto).astype(int)
        ok = (idx >= 0) & (idx < n) & (np.abs(t_rec - idx * dto) < 1e-6 * dto)
        q[idx[ok]] = rec[(nb, "Coordinates")][ok]
        qt[idx[ok]] = rec[(nb, "Coordinates_t")][ok]
        wd[idx[ok]] = rec[(nw, "Coordinates_t")][ok]
        steps = int(round(min(t_rec[-1], t_out[-1]) / h)) if len(t_rec) else 0
    if status != "ok":                 # the failing step's stage states never reach output
        late = t_out >= t_fail
        q[late] = qt[late] = wd[late] = np.nan
    quat = np.full((n, 4), np.nan)
    omega = np.full((n, 3), np.nan)
    for i in np.nonzero(np.all(np.isfinite(q), axis=1) & np.all(np.isfinite(qt), axis=1))[0]:
        quat[i], _, omega[i] = rxyz_kinematics(q[i], qt[i])
    stats = {"steps": steps, "rhs_evals": fail["calls"], "integrate_s": wall}
    return bc.result(params, t_out, q[:, :3], qt[:, :3], quat, omega, wd[:, 0], wd[:, 1],
                     status, t_fail, reason, stats, used, None if adaptive else h)


# ------------------------------------------------------------------ linearisation (xval modes)
# Exudyn differentiates the forces numerically with the step relativeEpsilon × max(minimum
# coordinate size, |q|). Against the closed form (`bearing_rotor.modal_closed_form`) the
# defaults (1e-7, 0.01: steps of 1e-9 m) leave the axial root 1.4e-8 off (round-off of
# z_a − l/2); steps of 1e-6 (1e-6, 1) leave every root within 1.3e-11, steps of 1e-5 the
# conical ones 4.3e-10 off (truncation).
FD_RELATIVE, FD_MINIMUM = 1e-6, 1.0


def _linearised(params: dict, relative: float) -> np.ndarray:
    """A (12 × 12) of the shaft's coordinates (x, y, z, α, β, γ) and their rates about the
    steady spin: `ComputeLinearizedSystem` at the sag spinning at γ̇ = Ω (defect-free), the
    work node left out (the mechanics does not depend on it)."""
    mbs, _, _, _, _ = _build({**params, "defect_height": 0.0}, False)
    n = mbs.systemData.ODE2Size()
    q, qt = np.zeros(n), np.zeros(n)
    q[:3] = br.static_sag(params)
    qt[5] = br.steady_spin_rate(params)
    mbs.systemData.SetODE2Coordinates(list(q), exu.ConfigurationType.Initial)
    mbs.systemData.SetODE2Coordinates_t(list(qt), exu.ConfigurationType.Initial)
    ss = exu.SimulationSettings()
    nd = ss.staticSolver.newton.numericalDifferentiation
    nd.relativeEpsilon, nd.minimumCoordinateSize = relative, FD_MINIMUM
    M, K, D = (np.asarray(x, float)[:6, :6] for x in mbs.ComputeLinearizedSystem(ss)[:3])
    Minv = np.linalg.inv(M)
    return np.block([[np.zeros((6, 6)), np.eye(6)], [-Minv @ K, -Minv @ D]])


def modes(params: dict, settings: dict | None = None):
    """Damped modes about the steady spin from Exudyn's linearisation (M, K, D with the
    gyroscopic terms in D); for small tilts (α, β) are the fixed-frame tilt (θx, θy) and γ the
    spin angle. Error estimate: the linearisation at half the differentiation step."""
    return br.modes_result(_linearised(params, FD_RELATIVE),
                           _linearised(params, 0.5 * FD_RELATIVE), params,
                           {"relativeEpsilon": FD_RELATIVE, "minimumCoordinateSize": FD_MINIMUM},
                           "exudyn ComputeLinearizedSystem → [[0, I], [−M⁻¹K, −M⁻¹D]]")
