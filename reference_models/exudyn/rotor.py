"""Exudyn reference model of the spin-up rotor (scenes `rotor-spinup` and `rotor-whirl`).

The rotor (massless shaft of length l on a spherical joint at O, eccentric disk at its end) is an
`ObjectKinematicTree` gimbal: three revolute joints X -> Y -> Z in one chain, the first two links
massless, the disk on the third. With the chart rotation A0 (see below) the body rotation is

    R = A0 · Rx(q0) · Ry(q1) · Rz(q2),

and the spatial angular velocity is ω = J(q)·q̇ with the columns A0·e_x, A0·Rx·e_y, R·e_z.

Loads (all in the tree's `forceUserFunction`, as generalised forces Jᵀτ of a spatial moment τ):
- the transverse spring τ_s = −kγ, γ = θ·(e_z × n)/|e_z × n|, n = R·e_z, θ = angle(e_z, n); it
  is −∂/∂q of ½kθ², so exactly conservative, and has no component along n;
- the drive torque τ_d = torque·e_z, fixed in space. (`linkTorques` is not used: it acts with
  the opposite sign to its docstring, see the Exudyn notes.)
Gravity is the tree's built-in `gravity`. The work A = ∫ torque·ω_z dt is an extra first-order
coordinate (`ObjectGenericODE1`) integrated by the same Runge–Kutta stages as the mechanics.

Charts. The Cardan chain locks where n = ±A0·e_x. The run starts with A0 = identity (lock at
n = ±e_x, i.e. tilt 90° towards x). When |cos q1| falls below `CHART_SWITCH` after a step (a
post-step user function stops the run), the run continues from that completed step on a new
model whose lock axis is ≥ 45° away from n and from the cone n sweeps when whirling about e_z
(`_new_chart`), so every tilt short of π is reachable; the output grid is kept because the step
size is unchanged. At tilt π the spring direction itself is undefined; the run stops there with
status `diverged`. An unstable step shows as a jump of the energy balance, which the compare
layer's one energy rule (the scene's `energy_bound`) reports as `diverged`.

Speed (the path is the fastest measured for this model; 10 s spin-up, RK67 at dt = 0.01, 1000
steps, best of 5 on 2 busy cores): the kinematic tree with the Python `forceUserFunction` and the
Python work rate, 85–96 ms (≈ 13 µs per stage evaluation, the Python calls dominate). Tried and
not taken: (a) the loads and the work rate as Exudyn symbolic user functions (C++ expression
trees; the work as the velocity of an extra ODE2 coordinate in an `ObjectGenericODE2` spanning
the tree's coordinates, the checks moved to a per-step post-step function): same numbers to all
digits but 85 ms at dt = 0.01 and 478 ms against 392 ms at dt = 0.002 — the expression trees are
interpreted, and the per-step Python check costs what the stage calls save; (b) the
`EXUDYN_MODULE=fast` module (no range checks): 171–182 ms against 156–196 ms, no difference in
the noise; (c) the tree's built-in joint springs (`jointPControlVector`) are C++ but are the
Cardan spring ½k(α²+β²), a different model (|ω(10 s)| moves by 0.3 rad/s, see the notes).
A fixed step longer than the output step runs on its own step grid and the channels are
interpolated linearly onto the output grid (as in the MuJoCo leaf); the final value is a step
end.

`modes` linearises the same tree (drive torque 0) about steady spin Ω at tilt 0 with Exudyn's
`ComputeLinearizedSystem` (M, K and the gyroscopic D = −∂f/∂q̇; gravity enters K through the
tree) and solves the quadratic eigenproblem.
"""
import math
import time

import exudyn as exu
import numpy as np
from exudyn.itemInterface import (
    NodeGenericODE1,
    NodeGenericODE2,
    ObjectGenericODE1,
    ObjectKinematicTree,
    SensorNode,
)

from compare.contract import LeafModes, LeafResult, merge_settings
from compare.physics import rotor as physics

