"""Exudyn reference model of the spin-up rotor (scenes `rotor-spinup` and `rotor-whirl`).

The rotor (massless shaft of length l on a spherical joint at O, eccentric disk at its end) is an
`ObjectKinematicTree` gimbal: three revolute joints X -> Y -> Z in one chain, the first two links
massless, the disk on the third. With the chart rotation A0 (see below) the body rotation is

    R = A0 · Rx(q0) · Ry(q1) · Rz(q2),

and the spatial angular velocity is ω = J(q)·q̇ with the columns A0·e_x, A0·Rx·e_y, R·e_z.

Loads (all in the tree's `forceUserFunction`, as generalised forces Jᵀτ of a spatial moment τ;
the kernel `_loads`):
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

Speed. Exudyn calls Python once per stage for the loads and once for the work rate; with
plain Python bodies those calls were the cost (10 s spin-up, RK67 at 2 ms: 570–620 ms of CPU on
2 busy cores, of which the tree's own C++ is 61–79 ms, measured without any user function).
The bodies are compiled kernels (`_loads`, `_work_rates`, numba) that take every rotor of a
tree at once: alone 286 ms; several rotors as branches of one tree (`regimes`, the map's
batch path) share each call — 111 ms a rotor at 8 per tree. `EXUDYN_MODULE=fast` (Exudyn
without range checks, chosen at import for the whole process) took 8 per tree from 120 to
101 ms (its numbers not compared); it is left to the user (an indexing fault would then
crash instead of raising).
Tried and not taken:
(a) the loads and the work rate as Exudyn symbolic user functions (C++ expression trees; the
work as the velocity of an extra ODE2 coordinate in an `ObjectGenericODE2` spanning the
tree's coordinates, the checks moved to a per-step post-step function): same numbers to all
digits but 478 ms against 392 ms at dt = 0.002 — the expression trees are interpreted;
(b) the fast module for one rotor alone: no difference in the noise; (c) the
tree's built-in joint springs (`jointPControlVector`) are C++ but are the Cardan spring
½k(α²+β²), a different model (|ω(10 s)| moves by 0.3 rad/s, see the notes); (d) one
`ObjectGenericODE2` carrying the loads of many single-rotor trees: its mass matrix cannot be
inverted per body, and the sparse solver it then needs costs more than it saves (155 ms a
rotor at 128); (e) one system reused across points with its parameters updated instead of
rebuilt: building the tree costs 0.4 ms of a 100–300 ms run.
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
import numba as nb
import numpy as np
from exudyn.itemInterface import (
    NodeGenericODE1,
    NodeGenericODE2,
    ObjectGenericODE1,
    ObjectKinematicTree,
    SensorNode,
)

from compare.contract import LeafModes, LeafResult, merge_settings
from compare.physics import eigen
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
# a map point's first look (compare/leafinfo.py `cheaper`): 5× the accurate step, the output
# step; |λ dt| ≤ 0.6 on the rotor map (tilt ~41 rad/s, spin ≤ 56 rad/s), well inside RK67's
# stability region. Measured (`xval bench rotor-spinup --points 200 --solver exudyn`): 0 of
# 200 labels differ from the all-accurate grid, 19.5 % rerun accurate, 4.4 → 9.9 points/s
CHEAP_DT = {"rk67": 1e-2}

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


@nb.njit(cache=True)
def _motion_rows(A0, q, qd, R, w):
    """Rows of R = A0·Rx(q0)·Ry(q1)·Rz(q2) and ω = J q̇, J = [A0 e_x, A0 Rx e_y, R e_z]."""
    for r in range(q.shape[0]):
        ca, sa = math.cos(q[r, 0]), math.sin(q[r, 0])
        cb, sb = math.cos(q[r, 1]), math.sin(q[r, 1])
        cc, sc = math.cos(q[r, 2]), math.sin(q[r, 2])
        for i in range(3):
            x1 = ca * A0[i, 1] + sa * A0[i, 2]          # (A0 Rx) e_y
            x2 = -sa * A0[i, 1] + ca * A0[i, 2]         # (A0 Rx) e_z
            y0 = cb * A0[i, 0] - sb * x2                # (A0 Rx Ry) e_x
            y2 = sb * A0[i, 0] + cb * x2                # (A0 Rx Ry) e_z = R e_z
            R[r, i, 0] = cc * y0 + sc * x1
            R[r, i, 1] = -sc * y0 + cc * x1
            R[r, i, 2] = y2
            w[r, i] = A0[i, 0] * qd[r, 0] + x1 * qd[r, 1] + y2 * qd[r, 2]


def _chart_motion(A0, q, qd):
    """Body rotations R (n, 3, 3) and spatial angular velocities ω (n, 3) from rows of Cardan
    coordinates q, rates qd (n, 3) in chart A0."""
    q, qd = np.atleast_2d(q).astype(float), np.atleast_2d(qd).astype(float)
    R, w = np.empty((len(q), 3, 3)), np.empty((len(q), 3))
    _motion_rows(np.ascontiguousarray(A0, float), q, qd, R, w)
    return R, w


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

_OK, _NONFINITE, _TILT, _LOCK = 0, 1, 2, 3
_STOP_KINDS = {_NONFINITE: "nonfinite", _TILT: "tilt", _LOCK: "chart"}


@nb.njit(cache=True)
def _loads(q, qd, A, k, c_ext, c_int, torque, checks, out):
    """Generalised forces Jᵀτ, τ = −kγ + torque·e_z and the dampers c_ext, c_int, of every
    rotor i of a tree (coordinates 3i…3i+2, chart A[i]) into `out`; with `checks`, the first
    rotor whose stage state is non-finite, at tilt π or near its chart's lock stops it:
    returns (kind, i), else (0, -1). `_work_rates` repeats the axes' z row on purpose: a work
    rate needs that row alone, once per stage."""
    for i in range(k.shape[0]):
        j = 3 * i
        a = A[i]
        ca, sa = math.cos(q[j]), math.sin(q[j])
        cb, sb = math.cos(q[j + 1]), math.sin(q[j + 1])
        # joint axes in the chart frame: e_x, Rx e_y, Rx Ry e_z = n; then rotated by A0
        j1x = a[0, 1] * ca + a[0, 2] * sa
        j1y = a[1, 1] * ca + a[1, 2] * sa
        j1z = a[2, 1] * ca + a[2, 2] * sa
        u0, u1, u2 = sb, -sa * cb, ca * cb
        nx = a[0, 0] * u0 + a[0, 1] * u1 + a[0, 2] * u2
        ny = a[1, 0] * u0 + a[1, 1] * u1 + a[1, 2] * u2
        nz = a[2, 0] * u0 + a[2, 1] * u1 + a[2, 2] * u2
        if checks:
            if not (math.isfinite(q[j] + q[j + 1] + q[j + 2])
                    and math.isfinite(qd[j] + qd[j + 1] + qd[j + 2])):
                return _NONFINITE, i
            if nz < _COS_TILT_LIMIT:
                return _TILT, i
            if abs(cb) < CHART_LOCK:                    # hard guard inside a stage
                return _LOCK, i
        s = math.sqrt(nx * nx + ny * ny)
        th = math.atan2(s, nz)
        f = th / s if s > 1e-6 else 1.0 + th * th / 6.0    # θ/sinθ, no 0/0 at θ = 0
        # τ = −k·θ/sinθ·(e_z × n) + torque·e_z
        tx = k[i] * f * ny
        ty = -k[i] * f * nx
        tz = torque[i]
        if c_ext[i] != 0.0 or c_int[i] != 0.0:
            # ω = J q̇; external damper: −c_ext (ω − (ω·n) n) = −c_ext n × ṅ, against the axis'
            # motion in the fixed frame; internal: a damper between the rotor and a hub spinning
            # with it about the fixed z axis, −c_int (ω_x, ω_y, 0) (to first order the tilt
            # rate seen in the rotor's frame, θ̇ − iΩθ)
            wx = a[0, 0] * qd[j] + j1x * qd[j + 1] + nx * qd[j + 2]
            wy = a[1, 0] * qd[j] + j1y * qd[j + 1] + ny * qd[j + 2]
            wz = a[2, 0] * qd[j] + j1z * qd[j + 1] + nz * qd[j + 2]
            wn = wx * nx + wy * ny + wz * nz
            tx -= c_ext[i] * (wx - wn * nx) + c_int[i] * wx
            ty -= c_ext[i] * (wy - wn * ny) + c_int[i] * wy
            tz -= c_ext[i] * (wz - wn * nz)
        out[j] = tx * a[0, 0] + ty * a[1, 0] + tz * a[2, 0]
        out[j + 1] = tx * j1x + ty * j1y + tz * j1z
        out[j + 2] = tx * nx + ty * ny + tz * nz
    return _OK, -1


@nb.njit(cache=True)
def _work_rates(q, qd, A, torque, out):
    """torque·ω_z of every rotor of a tree: ω_z = (J q̇)_z at the stage state."""
    for i in range(torque.shape[0]):
        j = 3 * i
        a = A[i]
        ca, sa = math.cos(q[j]), math.sin(q[j])
        cb, sb = math.cos(q[j + 1]), math.sin(q[j + 1])
        j1z = a[2, 1] * ca + a[2, 2] * sa
        nz = a[2, 0] * sb - a[2, 1] * sa * cb + a[2, 2] * ca * cb
        out[i] = torque[i] * (a[2, 0] * qd[j] + j1z * qd[j + 1] + nz * qd[j + 2])


def _build(rotors, with_work=True, stop_checks=True, chart_stop=True):
    """One kinematic tree holding every rotor of `rotors` as its own branch (a gimbal X → Y → Z,
    the first two links massless), each a dict with ph (the model's numbers; every rotor of a
    tree has one gravity), A0, q0, qd0, w0, torque. A tree of n rotors is n independent
    systems in one: its mass matrix is block diagonal, and the dense LU of a block-diagonal
    matrix does, block by block, the arithmetic of each block alone (the off-block entries are
    exact zeros), so each rotor's numbers are those of its run alone, bit for bit (tests).
    Loads and work rates are one compiled call per stage for the whole tree. `chart_stop`: a
    completed step with |cos q1| < CHART_SWITCH stops the run (a post-step function; off,
    the caller reads it off the stored steps)."""
    n = len(rotors)
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    nq = mbs.AddNode(NodeGenericODE2(
        referenceCoordinates=[0.0] * 3 * n,
        initialCoordinates=[float(x) for r in rotors for x in r["q0"]],
        initialCoordinates_t=[float(x) for r in rotors for x in r["qd0"]],
        numberOfODE2Coordinates=3 * n))
    A = np.ascontiguousarray([r["A0"] for r in rotors], dtype=float)
    k = np.array([r["ph"]["k"] for r in rotors], float)
    c_ext = np.array([r["ph"].get("c_ext", 0.0) for r in rotors], float)
    c_int = np.array([r["ph"].get("c_int", 0.0) for r in rotors], float)
    torque = np.array([r["torque"] for r in rotors], float)
    forces = np.zeros(3 * n)
    flag = {"kind": None, "t": None, "rotor": None, "calls": 0}

    def force(mbs_, t, itemNumber, q, q_t):
        flag["calls"] += 1
        kind, i = _loads(np.array(q), np.array(q_t), A, k, c_ext, c_int, torque, stop_checks,
                         forces)
        if kind:
            flag["kind"], flag["t"], flag["rotor"] = _STOP_KINDS[kind], t, i
            raise _Stop()
        return forces

    Z = np.zeros((3, 3))
    I3 = np.eye(3)
    mbs.AddObject(ObjectKinematicTree(
        nodeNumber=nq,
        jointTypes=[exu.JointType.RevoluteX, exu.JointType.RevoluteY,
                    exu.JointType.RevoluteZ] * n,
        linkParents=[p for i in range(n) for p in (-1, 3 * i, 3 * i + 1)],
        jointTransformations=exu.Matrix3DList([m for a in A for m in (a, I3, I3)]),
        jointOffsets=exu.Vector3DList([[0.0, 0.0, 0.0]] * 3 * n),
        linkInertiasCOM=exu.Matrix3DList([m for r in rotors for m in (Z, Z, r["ph"]["I_c"])]),
        linkCOMs=exu.Vector3DList([c for r in rotors for c in
                                   ([0.0, 0.0, 0.0], [0.0, 0.0, 0.0], list(r["ph"]["rc0"]))]),
        linkMasses=[mass for r in rotors for mass in (0.0, 0.0, r["ph"]["m"])],
        gravity=[float(x) for x in rotors[0]["ph"]["g"]],
        forceUserFunction=force))
    items = {"mbs": mbs, "SC": SC, "nq": nq, "flag": flag, "n": n}
    if with_work:
        nw = mbs.AddNode(NodeGenericODE1(referenceCoordinates=[0.0] * n,
                                         initialCoordinates=[float(r["w0"]) for r in rotors],
                                         numberOfODE1Coordinates=n))
        sysdata = mbs.systemData
        cur = exu.ConfigurationType.Current
        rates = np.zeros(n)

        def work_rate(mbs_, t, itemNumber, w):
            # the ODE1 right-hand side is evaluated at the stage state the solver is evaluating
            _work_rates(sysdata.GetODE2Coordinates(cur), sysdata.GetODE2Coordinates_t(cur), A,
                        torque, rates)
            return rates

        mbs.AddObject(ObjectGenericODE1(nodeNumbers=[nw], rhsUserFunction=work_rate))

        if stop_checks and chart_stop:
            def post_step(mbs_, t):
                # completed step: leave the chart well before its lock (restart happens outside)
                c = np.abs(np.cos(sysdata.GetODE2Coordinates(cur)[1::3]))
                if np.any(c < CHART_SWITCH):
                    flag["kind"], flag["t"] = "chart", t
                    flag["rotor"] = int(np.argmax(c < CHART_SWITCH))
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


def _stored(model):
    """The stored rows of a tree's run: times (r,), q and q̇ (r, n, 3), work (r, n)."""
    rows = [np.atleast_2d(model["mbs"].GetSensorStoredData(model[k])) for k in ("sq", "sv", "sw")]
    m, n = min(len(r) for r in rows), model["n"]
    if not m or rows[0].shape[1] < 2:
        return np.empty(0), np.empty((0, n, 3)), np.empty((0, n, 3)), np.empty((0, n))
    return (rows[0][:m, 0], rows[0][:m, 1:].reshape(m, n, 3), rows[1][:m, 1:].reshape(m, n, 3),
            rows[2][:m, 1:1 + n])


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


