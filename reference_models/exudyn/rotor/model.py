"""The engine model: one `ObjectKinematicTree` per run, built from the resolved parameters by
`build` (every path — time, batch, modes, response — goes through it), and the few calls
around Exudyn's solver.

Each rotor is a gimbal, three revolute joints X → Y → Z in one chain, the first two links
massless, the disk on the third (chart rotation A0: `chart`). Loads (the kernels' `loads`, as
generalised forces Jᵀτ of a spatial moment τ, in the tree's `forceUserFunction`):
- the transverse spring τ_s = −kγ, γ = θ·(e_z × n)/|e_z × n|, n = R·e_z, θ = angle(e_z, n); it
  is −∂/∂q of ½kθ², so exactly conservative, and has no component along n;
- the drive torque τ_d = torque·e_z, fixed in space. (`linkTorques` is not used: it acts with
  the opposite sign to its docstring, see the Exudyn notes.)
Gravity is the tree's built-in `gravity`. The work A = ∫ torque·ω_z dt is an extra first-order
coordinate (`ObjectGenericODE1`) integrated by the same Runge–Kutta stages as the mechanics.
A model is rebuilt rather than one system reused with its parameters updated: building the
tree costs 0.4 ms of a 100–300 ms run.
"""
import math

import exudyn as exu
import numpy as np
from exudyn.itemInterface import (
    NodeGenericODE1,
    NodeGenericODE2,
    ObjectGenericODE1,
    ObjectKinematicTree,
    SensorNode,
)

from compare.physics import rotor as physics

from .chart import CHART_SWITCH
from .kernels import STOP_KINDS, loads, work_rates
from .settings import ADAPTIVE


class Stop(Exception):
    """Raised inside a user function to end the Exudyn run (rechart / failure)."""


def physical(params):
    """The model's numbers, from the shared rotor constants (the scene validated them)."""
    c = physics.constants(params)
    return {"m": float(params["m"]), "k": float(params["k"]), "g": c["gravity"],
            "rc0": c["rc0"], "I_c": c["I_c"],
            "c_ext": float(params.get("c_ext", 0.0)), "c_int": float(params.get("c_int", 0.0))}


def rotor(params, A0=None, q0=None, qd0=None, w0=0.0, torque=0.0):
    """One branch of a tree for `build`: the rotor of `params` in chart A0 (default identity)
    at Cardan coordinates q0, rates qd0 (default 0), work w0, drive torque."""
    return {"ph": physical(params), "A0": np.eye(3) if A0 is None else A0,
            "q0": np.zeros(3) if q0 is None else q0, "qd0": np.zeros(3) if qd0 is None else qd0,
            "w0": w0, "torque": torque}


def upright(params):
    """The tree the linearisations use: upright, at rest, no drive torque, no work, no checks."""
    return build([rotor(params)], with_work=False, stop_checks=False)


def build(rotors, with_work=True, stop_checks=True, chart_stop=True):
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
        kind, i = loads(np.array(q), np.array(q_t), A, k, c_ext, c_int, torque, stop_checks,
                         forces)
        if kind:
            flag["kind"], flag["t"], flag["rotor"] = STOP_KINDS[kind], t, i
            raise Stop()
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
            work_rates(sysdata.GetODE2Coordinates(cur), sysdata.GetODE2Coordinates_t(cur), A,
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


def stored(model):
    """The stored rows of a tree's run: times (r,), q and q̇ (r, n, 3), work (r, n)."""
    rows = [np.atleast_2d(model["mbs"].GetSensorStoredData(model[k])) for k in ("sq", "sv", "sw")]
    m, n = min(len(r) for r in rows), model["n"]
    if not m or rows[0].shape[1] < 2:
        return np.empty(0), np.empty((0, n, 3)), np.empty((0, n, 3)), np.empty((0, n))
    return (rows[0][:m, 0], rows[0][:m, 1:].reshape(m, n, 3), rows[1][:m, 1:].reshape(m, n, 3),
            rows[2][:m, 1:1 + n])


def sim_settings(t0, t1, n_steps, write_period, name, rtol, spectral_radius=1.0, h0=None):
    ss = exu.SimulationSettings()
    ti = ss.timeIntegration
    ti.startTime = float(t0)
    ti.endTime = float(t1)
    ti.numberOfSteps = int(n_steps)
    ti.verboseMode = 0
    ti.explicit.useLieGroupIntegration = False     # no rotation nodes: plain RK on q
    ti.explicit.eliminateConstraints = False
    ti.explicit.computeEndOfStepAccelerations = False   # not needed: saves one RHS per step
    if name in ADAPTIVE:
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


def steps_of(mbs):
    dyn = mbs.sys.get("dynamicSolver") if hasattr(mbs, "sys") else None
    try:
        return int(dyn.it.currentStepIndex)
    except Exception:                               # noqa: BLE001 - stats are best effort
        return 0


def last_step_of(mbs, default):
    dyn = mbs.sys.get("dynamicSolver") if hasattr(mbs, "sys") else None
    try:
        it = dyn.it
        # the last step may be cut short to land on the interval end: take the mean step too
        h = max(float(it.currentStepSize),
                (float(it.endTime) - float(it.startTime)) / max(1, int(it.currentStepIndex)))
        return h if math.isfinite(h) and h > 0 else default
    except Exception:                               # noqa: BLE001
        return default


def solve(mbs, ss, solver, update=False):
    """SolveDynamic with Exudyn's console chatter off; returns the exception (or None)."""
    previous = exu.config.printToConsole
    exu.config.printToConsole = False
    try:
        mbs.SolveDynamic(ss, solverType=solver, storeSolver=True, updateInitialValues=update)
        return None
    except Exception as ex:                         # noqa: BLE001 - Stop, SolverError, ModelError
        return ex
    finally:
        exu.config.printToConsole = previous