_SOLVERS = {
    "rk4": exu.DynamicSolverType.RK44,
    "rk67": exu.DynamicSolverType.RK67,
    "dopri5": exu.DynamicSolverType.DOPRI5,
    "rk23": exu.DynamicSolverType.ODE23,
    "explicit_euler": exu.DynamicSolverType.ExplicitEuler,
    "generalized_alpha": exu.DynamicSolverType.GeneralizedAlpha,
}
_ADAPTIVE = ("dopri5", "rk23")
INTEGRATORS = tuple(_SOLVERS)

# Accurate default (measured, see tests and the module report): RK67 fixed step 2 ms gives an
# energy-balance drift of ~2e-6 J over the 10 s default run and |ω| converged to ~1e-8 rad/s.
DEFAULT_SETTINGS = {"integrator": "rk67", "dt": 2e-3, "rtol": 1e-10, "spectral_radius": 1.0}
ADAPTIVE = _ADAPTIVE                      # integrators that take rtol

TILT_LIMIT = math.pi - 1e-3        # stop here: −kγ has no defined direction at tilt π
CHART_SWITCH = 0.6                 # |cos q1| below this after a step -> change of Cardan chart
CHART_LOCK = 0.2                   # ... and in any stage state (hard guard near the lock)
_COS_TILT_LIMIT = math.cos(TILT_LIMIT)

MAX_CHART_CHANGES = 10000
_REASON_TILT = "singular spring direction at tilt pi"
_REASON_NONFINITE = "non-finite state"


class _Stop(Exception):
    """Raised inside a user function to end the Exudyn run (rechart / failure)."""


# ----------------------------------------------------------------------------------------------
# parameters and small rotation helpers

def _physical(params):
    """The model's numbers, from the shared rotor constants (the scene validated them)."""
    c = physics.constants(params)
    return {"m": float(params["m"]), "k": float(params["k"]), "g": c["gravity"],
            "rc0": c["rc0"], "I_c": c["I_c"],
            "c_ext": float(params.get("c_ext", 0.0)), "c_int": float(params.get("c_int", 0.0))}


def _rx(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1.0, 0, 0], [0, c, -s], [0, s, c]])


def _ry(b):
    c, s = math.cos(b), math.sin(b)
    return np.array([[c, 0, s], [0, 1.0, 0], [-s, 0, c]])


def _rz(c_):
    c, s = math.cos(c_), math.sin(c_)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])


def _chart_motion(A0, q, qd):
    """Body rotation R and spatial angular velocity ω from Cardan coordinates in chart A0."""
    Rx = A0 @ _rx(q[0])
    Rxy = Rx @ _ry(q[1])
    R = Rxy @ _rz(q[2])
    J = np.column_stack([A0[:, 0], Rx[:, 1], Rxy[:, 2]])
    return R, J @ qd


def _chart_coordinates(A0, R, w):
    """Inverse of `_chart_motion` (Cardan XYZ angles of A0ᵀR and the rates that give ω)."""
    M = A0.T @ R
    b = math.asin(max(-1.0, min(1.0, M[0, 2])))
    a = math.atan2(-M[1, 2], M[2, 2])
    c = math.atan2(-M[0, 1], M[0, 0])
    q = np.array([a, b, c])
    Rx = A0 @ _rx(a)
    Rxy = Rx @ _ry(b)
    J = np.column_stack([A0[:, 0], Rx[:, 1], Rxy[:, 2]])
    return q, np.linalg.solve(J, w)


def _new_chart(R):
    """Chart for the current body axis n, with its lock axes ±A0·e_x at least 45° from n and
    from the cone n sweeps when it whirls about e_z at the current tilt θ:
    - 45° < θ < 135°: lock axis e_z (distance θ and π − θ from the whirl cone);
    - otherwise: lock axis horizontal and ⊥ n (distance 90° − |90° − θ| ≥ 45° from the cone)."""
    n = R[:, 2]
    tilt = math.atan2(math.hypot(n[0], n[1]), n[2])
    if math.pi / 4 < tilt < 3 * math.pi / 4:
        a = np.array([0.0, 0.0, 1.0])
    else:
        a = np.cross([0.0, 0.0, 1.0], n)
        if np.linalg.norm(a) < 1e-9:
            a = np.array([1.0, 0.0, 0.0])
    a = a / np.linalg.norm(a)
    b = np.cross(a, [1.0, 0.0, 0.0]) if abs(a[0]) < 0.9 else np.cross(a, [0.0, 1.0, 0.0])
    b /= np.linalg.norm(b)
    return np.column_stack([a, b, np.cross(a, b)])