def _fixed_step(dto, dt):
    """The largest step ≤ dt that divides the output step."""
    return dto / int(math.ceil(dto / dt - 1e-9))


def _on_grid(tt, t_out, i_good):
    """Output-grid index of each stored time and which of them are new samples on the grid."""
    n_out = len(t_out)
    dto = float(t_out[1] - t_out[0]) if n_out > 1 else 1.0
    idx = np.rint((tt - t_out[0]) / dto).astype(int)
    on_grid = (idx > i_good) & (idx < n_out) & \
        (np.abs(t_out[np.clip(idx, 0, n_out - 1)] - tt) <= 1e-6 * dto)
    return idx, on_grid


def _start(params):
    """The initial rows (R, ω, work) and the rotor's Cardan coordinates in the first chart."""
    R0 = _rx(float(params["tilt0"]))
    w0 = float(params["spin0"]) * R0[:, 2]
    return R0, w0, _chart_coordinates(np.eye(3), R0, w0)


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
        h = _fixed_step(dto, dt)
        used["dt"] = h
        if abs(h - dt) > 1e-12 * dt:
            used["dt_requested"] = dt
    if name == "generalized_alpha":
        used["spectral_radius"] = float(s["spectral_radius"])

    Rs = np.full((n_out, 3, 3), np.nan)
    Ws = np.full((n_out, 3), np.nan)
    Wk = np.full(n_out, np.nan)
    Rs[0], Ws[0], _ = _start(params)
    Wk[0] = 0.0

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
        model = _build([{"ph": ph, "A0": A0, "q0": q0, "qd0": qd0, "w0": W_c,
                         "torque": float(params["torque"])}])
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
            tt, q, qd, w = _stored(model)
            keep = tt > t_c + 1e-12 * max(1.0, t_c)
            tt, q, qd, w = tt[keep], q[keep, 0], qd[keep, 0], w[keep, 0]
            fin = np.isfinite(q).all(axis=1) & np.isfinite(qd).all(axis=1) & np.isfinite(w)
            if not np.all(fin):
                first = int(np.argmin(fin))
                flag["kind"], flag["t"] = "nonfinite", float(tt[first])
                tt, q, qd, w = tt[:first], q[:first], qd[:first], w[:first]
                ex = ex or _Stop()
            if len(tt):
                Rd, wd = _chart_motion(A0, q, qd)
                idx, on_grid = _on_grid(tt, t_out, i_good)
                Rs[idx[on_grid]], Ws[idx[on_grid]], Wk[idx[on_grid]] = \
                    Rd[on_grid], wd[on_grid], w[on_grid]
                if np.any(on_grid):
                    i_good = int(idx[on_grid][-1])
                t_c, R_c, w_c, W_c = float(tt[-1]), Rd[-1], wd[-1], float(w[-1])
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
# the map's batch path

