"""Exudyn multibody model of the benchmark bicycle (`bicycle`): four rigid bodies (rear wheel,
rear frame with rider, front handlebar and fork, front wheel; Euler-parameter nodes, the
paper's inertias turned into Exudyn's z-up frame), revolute joints at the hubs and the steer
axis, and an ideal rolling-disc joint (`ObjectJointRollingDisc`: no slip, lateral, longitudinal
and normal) per wheel on the ground plane — the paper's Whipple model in full nonlinear form,
with none of its linearisation.

Its roots are not a linearisation (Exudyn does not linearise about a steady motion with
nonholonomic constraints) but a free response: the bicycle rolling upright at the scene's
speed, a roll torque pulse of 1e-3 N·m for 0.02 s on the rear frame, then lean and steer
sampled every `output_dt` and fitted together by a matrix pencil of four poles (weave pair,
capsize, castor; or four real roots at low speed). Lean starts at ~1e-7 rad; a growing motion
is cut where |lean| reaches 1e-5 rad (at rest, a cut at 1e-4 moved the decaying roots by
~9e-4 /s through the growing ones' nonlinear terms; at 1e-5, 1.5e-4).
Generalized-α (spectral radius 0.95) is second order: the error bar of each root is 4/3 of its
change from a run at twice the step, plus twice the fit's own floor (its change on half the record).
"""
from __future__ import annotations

import time

import exudyn as exu
import numpy as np
from exudyn import itemInterface as ii
from exudyn.rigidBodyUtilities import RigidBodyInertia

from compare.contract import LeafModes, merge_settings, require_positive

from .. import bicycle_common as common

MODES_SETTINGS = {"dt": 5e-4, "spectral_radius": 0.95, "record_s": 3.0, "output_dt": 0.01,
                  "newton_tol": 1e-12}


def free_response(p: dict, v: float, dt: float, record_s: float, output_dt: float,
                  rho: float, newton_tol: float):
    """(t, lean, steer, wall_s) after the pulse: the rear frame's roll and the steer angle
    about the steer axis (rad), every output_dt from the pulse's end."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    w, rR, rF = p["w"], p["r_R"], p["r_F"]
    gravity = [0.0, 0.0, -p["g"]]

    def body(m, inertia, pos, spin=0.0):
        return mbs.CreateRigidBody(
            inertia=RigidBodyInertia(mass=m, inertiaTensor=inertia), referencePosition=pos,
            initialVelocity=[v, 0.0, 0.0], initialAngularVelocity=[0.0, spin, 0.0],
            nodeType=exu.NodeType.RotationEulerParameters, gravity=gravity)

    inertia = common.tensor
    rear = body(p["m_R"], inertia(p["I_Rxx"], p["I_Ryy"], p["I_Rxx"], 0.0), [0, 0, rR], v / rR)
    frame = body(p["m_B"], inertia(p["I_Bxx"], p["I_Byy"], p["I_Bzz"], p["I_Bxz"]),
                 [p["x_B"], 0.0, -p["z_B"]])
    fork = body(p["m_H"], inertia(p["I_Hxx"], p["I_Hyy"], p["I_Hzz"], p["I_Hxz"]),
                [p["x_H"], 0.0, -p["z_H"]])
    front = body(p["m_F"], inertia(p["I_Fxx"], p["I_Fyy"], p["I_Fxx"], 0.0), [w, 0, rF], v / rF)
    axis, on_axis = common.steer_axis(p)
    for pair, at, ax in (([frame, rear], [0, 0, rR], [0, 1, 0]),
                         ([frame, fork], list(on_axis), list(axis)),
                         ([fork, front], [w, 0, rF], [0, 1, 0])):
        mbs.CreateRevoluteJoint(itemNumbers=pair, position=at, axis=ax, useGlobalFrame=True,
                                show=False)
    ground = mbs.AddMarker(ii.MarkerBodyRigid(bodyNumber=mbs.CreateGround(show=False)))
    for wheel, r in ((rear, rR), (front, rF)):
        m = mbs.AddMarker(ii.MarkerBodyRigid(bodyNumber=wheel))
        mbs.AddObject(ii.ObjectJointRollingDisc(markerNumbers=[ground, m], discRadius=r,
                                                discAxis=[0, 1, 0]))
    torque, t_pulse = common.PULSE
    mbs.AddLoad(ii.LoadTorqueVector(
        markerNumber=mbs.AddMarker(ii.MarkerBodyRigid(bodyNumber=frame)), bodyFixed=False,
        loadVector=[0, 0, 0],
        loadVectorUserFunction=lambda m_, t, load: [torque if t < t_pulse else 0.0, 0, 0]))
    sensors = [mbs.AddSensor(ii.SensorBody(bodyNumber=b, storeInternal=True, writeToFile=False,
                                           outputVariableType=exu.OutputVariableType.
                                           RotationMatrix)) for b in (frame, fork)]
    node = mbs.GetObject(frame)["nodeNumber"]

    def lean_ok(m_, t):        # stop a growing motion while it is still linear
        lean = m_.GetNodeOutput(node, exu.OutputVariableType.RotationMatrix)[7]
        return abs(lean) < common.LEAN_CUT
    mbs.SetPreStepUserFunction(lean_ok)
    mbs.Assemble()
    ss = exu.SimulationSettings()
    ti = ss.timeIntegration
    ti.endTime = t_pulse + record_s
    ti.numberOfSteps = int(round(ti.endTime / dt))
    ti.verboseMode = 0
    ti.adaptiveStep = False
    ti.newton.relativeTolerance = newton_tol
    ti.newton.absoluteTolerance = newton_tol * 1e-2
    ti.generalizedAlpha.spectralRadius = rho
    ti.generalizedAlpha.computeInitialAccelerations = True
    ss.solution.file.write = False
    ss.solution.sensors.writePeriod = output_dt
    t0 = time.perf_counter()
    mbs.SolveDynamic(ss)
    wall = time.perf_counter() - t0
    RB, RH = (mbs.GetSensorStoredData(s) for s in sensors)
    n = min(len(RB), len(RH))
    t = RB[:n, 0]
    RB, RH = RB[:n, 1:].reshape(-1, 3, 3), RH[:n, 1:].reshape(-1, 3, 3)
    lean = np.arcsin(RB[:, 2, 1])                  # R = Rz(ψ) Rx(φ) Ry(θ): R[2, 1] = sin φ
    rel = np.einsum("nji,njk->nik", RB, RH)        # the fork in the frame's axes
    sin_axis = 0.5 * np.stack([rel[:, 2, 1] - rel[:, 1, 2], rel[:, 0, 2] - rel[:, 2, 0],
                               rel[:, 1, 0] - rel[:, 0, 1]], axis=1)
    steer = np.arcsin(sin_axis @ axis)
    keep = (t >= t_pulse - 1e-12) & (np.abs(lean) < common.LEAN_CUT)
    return t[keep], lean[keep], steer[keep], wall


def modes(params: dict, settings: dict) -> LeafModes:
    s = merge_settings(settings, MODES_SETTINGS, ())
    require_positive(s, ("dt", "record_s", "output_dt", "newton_tol"))
    return common.fitted_modes(
        lambda p, v, dt: free_response(p, v, dt, s["record_s"], s["output_dt"],
                                       s["spectral_radius"], s["newton_tol"]),
        params, s, "roots fitted from a free response (matrix pencil on lean and steer): "
                   "no linearisation with nonholonomic constraints")
