"""Exudyn leaf: an `ObjectKinematicTree` of two RevoluteZ joints in the x–y plane (minimal
coordinates, so the explicit solvers apply; angle θ from the downward vertical), massless links
with point masses at their ends, Exudyn's RK67 at a fixed step; sensors on the joint node at
every output sample."""
import time

import exudyn as exu
import numpy as np
from exudyn.itemInterface import NodeGenericODE2, ObjectKinematicTree, SensorNode

from compare.contract import LeafResult, merge_settings

from .scene import channels

SOLVER_TYPES = {"rk67": exu.DynamicSolverType.RK67, "rk4": exu.DynamicSolverType.RK44}
INTEGRATORS = tuple(SOLVER_TYPES)
DEFAULT_SETTINGS = {"integrator": "rk67", "dt": 1e-3}


def check_settings(settings, t_out=None):
    s = merge_settings(settings, DEFAULT_SETTINGS, INTEGRATORS)
    if not (isinstance(s["dt"], (int, float)) and s["dt"] > 0):
        raise ValueError(f"dt must be a positive number, got {s['dt']!r}")
    return s


def simulate(params, t_out, settings=None):
    s = check_settings(settings, t_out)
    p = params
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    q0 = [float(p["theta1_0"]), float(p["theta2_0"] - p["theta1_0"])]   # relative 2nd joint
    node = mbs.AddNode(NodeGenericODE2(referenceCoordinates=[0.0, 0.0], initialCoordinates=q0,
                                       initialCoordinates_t=[0.0, 0.0],
                                       numberOfODE2Coordinates=2))
    Z = np.zeros((3, 3))
    mbs.AddObject(ObjectKinematicTree(
        nodeNumber=node, jointTypes=[exu.JointType.RevoluteZ] * 2, linkParents=[-1, 0],
        jointTransformations=exu.Matrix3DList([np.eye(3)] * 2),
        jointOffsets=exu.Vector3DList([[0.0, 0.0, 0.0], [0.0, -float(p["l1"]), 0.0]]),
        linkInertiasCOM=exu.Matrix3DList([Z, Z]),
        linkCOMs=exu.Vector3DList([[0.0, -float(p["l1"]), 0.0], [0.0, -float(p["l2"]), 0.0]]),
        linkMasses=[float(p["m1"]), float(p["m2"])], gravity=[0.0, -float(p["g"]), 0.0]))
    kinds = (exu.OutputVariableType.Coordinates, exu.OutputVariableType.Coordinates_t)
    sensors = [mbs.AddSensor(SensorNode(nodeNumber=node, storeInternal=True, writeToFile=False,
                                        outputVariableType=k)) for k in kinds]
    mbs.Assemble()
    ss = exu.SimulationSettings()
    ti = ss.timeIntegration
    ti.endTime = float(t_out[-1])
    ti.numberOfSteps = int(round(t_out[-1] / s["dt"]))
    ti.verboseMode = 0
    ti.automaticStepSize = False
    ss.solution.file.write = False
    ss.solution.sensors.writePeriod = float(t_out[1] - t_out[0])
    ss.show.computationTime = False
    t0 = time.perf_counter()
    status, t_fail, reason = "ok", None, None
    try:
        mbs.SolveDynamic(ss, solverType=SOLVER_TYPES[s["integrator"]])
    except exu.SolverError as e:                      # recorded, never raised
        status, reason = "diverged", f"exudyn: {str(e).splitlines()[0]}"
    wall = time.perf_counter() - t0
    q, qd = (np.atleast_2d(mbs.GetSensorStoredData(k)) for k in sensors)
    idx = np.rint(q[:, 0] / (t_out[1] - t_out[0])).astype(int)     # samples onto the grid
    keep = (idx >= 0) & (idx < len(t_out))
    Y = np.full((len(t_out), 4), np.nan)
    Y[idx[keep], :2], Y[idx[keep], 2:] = q[keep, 1:3], qd[keep, 1:3]
    if status != "ok" or not np.all(np.isfinite(Y)):
        bad = int(np.argmin(np.all(np.isfinite(Y), axis=1)))
        status, t_fail = "diverged", float(t_out[bad])
        reason = reason or "non-finite or missing samples"
        Y[bad:] = np.nan
    return LeafResult(channels=channels(p, Y[:, 0], Y[:, 0] + Y[:, 1], Y[:, 2],
                                        Y[:, 2] + Y[:, 3]),
                      stats={"steps": ti.numberOfSteps, "rhs_evals": -1, "integrate_s": wall},
                      settings=s, status=status, t_fail=t_fail, reason=reason)