TREE_SIZE = 8          # rotors per tree in `regimes` (measured in its note)
_TOGETHER = ("rk4", "rk67", "explicit_euler")   # fixed-step explicit: no system-wide decision


def _together(params_list, t_out, s):
    """Fixed-step runs of rotors with one gravity, all in one tree from 0 to t_end, as each
    would run alone in `simulate` (same step, same start, same arithmetic per rotor): rows
    (R, ω, work) on t_out per rotor. A rotor whose run would stop (a chart change, tilt π, a
    non-finite state: `simulate` goes on or ends there on its own) stops the whole tree; it
    is left out (None: `simulate` runs it alone) and, where it stopped the tree (any stop
    but a change of chart, which is read off the stored steps), the others run again from
    t = 0."""
    n_out = len(t_out)
    dto = float(t_out[1] - t_out[0])
    h = _fixed_step(dto, float(s["dt"]))
    n_steps = max(1, int(round(t_out[-1] / h)))
    starts = [_start(p) for p in params_list]
    out, todo = [None] * len(params_list), list(range(len(params_list)))
    while todo:
        model = _build([{"ph": _physical(params_list[i]), "A0": np.eye(3),
                         "q0": starts[i][2][0], "qd0": starts[i][2][1], "w0": 0.0,
                         "torque": float(params_list[i]["torque"])} for i in todo],
                       chart_stop=False)
        ex = _solve(model["mbs"], _sim_settings(0.0, t_out[-1], n_steps, 0.0, s["integrator"],
                                                s["rtol"], s["spectral_radius"]),
                    _SOLVERS[s["integrator"]])
        if ex is not None or model["flag"]["kind"] is not None:
            stopped = model["flag"]["rotor"]          # None: Exudyn's own error, unassigned
            todo = [i for j, i in enumerate(todo) if stopped is not None and j != stopped]
            continue
        tt, q, qd, w = _stored(model)
        keep = tt > 0.0
        tt, q, qd, w = tt[keep], q[keep], qd[keep], w[keep]
        idx, on_grid = _on_grid(tt, t_out, 0)
        if not np.array_equal(idx[on_grid], np.arange(1, n_out)):
            break                                     # fell short: every rotor runs alone
        bad = ~(np.isfinite(q).all(axis=(0, 2)) & np.isfinite(qd).all(axis=(0, 2))
                & np.isfinite(w).all(axis=0))
        if bad.any():           # a last step gone non-finite (after the checks of its stages)
            todo = [i for j, i in enumerate(todo) if not bad[j]]
            continue
        # a step `simulate` would have ended for a change of chart: that rotor runs alone (the
        # others' runs stand: they never read it)
        charted = np.any(np.abs(np.cos(q[:, :, 1])) < CHART_SWITCH, axis=0)
        for j, i in enumerate(todo):
            if charted[j]:
                continue
            R, om = _chart_motion(np.eye(3), q[on_grid, j], qd[on_grid, j])
            out[i] = (np.concatenate([starts[i][0][None], R]),
                      np.concatenate([starts[i][1][None], om]),
                      np.concatenate([[0.0], w[on_grid, j]]))
        break
    return out