def _quaternions(R):
    """(n,4) unit quaternions w,x,y,z of rotation matrices (n,3,3), sign kept continuous."""
    n = R.shape[0]
    Q = np.empty((n, 4))
    tr = R[:, 0, 0] + R[:, 1, 1] + R[:, 2, 2]
    cand = np.stack([tr, R[:, 0, 0], R[:, 1, 1], R[:, 2, 2]], axis=1)
    which = np.argmax(cand, axis=1)
    for i in range(n):
        r = R[i]
        j = which[i]
        if j == 0:
            s = 2.0 * math.sqrt(max(1.0 + tr[i], 0.0))
            Q[i] = [0.25 * s, (r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s,
                    (r[1, 0] - r[0, 1]) / s]
        elif j == 1:
            s = 2.0 * math.sqrt(max(1.0 + r[0, 0] - r[1, 1] - r[2, 2], 0.0))
            Q[i] = [(r[2, 1] - r[1, 2]) / s, 0.25 * s, (r[0, 1] + r[1, 0]) / s,
                    (r[0, 2] + r[2, 0]) / s]
        elif j == 2:
            s = 2.0 * math.sqrt(max(1.0 + r[1, 1] - r[0, 0] - r[2, 2], 0.0))
            Q[i] = [(r[0, 2] - r[2, 0]) / s, (r[0, 1] + r[1, 0]) / s, 0.25 * s,
                    (r[1, 2] + r[2, 1]) / s]
        else:
            s = 2.0 * math.sqrt(max(1.0 + r[2, 2] - r[0, 0] - r[1, 1], 0.0))
            Q[i] = [(r[1, 0] - r[0, 1]) / s, (r[0, 2] + r[2, 0]) / s, (r[1, 2] + r[2, 1]) / s,
                    0.25 * s]
        if i > 0 and Q[i] @ Q[i - 1] < 0:
            Q[i] = -Q[i]
    return Q


# ----------------------------------------------------------------------------------------------
# the Exudyn model

def _build(ph, A0, q0, qd0, w0, torque, with_work=True, stop_checks=True):
    """Kinematic-tree rotor in chart A0 with initial coordinates q0, rates qd0 and work w0."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    nq = mbs.AddNode(NodeGenericODE2(referenceCoordinates=[0.0] * 3,
                                     initialCoordinates=list(map(float, q0)),
                                     initialCoordinates_t=list(map(float, qd0)),
                                     numberOfODE2Coordinates=3))
    k, c_ext, c_int = ph["k"], ph.get("c_ext", 0.0), ph.get("c_int", 0.0)
    a0 = [float(x) for x in A0[:, 0]]
    A = [[float(x) for x in row] for row in A0]
    flag = {"kind": None, "t": None, "calls": 0}

    def force(mbs_, t, itemNumber, q, q_t):
        flag["calls"] += 1
        ca, sa = math.cos(q[0]), math.sin(q[0])
        cb, sb = math.cos(q[1]), math.sin(q[1])
        # joint axes in the chart frame: e_x, Rx e_y, Rx Ry e_z; then rotate by A0
        u1 = (0.0, ca, sa)
        u2 = (sb, -sa * cb, ca * cb)
        j1 = (A[0][1] * u1[1] + A[0][2] * u1[2], A[1][1] * u1[1] + A[1][2] * u1[2],
              A[2][1] * u1[1] + A[2][2] * u1[2])
        nx = A[0][0] * u2[0] + A[0][1] * u2[1] + A[0][2] * u2[2]
        ny = A[1][0] * u2[0] + A[1][1] * u2[1] + A[1][2] * u2[2]
        nz = A[2][0] * u2[0] + A[2][1] * u2[1] + A[2][2] * u2[2]
        if stop_checks:
            if not (math.isfinite(q[0] + q[1] + q[2]) and math.isfinite(q_t[0] + q_t[1] + q_t[2])):
                flag["kind"], flag["t"] = "nonfinite", t
                raise _Stop()
            if nz < _COS_TILT_LIMIT:
                flag["kind"], flag["t"] = "tilt", t
                raise _Stop()
            if abs(cb) < CHART_LOCK:               # hard guard inside a stage
                flag["kind"], flag["t"] = "chart", t
                raise _Stop()
        s = math.sqrt(nx * nx + ny * ny)
        th = math.atan2(s, nz)
        f = th / s if s > 1e-6 else 1.0 + th * th / 6.0    # θ/sinθ, no 0/0 at θ = 0
        # τ = −k·θ/sinθ·(e_z × n) + torque·e_z
        tx = k * f * ny
        ty = -k * f * nx
        tz = torque
        if c_ext or c_int:
            # ω = J q̇; external damper: −c_ext (ω − (ω·n) n) = −c_ext n × ṅ, against the axis'
            # motion in the fixed frame; internal: a damper between the rotor and a hub spinning
            # with it about the fixed z axis, −c_int (ω_x, ω_y, 0) (to first order the tilt
            # rate seen in the rotor's frame, θ̇ − iΩθ)
            w = [a0[i] * q_t[0] + j1[i] * q_t[1] + (nx, ny, nz)[i] * q_t[2] for i in range(3)]
            wn = w[0] * nx + w[1] * ny + w[2] * nz
            tx -= c_ext * (w[0] - wn * nx) + c_int * w[0]
            ty -= c_ext * (w[1] - wn * ny) + c_int * w[1]
            tz -= c_ext * (w[2] - wn * nz)
        return [tx * a0[0] + ty * a0[1] + tz * a0[2],
                tx * j1[0] + ty * j1[1] + tz * j1[2],
                tx * nx + ty * ny + tz * nz]

    Z = np.zeros((3, 3))
    mbs.AddObject(ObjectKinematicTree(
        nodeNumber=nq,
        jointTypes=[exu.JointType.RevoluteX, exu.JointType.RevoluteY, exu.JointType.RevoluteZ],
        linkParents=[-1, 0, 1],
        jointTransformations=exu.Matrix3DList([np.asarray(A0, float), np.eye(3), np.eye(3)]),
        jointOffsets=exu.Vector3DList([[0.0, 0.0, 0.0]] * 3),
        linkInertiasCOM=exu.Matrix3DList([Z, Z, ph["I_c"]]),
        linkCOMs=exu.Vector3DList([[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], list(ph["rc0"])]),
        linkMasses=[0.0, 0.0, ph["m"]],
        gravity=[float(x) for x in ph["g"]],
        forceUserFunction=force))
    items = {"mbs": mbs, "SC": SC, "nq": nq, "flag": flag}
    if with_work:
        nw = mbs.AddNode(NodeGenericODE1(referenceCoordinates=[0.0], initialCoordinates=[float(w0)],
                                         numberOfODE1Coordinates=1))
        sysdata = mbs.systemData
        cur = exu.ConfigurationType.Current

        def work_rate(mbs_, t, itemNumber, w):
            # ω_z = (J q̇)_z at the stage state the solver is evaluating
            q = sysdata.GetODE2Coordinates(cur)
            qd = sysdata.GetODE2Coordinates_t(cur)
            ca, sa = math.cos(q[0]), math.sin(q[0])
            cb, sb = math.cos(q[1]), math.sin(q[1])
            j1z = A[2][1] * ca + A[2][2] * sa
            nz = A[2][0] * sb - A[2][1] * sa * cb + A[2][2] * ca * cb
            return [torque * (A[2][0] * qd[0] + j1z * qd[1] + nz * qd[2])]

        mbs.AddObject(ObjectGenericODE1(nodeNumbers=[nw], rhsUserFunction=work_rate))

        if stop_checks:
            def post_step(mbs_, t):
                # completed step: leave the chart well before its lock (restart happens outside)
                if abs(math.cos(sysdata.GetODE2Coordinates(cur)[1])) < CHART_SWITCH:
                    flag["kind"], flag["t"] = "chart", t
                    return False
                return True

            mbs.SetPostStepUserFunction(post_step)
        items["nw"] = nw
        items["sq"] = mbs.AddSensor(SensorNode(nodeNumber=nq, storeInternal=True, writeToFile=False,
                                               outputVariableType=exu.OutputVariableType.Coordinates))
        items["sv"] = mbs.AddSensor(SensorNode(nodeNumber=nq, storeInternal=True, writeToFile=False,
                                               outputVariableType=exu.OutputVariableType.Coordinates_t))
        items["sw"] = mbs.AddSensor(SensorNode(nodeNumber=nw, storeInternal=True, writeToFile=False,
                                               outputVariableType=exu.OutputVariableType.Coordinates))
    mbs.Assemble()
    return items


def _sim_settings(t0, t1, n_steps, write_period, name, rtol, spectral_radius=1.0, h0=None):
    ss = exu.SimulationSettings()
    ti = ss.timeIntegration
    ti.startTime = float(t0)
    ti.endTime = float(t1)
    ti.numberOfSteps = int(n_steps)
    ti.verboseMode = 0
    ti.explicit.useLieGroupIntegration = False     # no rotation nodes: plain RK on q
    ti.explicit.eliminateConstraints = False
    ti.explicit.computeEndOfStepAccelerations = False   # not needed: saves one RHS per step
    if name in _ADAPTIVE:
        ti.automaticStepSize = True
        ti.relativeTolerance = float(rtol)
        ti.absoluteTolerance = float(rtol)
        ti.minimumStepSize = 1e-12
        # a huge first trial step can hit the lock guard: start small, then go on with the
        # step size the previous interval ended with
        ti.initialStepSize = float(h0) if h0 else 1e-6 * (t1 - t0)
    else:
        ti.automaticStepSize = False
    if name == "generalized_alpha":
        ti.generalizedAlpha.spectralRadius = float(spectral_radius)
        ti.adaptiveStep = False
    ss.solution.file.write = False
    ss.solution.sensors.writePeriod = float(write_period)
    ss.show.computationTime = False
    ss.show.statistics = False
    return ss


def _steps_of(mbs):
    dyn = mbs.sys.get("dynamicSolver") if hasattr(mbs, "sys") else None
    try:
        return int(dyn.it.currentStepIndex)
    except Exception:                               # noqa: BLE001 - stats are best effort
        return 0


def _last_step_of(mbs, default):
    dyn = mbs.sys.get("dynamicSolver") if hasattr(mbs, "sys") else None
    try:
        it = dyn.it
        # the last step may be cut short to land on the interval end: take the mean step too
        h = max(float(it.currentStepSize),
                (float(it.endTime) - float(it.startTime)) / max(1, int(it.currentStepIndex)))
        return h if math.isfinite(h) and h > 0 else default
    except Exception:                               # noqa: BLE001
        return default


def _solve(mbs, ss, solver, update=False):
    """SolveDynamic with Exudyn's console chatter off; returns the exception (or None)."""
    previous = exu.config.printToConsole
    exu.config.printToConsole = False
    try:
        mbs.SolveDynamic(ss, solverType=solver, storeSolver=True, updateInitialValues=update)
        return None
    except Exception as ex:                         # noqa: BLE001 - _Stop, SolverError, ModelError
        return ex
    finally:
        exu.config.printToConsole = previous


# ----------------------------------------------------------------------------------------------
# time domain

def check_settings(settings, t_out=None):
    """Settings merged and checked before anything runs."""
    s = merge_settings(settings, DEFAULT_SETTINGS, INTEGRATORS)
    name = s["integrator"]
    if name in _ADAPTIVE:
        try:
            rtol = float(s["rtol"])
        except (TypeError, ValueError):
            raise ValueError(f"rtol must be in (0, 1), got {s['rtol']!r}") from None
        if not (math.isfinite(rtol) and 0 < rtol < 1):
            raise ValueError(f"rtol must be in (0, 1), got {s['rtol']!r}")
    else:
        try:
            dt = float(s["dt"])
        except (TypeError, ValueError):
            raise ValueError(f"dt must be a positive number, got {s['dt']!r}") from None
        if not (math.isfinite(dt) and dt > 0):
            raise ValueError(f"dt must be a positive number, got {s['dt']!r}")
        if t_out is not None and len(t_out) > 1 and dt > (t_out[-1] - t_out[0]) * (1 + 1e-9):
            raise ValueError(f"dt ({dt:g}) must not exceed the horizon "
                             f"({t_out[-1] - t_out[0]:g} s)")
    return s


def _coarse(params, t_out, s):
    """A fixed step longer than the output step: run on the step grid (N = ⌈t_end/dt⌉ equal
    steps, so the last one lands on t_end) and interpolate the channels linearly onto t_out,
    as the MuJoCo leaf does; the final value is a step end."""
    n = int(math.ceil((t_out[-1] - t_out[0]) / float(s["dt"]) - 1e-9))
    grid = np.linspace(t_out[0], t_out[-1], n + 1)
    res = simulate(params, grid, {**s, "dt": float(grid[1] - grid[0])})
    ok = np.isfinite(res.channels["omega_norm"])

    def interp(v):
        return (np.interp(t_out, grid[ok], v[ok], right=np.nan) if ok.sum() > 1
                else np.where(t_out == t_out[0], v[0], np.nan))

    q = np.stack([interp(res.extra["orientation"][:, j]) for j in range(4)], axis=1)
    w = np.stack([interp(res.extra["angular_velocity"][:, j]) for j in range(3)], axis=1)
    channels = {k: interp(v) for k, v in res.channels.items()}
    if res.t_fail is not None:
        late = t_out >= res.t_fail
        for v in (*channels.values(), q, w):
            v[late] = np.nan
    return LeafResult(channels=channels, status=res.status, t_fail=res.t_fail,
                      reason=res.reason, stats=res.stats,
                      settings={**res.settings, "dt": float(grid[1] - grid[0]),
                                "output": "linear interpolation between steps"},
                      extra={"orientation": q / np.linalg.norm(q, axis=1, keepdims=True),
                             "angular_velocity": w})


def simulate(params, t_out, settings):
    """Spin-up run on the output grid t_out (uniform, t_out[0] = 0); see the leaf contract."""
    t_out = np.asarray(t_out, dtype=float)
    s = check_settings(settings, t_out)
    name = s["integrator"]
    adaptive = name in _ADAPTIVE
    if not adaptive and len(t_out) > 1 and float(s["dt"]) > (t_out[1] - t_out[0]) * (1 + 1e-9):
        return _coarse(params, t_out, s)
    ph = _physical(params)
    n_out = len(t_out)
    dto = float(t_out[1] - t_out[0]) if n_out > 1 else 1.0
    used = {"integrator": name}
    if adaptive:
        used["rtol"] = float(s["rtol"])
        h = dto
    else:
        dt = float(s["dt"])
        h = dto / int(math.ceil(dto / dt - 1e-9))       # largest step <= dt dividing output_dt
        used["dt"] = h
        if abs(h - dt) > 1e-12 * dt:
            used["dt_requested"] = dt
    if name == "generalized_alpha":
        used["spectral_radius"] = float(s["spectral_radius"])

    R0 = _rx(float(params["tilt0"]))
    Rs = np.full((n_out, 3, 3), np.nan)
    Ws = np.full((n_out, 3), np.nan)
    Wk = np.full(n_out, np.nan)
    Rs[0], Ws[0], Wk[0] = R0, float(params["spin0"]) * R0[:, 2], 0.0

    # state to start the next Exudyn run from: time, rotation, angular velocity, work
    t_c, R_c, w_c, W_c = 0.0, Rs[0], Ws[0], 0.0
    i_good = 0                                          # last output sample filled
    A0 = np.eye(3)
    status, t_fail, reason = "ok", None, None
    steps = rhs_evals = charts = 0
    no_progress = 0
    h_adapt = None                                      # adaptive: step size to go on with
    solver = _SOLVERS[name]
    wall0 = time.perf_counter()
    while i_good < n_out - 1:
        q0, qd0 = _chart_coordinates(A0, R_c, w_c)
        model = _build(ph, A0, q0, qd0, W_c, float(params["torque"]))
        mbs, flag = model["mbs"], model["flag"]
        t_start = t_c
        ex = None
        # adaptive runs go interval by interval (each run ends exactly on the grid, the end state
        # is the next run's initial state); fixed-step runs go to the end in one call
        while i_good < n_out - 1:
            t_end = t_out[i_good + 1] if adaptive else t_out[-1]
            n_steps = 1 if adaptive else max(1, int(round((t_end - t_c) / h)))
            ss = _sim_settings(t_c, t_end, n_steps, 0.0, name, s["rtol"],
                               s["spectral_radius"], h_adapt)
            ex = _solve(mbs, ss, solver, update=adaptive)
            steps += _steps_of(mbs)
            if adaptive:
                h_adapt = _last_step_of(mbs, h_adapt)
            rows = [np.atleast_2d(mbs.GetSensorStoredData(model[k])) for k in ("sq", "sv", "sw")]
            m = min(len(r) for r in rows)
            data = np.column_stack([rows[0][:m, :4], rows[1][:m, 1:4], rows[2][:m, 1:2]])
            data = data[data[:, 0] > t_c + 1e-12 * max(1.0, t_c)] if m else data[:0]
            fin = np.all(np.isfinite(data), axis=1)
            if not np.all(fin):
                first = int(np.argmin(fin))
                flag["kind"], flag["t"] = "nonfinite", float(data[first, 0])
                data = data[:first]
                ex = ex or _Stop()
            if len(data):
                Rd = np.empty((len(data), 3, 3))
                wd = np.empty((len(data), 3))
                for r in range(len(data)):
                    Rd[r], wd[r] = _chart_motion(A0, data[r, 1:4], data[r, 4:7])
                idx = np.rint((data[:, 0] - t_out[0]) / dto).astype(int)
                on_grid = (idx > i_good) & (idx < n_out) & \
                    (np.abs(t_out[np.clip(idx, 0, n_out - 1)] - data[:, 0]) <= 1e-6 * dto)
                Rs[idx[on_grid]], Ws[idx[on_grid]] = Rd[on_grid], wd[on_grid]
                Wk[idx[on_grid]] = data[on_grid, 7]
                if np.any(on_grid):
                    i_good = int(idx[on_grid][-1])
                t_c, R_c, w_c, W_c = float(data[-1, 0]), Rd[-1], wd[-1], float(data[-1, 7])
            if ex is not None or not adaptive or flag["kind"] is not None:
                break
        rhs_evals += flag["calls"]
        if status != "ok":
            break
        if ex is None and flag["kind"] == "chart":     # stopped by the post-step check
            ex = _Stop()
        if ex is None:
            if i_good < n_out - 1:                      # ran without error but fell short
                status, t_fail = "diverged", float(t_out[i_good + 1])
                reason = "exudyn run ended before t_end"
            break
        kind = flag["kind"]
        no_progress = no_progress + 1 if t_c <= t_start else 0
        if kind == "chart" and no_progress < 2 and charts < MAX_CHART_CHANGES:
            A0 = _new_chart(R_c)
            charts += 1
            continue
        status = "diverged"
        t_fail = float(flag["t"]) if flag["t"] is not None else float(t_c)
        if kind == "tilt":
            reason = _REASON_TILT
        elif kind == "nonfinite":
            reason = _REASON_NONFINITE
        elif kind == "chart":
            reason = ("Cardan chart lock persists after a chart change (state running away: "
                      "step too large?)" if no_progress >= 2 else "too many chart changes")
        else:
            msg = str(ex).strip().splitlines()
            reason = "exudyn: " + (msg[0] if msg else type(ex).__name__)
        break

    wall = time.perf_counter() - wall0
    last = i_good if status != "ok" else n_out - 1
    Rs[last + 1:], Ws[last + 1:], Wk[last + 1:] = np.nan, np.nan, np.nan
    ch = physics.channels(params, Rs, Ws, Wk)
    quat = np.full((n_out, 4), np.nan)
    quat[: last + 1] = _quaternions(Rs[: last + 1])
    used["chart_changes"] = charts
    return LeafResult(channels=ch, status=status, t_fail=t_fail, reason=reason,
                      stats={"steps": int(steps), "rhs_evals": int(rhs_evals),
                             "integrate_s": wall}, settings=used,
                      extra={"orientation": quat, "angular_velocity": Ws.copy()})


# ----------------------------------------------------------------------------------------------
# whirl frequencies

def _linearised(model, spin):
    """M, K, D of the tree at tilt 0 spinning at `spin` (rad/s) about e_z."""
    mbs = model["mbs"]
    mbs.systemData.SetODE2Coordinates([0.0, 0.0, 0.0], exu.ConfigurationType.Initial)
    mbs.systemData.SetODE2Coordinates_t([0.0, 0.0, float(spin)], exu.ConfigurationType.Initial)
    out = mbs.ComputeLinearizedSystem()
    return [np.asarray(x, float) for x in out[:3]]


def _whirl_pair(M, K, D, spin):
    """Two whirl frequencies (rad/s) and their labels from the quadratic eigenproblem."""
    n = M.shape[0]
    Minv = np.linalg.inv(M)
    Acal = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ K, -Minv @ D]])
    lam, V = np.linalg.eig(Acal)
    w = lam.imag
    sel = np.where(w > 1e-6 * max(1.0, np.max(np.abs(lam))))[0]
    pairs = []
    for i in sel:
        X, Y = V[0, i], V[1, i]           # q0 ~ tilt about x, q1 ~ tilt about y
        # n ≈ (q1, −q0): sense of the whirl of n about +z for the motion Re(v e^{iwt})
        nx, ny = Y, -X
        sense = w[i] * np.imag(nx * np.conj(ny))
        pairs.append((w[i], sense, lam[i].real))
    pairs.sort(key=lambda p: p[0])
    if len(pairs) != 2:
        raise ValueError(f"the upright rotor is not a stable whirl at spin {spin:g} rad/s "
                         f"({len(pairs)} oscillatory modes; is k <= m g l?)")
    if abs(spin) < 1e-12:
        labels = ["backward whirl", "forward whirl"]
    else:
        labels = ["forward whirl" if p[1] * spin > 0 else "backward whirl" for p in pairs]
    return [p[0] for p in pairs], labels, [p[2] for p in pairs]


