"""Exudyn model of Andrews' squeezer (scene `andrews-squeezer`).

Seven `NodeRigidBody2D`/`ObjectRigidBody2D` bodies (node = centre of mass) placed from the
shared layout (compare.physics.andrews.body_layout / body_poses: the geometry the test set's
M(q) and g(q) encode), ten `RevoluteJoint2D` (O, P, B, A twice, G, H and three at E) — 21
coordinates, 20 constraints, an index-3 DAE solved by Exudyn's generalized-α (position-level
constraints: no drift) —, the spring c0 a `SpringDamper` between D on K3 and a ground marker at
C with reference length l0, and the motor torque `mom` a `LoadCoordinate` on K1's rotation
coordinate. Solved output interval by output interval (`SolveDynamic` with
`updateInitialValues=True`); the angles are read back from the body angles.
"""
from __future__ import annotations

import math

import exudyn as exu
import numpy as np
from exudyn import itemInterface as ii

from compare.contract import LeafResult, merge_settings
from compare.physics import andrews as phys

DEFAULT_SETTINGS = {"integrator": "generalized_alpha", "dt": 2e-6, "spectral_radius": 1.0,
                    "newton_tol": 1e-10, "newton_abs_tol": 1e-12}
INTEGRATORS = ("generalized_alpha", "trapezoidal")
BODIES = ("K1", "K2", "K3", "K4", "K5", "K6", "K7")


def check_settings(settings: dict | None, t_out: np.ndarray | None = None) -> dict:
    """The settings merged and checked before anything runs (ValueError with one line)."""
    s = merge_settings(settings, DEFAULT_SETTINGS, INTEGRATORS)
    s["dt"] = float(s["dt"])
    if not s["dt"] > 0:
        raise ValueError(f"dt must be > 0, got {s['dt']!r}")
    rho = float(s["spectral_radius"])
    if not 0.0 <= rho <= 1.0:
        raise ValueError(f"spectral_radius must be in [0, 1], got {rho!r}")
    s["spectral_radius"] = rho
    return s


def build(params: dict, s: dict):
    """(SystemContainer, mbs, {body: node}, simulation settings) at the test set's start."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddObject(ii.ObjectGround())
    lay = phys.body_layout(params)
    pose, _ = phys.body_poses(phys.initial_angles(params), params)
    nodes, bodies = {}, {}
    for k in BODIES:
        m, J, _ = lay[k]
        c, a = pose[k]
        nodes[k] = mbs.AddNode(ii.NodeRigidBody2D(referenceCoordinates=[c[0], c[1], a],
                                                  initialCoordinates=[0, 0, 0],
                                                  initialVelocities=[0, 0, 0]))
        bodies[k] = mbs.AddObject(ii.ObjectRigidBody2D(nodeNumber=nodes[k], mass=m, inertia=J))

    def marker(body, point):
        if body is None:
            x = phys.fixed_point(point, params)
            return mbs.AddMarker(ii.MarkerBodyPosition(bodyNumber=ground,
                                                       localPosition=[x[0], x[1], 0.0]))
        x = lay[body][2][point]
        return mbs.AddMarker(ii.MarkerBodyPosition(bodyNumber=bodies[body],
                                                   localPosition=[x[0], x[1], 0.0]))
    for b0, p0, b1, p1 in phys.JOINTS:
        mbs.AddObject(ii.RevoluteJoint2D(markerNumbers=[marker(b1, p1), marker(b0, p0)]))
    mbs.AddObject(ii.SpringDamper(markerNumbers=[marker(None, "C"), marker("K3", "D")],
                                  referenceLength=float(params["l0"]),
                                  stiffness=float(params["c0"]), damping=0.0))
    mk1 = mbs.AddMarker(ii.MarkerNodeCoordinate(nodeNumber=nodes["K1"], coordinate=2))
    mbs.AddLoad(ii.LoadCoordinate(markerNumber=mk1, load=float(params["mom"])))
    mbs.Assemble()

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
    return SC, mbs, nodes, ss


def _angles_and_rates(mbs, nodes, ref):
    sd = mbs.systemData
    C = exu.ConfigurationType.Current
    q = np.array(sd.GetODE2Coordinates(configuration=C)) + ref
    v = np.array(sd.GetODE2Coordinates_t(configuration=C))
    idx = [mbs.GetNodeODE2Index(nodes[k]) + 2 for k in BODIES]
    return phys.angles_from_bodies(q[idx]), phys.angles_from_bodies(v[idx])


def simulate(params: dict, t_out: np.ndarray, settings: dict | None = None) -> LeafResult:
    s = check_settings(settings)
    t_out = np.asarray(t_out, float)
    prev = exu.config.printToConsole
    exu.config.printToConsole = False
    n = len(t_out)
    Q, QD = np.full((n, 7), np.nan), np.full((n, 7), np.nan)
    steps, status, t_fail, reason = 0, "ok", None, None
    try:
        SC, mbs, nodes, ss = build(params, s)
        ref = np.array(mbs.systemData.GetODE2Coordinates(
            configuration=exu.ConfigurationType.Reference))
        Q[0], QD[0] = _angles_and_rates(mbs, nodes, ref)
        for i in range(1, n):
            t0, t1 = float(t_out[i - 1]), float(t_out[i])
            nst = max(1, int(math.ceil((t1 - t0) / s["dt"] - 1e-9)))
            ss.timeIntegration.startTime, ss.timeIntegration.endTime = t0, t1
            ss.timeIntegration.numberOfSteps = nst
            try:
                ok = mbs.SolveDynamic(ss, solverType=exu.DynamicSolverType.GeneralizedAlpha,
                                      updateInitialValues=True)
            except Exception as exc:      # exudyn.SolverError, RuntimeError
                why = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
                ok, reason = False, f"exudyn solver failed in [{t0:.6g}, {t1:.6g}]: {why}"
            if not ok:
                status, t_fail = "diverged", t0
                reason = reason or f"exudyn SolveDynamic returned False in [{t0:.6g}, {t1:.6g}]"
                break
            steps += nst
            Q[i], QD[i] = _angles_and_rates(mbs, nodes, ref)
            if not (np.all(np.isfinite(Q[i])) and np.all(np.isfinite(QD[i]))):
                status, t_fail, reason = "diverged", t1, "non-finite state"
                Q[i], QD[i] = np.nan, np.nan
                break
    finally:
        exu.config.printToConsole = prev
    used = {**s, "dt": float((t_out[1] - t_out[0]) / max(1, int(math.ceil(
        (t_out[1] - t_out[0]) / s["dt"] - 1e-9))))}
    return LeafResult(channels=phys.channels(Q, QD, phys.pack(params)), status=status,
                      t_fail=t_fail, reason=reason, stats={"steps": steps, "rhs_evals": -1},
                      settings=used)