def regimes(params_list, t_out, settings, channel, levels, window):
    """The map's batch path: the points run `TREE_SIZE` at a time in one kinematic tree
    (`_together`: each rotor's numbers are its `simulate` run's, bit for bit), reduced to the
    regime on |ω| by `physics.regime_summaries`; a rotor left out has code 1 (the caller runs
    it alone). None where runs cannot share a tree: another channel, an error-controlled or
    implicit integrator (their step or Newton decisions are system-wide), a step longer than
    the output step (`_coarse`). Measured (10 s spin-up, RK67 at 2 ms, 2 busy cores, CPU
    time a rotor): 1, 4, 8, 16, 32 per tree 286, 132, 111, 113, 150 ms (the dense LU of the
    tree's mass matrix grows as n³) — against 61–79 ms for the tree's own C++ without any
    Python call; the Python loads before 570–620 ms."""
    t_out = np.asarray(t_out, dtype=float)
    s = check_settings(settings, t_out)
    if channel != "omega_norm" or s["integrator"] not in _TOGETHER or len(t_out) < 2 or \
            float(s["dt"]) > (t_out[1] - t_out[0]) * (1 + 1e-9):
        return None
    by_gravity = {}
    for i, p in enumerate(params_list):
        by_gravity.setdefault(tuple(np.asarray(p["gravity"], float).tolist()), []).append(i)
    runs = [None] * len(params_list)
    for members in by_gravity.values():
        for c in range(0, len(members), TREE_SIZE):
            idx = members[c:c + TREE_SIZE]
            for i, rows in zip(idx, _together([params_list[i] for i in idx], t_out, s)):
                runs[i] = (LeafResult(channels={}, status="diverged", t_fail=float("nan"))
                           if rows is None else
                           LeafResult(channels=physics.channels(params_list[i], *rows)))
    levels = np.asarray(levels, float)
    return physics.regime_summaries(t_out, runs, levels[:, 0], levels[:, 1], window)