def _modes_model(params):
    ph = _physical(params)
    return _build(ph, np.eye(3), np.zeros(3), np.zeros(3), 0.0, torque=0.0,
                  with_work=False, stop_checks=False)


def modes(params, settings=None):
    """Linearised whirl frequencies (Hz) at steady spin params['spin'] about the upright axis."""
    spin = float(params["spin"])
    model = _modes_model(params)
    M, K, D = _linearised(model, spin)
    w, labels, re = _whirl_pair(M, K, D, spin)
    re = np.asarray(re, float)
    return LeafModes(frequencies_hz=np.array(w) / (2 * math.pi), labels=labels,
                     damping=-re / np.hypot(re, w),           # ζ = −Re λ / |λ|
                     whirl=[lb.split()[0] for lb in labels],
                     extra={"max_re_per_s": float(np.max(re))},
                     settings={"method": "exudyn ComputeLinearizedSystem + dense quadratic "
                                         "eigenproblem", "drive_torque": 0.0},
                     notes=_approximate_note(params))


def whirl_sweep(params, spins):
    """Backward and forward whirl frequencies (rad/s) over an array of spins, one model reused."""
    model = _modes_model(params)
    spins = np.asarray(spins, dtype=float)
    bw = np.empty(len(spins))
    fw = np.empty(len(spins))
    for i, sp in enumerate(spins):
        M, K, D = _linearised(model, sp)
        w, labels, _ = _whirl_pair(M, K, D, sp)
        if sp == 0.0:
            bw[i], fw[i] = w
        else:
            fw[i] = w[labels.index("forward whirl")]
            bw[i] = w[labels.index("backward whirl")]
    return bw, fw


def _approximate_note(params):
    if params["spin"] != 0 and params["eccentricity"] != 0:
        return ["approximate: steady spin is no equilibrium of an eccentric rotor"]
    return []