# ----------------------------------------------------------------------------------------------
# whirl frequencies

FD_VARY = 10.0      # Exudyn's finite-difference step × this: the linearisation's own error


def _linearised(model, spin, fd_scale=1.0):
    """M, K, D of the tree at tilt 0 spinning at `spin` (rad/s) about e_z; `fd_scale` ×
    Exudyn's finite-difference step."""
    mbs = model["mbs"]
    mbs.systemData.SetODE2Coordinates([0.0, 0.0, 0.0], exu.ConfigurationType.Initial)
    mbs.systemData.SetODE2Coordinates_t([0.0, 0.0, float(spin)], exu.ConfigurationType.Initial)
    ss = exu.SimulationSettings()
    ss.staticSolver.newton.numericalDifferentiation.relativeEpsilon *= fd_scale
    out = mbs.ComputeLinearizedSystem(ss)
    return [np.asarray(x, float) for x in out[:3]]


def _state_matrix(M, K, D):
    n = M.shape[0]
    Minv = np.linalg.inv(M)
    return np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ K, -Minv @ D]])


def _whirl_pair(M, K, D, spin):
    """Two whirl frequencies (rad/s) and their labels from the quadratic eigenproblem."""
    lam, V = np.linalg.eig(_state_matrix(M, K, D))
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
    return _build([{"ph": _physical(params), "A0": np.eye(3), "q0": np.zeros(3),
                    "qd0": np.zeros(3), "w0": 0.0, "torque": 0.0}],
                  with_work=False, stop_checks=False)


def modes(params, settings=None):
    """Linearised whirl frequencies (Hz) at steady spin params['spin'] about the upright axis."""
    spin = float(params["spin"])
    model = _modes_model(params)
    M, K, D = _linearised(model, spin)
    w, labels, re = _whirl_pair(M, K, D, spin)
    re = np.asarray(re, float)
    # ζ's and the frequencies' errors: eigen round-off plus the change when the FD step is
    # varied, mode by mode
    A, A_varied = _state_matrix(M, K, D), _state_matrix(*_linearised(model, spin, FD_VARY))
    roots = re + 1j * np.asarray(w)
    z_err = eigen.root_zeta_errors(A, roots, A_varied)
    f_err = eigen.root_errors(A, roots, A_varied) / (2 * math.pi)
    return LeafModes(frequencies_hz=np.array(w) / (2 * math.pi), labels=labels,
                     damping=-re / np.hypot(re, w),           # ζ = −Re λ / |λ|
                     whirl=[lb.split()[0] for lb in labels],
                     extra={"max_re_per_s": float(np.max(re)),
                            "damping_error": z_err, "frequency_error_hz": f_err},
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


# ----------------------------------------------------------------------------------------------
# unbalance response

def _acceleration(params, phi, spin, h=1e-3):
    """q̈ of the tree at tilt 0, spin angle φ, spin rate Ω: one explicit Euler step of size h
    from q̇0 = (0, 0, Ω) gives q̇1 = q̇0 + h q̈(q0, q̇0), so (q̇1 − q̇0)/h is Exudyn's own
    acceleration (no cancellation in the transverse rows, where q̇0 is 0)."""
    model = _build([{"ph": _physical(params), "A0": np.eye(3), "q0": np.array([0.0, 0.0, phi]),
                     "qd0": np.array([0.0, 0.0, spin]), "w0": 0.0, "torque": 0.0}],
                   with_work=False, stop_checks=False)
    ex = _solve(model["mbs"], _sim_settings(0.0, h, 1, 0.0, "explicit_euler", 1e-10),
                _SOLVERS["explicit_euler"])
    if ex is not None:
        raise RuntimeError(f"exudyn: {ex}")
    v1 = np.asarray(model["mbs"].systemData.GetODE2Coordinates_t(exu.ConfigurationType.Current))
    return (v1 - np.array([0.0, 0.0, spin])) / h


def _unbalance_amplitudes(params, spins, he):
    """Forward tilt amplitudes a (θ ≈ q0 + i q1 = a e^{iΩt}: the first two Cardan angles are
    the fixed-frame tilt to first order) from M, K, D of `ComputeLinearizedSystem` and the
    unbalance input: d q̈/de by central differences (±he) of Exudyn's acceleration at spin
    angle φ. The input turns with the rotor, B(φ) = Re(b e^{iφ}), b = B(0) − i B(π/2); the
    steady q = Re(X e^{iΩt}) solves (K − Ω² M + iΩ D) X = M b e."""
    base = dict(params, eccentricity=0.0)
    model = _modes_model(base)
    out = []
    for spin in spins:
        M, K, D = _linearised(model, spin)
        B = [(_acceleration({**base, "eccentricity": he}, phi, spin)
              - _acceleration({**base, "eccentricity": -he}, phi, spin)) / (2 * he)
             for phi in (0.0, np.pi / 2)]
        X = np.linalg.solve(K - spin**2 * M + 1j * spin * D,
                            M @ (B[0] - 1j * B[1]) * params["eccentricity"])
        out.append((X[0] + 1j * X[1]) / 2)
    return np.array(out)


HE = 1e-7            # the eccentricity step of the input derivative, per unit l


def unbalance_response(params, spins):
    """(a, error) per spin (`_unbalance_amplitudes`); the error is the central differences'
    change from step 2he to he (4/3 of it; he = 1e-7 l: 1e-4 l left the O(he²) truncation,
    9.4e-9 relative, the closed form 9e-15 away at 1e-7 l), plus a few roundings."""
    he = HE * params["l"]
    a, a2 = _unbalance_amplitudes(params, spins, he), _unbalance_amplitudes(params, spins, 2 * he)
    return a, 4 / 3 * np.abs(a - a2) + 8 * np.finfo(float).eps * np.abs(a)
