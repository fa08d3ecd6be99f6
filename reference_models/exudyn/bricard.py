"""Exudyn model of Bricard's mechanism (scene `bricard`).

Five `CreateRigidBody` rods (Euler-parameter nodes at the rods' centres, body axes = space axes
at the start; uniform square prisms of side a: m (L² + a²)/12 about the two transverse axes,
m a²/6 about their own, compare.physics.bricard.principal_inertia; a = 0: thin rods) under
gravity −g ŷ, and six revolute joints at the library's points and axes
(compare.physics.bricard.POINTS, AXES): five `CreateRevoluteJoint` (ground–rod 1, rod–rod) and
the loop's last, rod 5 to ground, a `CreateGenericJoint` that keeps the three positions and
only one of the two rotations a revolute joint fixes — the other is the redundant constraint
(Grübler's zero against the one degree of freedom): with it the constraint Jacobian is
singular and Exudyn's default solver stops ("matrix is not factorized"). Which one is
redundant is the one whose removal leaves `ComputeSystemDegreeOfFreedom` at one degree of
freedom and no redundancy (measured in tests/engines/test_bricard_engines.py). An index-3 DAE
solved by generalized-α (position-level constraints: no drift) output interval by output
interval; the joint angles and rates are read back from the bodies' rotations.
"""
from __future__ import annotations

import math

import exudyn as exu
import numpy as np
from exudyn.rigidBodyUtilities import RigidBodyInertia

from compare.contract import LeafResult, check_once
from compare.physics import bricard as phys

from .. import loop_common as lc

DEFAULT_SETTINGS = {"integrator": "generalized_alpha", "dt": 1e-3, "spectral_radius": 1.0,
                    "newton_tol": 1e-10, "newton_abs_tol": 1e-12}
INTEGRATORS = ("generalized_alpha", "trapezoidal")
# the loop's last joint (axis x at P5): constrained axes (x, y, z, rot x, rot y, rot z) in the
# space frame — rotation about x free (the joint), about z kept, about y the redundant one
CLOSING_AXES = [1, 1, 1, 0, 0, 1]


@check_once
def check_settings(settings: dict | None, t_out: np.ndarray | None = None) -> dict:
    """The settings merged and checked before anything runs (ValueError with one line)."""
    return lc.exudyn_settings(settings, DEFAULT_SETTINGS, INTEGRATORS)


def build(params: dict, s: dict, closing_axes=None):
    """(SystemContainer, mbs, [node per rod], simulation settings) at the library's start."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    m, L, g = (float(params[n]) for n in ("m", "L", "g"))
    i_t, i_a = phys.principal_inertia(phys.pack(params))
    ground = mbs.CreateGround(show=False)
    bodies, nodes = [], []
    for k in range(5):
        d = phys.POINTS[k + 1] - phys.POINTS[k]
        inertia = i_t * (np.eye(3) - np.outer(d, d)) + i_a * np.outer(d, d)
        b = mbs.CreateRigidBody(
            inertia=RigidBodyInertia(mass=m, inertiaTensor=inertia),
            referencePosition=list(0.5 * (phys.POINTS[k] + phys.POINTS[k + 1]) * L),
            nodeType=exu.NodeType.RotationEulerParameters, gravity=[0.0, -g, 0.0])
        bodies.append(b)
        nodes.append(mbs.GetObject(b)["nodeNumber"])
    pairs = [ground] + bodies + [ground]
    for j in range(5):
        mbs.CreateRevoluteJoint(itemNumbers=[pairs[j], pairs[j + 1]],
                                position=list(phys.POINTS[j] * L), axis=list(phys.AXES[j]),
                                useGlobalFrame=True, show=False)
    mbs.CreateGenericJoint(itemNumbers=[bodies[4], ground], position=list(phys.POINTS[5] * L),
                           constrainedAxes=list(closing_axes or CLOSING_AXES),
                           useGlobalFrame=True, show=False)
    mbs.Assemble()

    return SC, mbs, nodes, lc.ga_simulation_settings(s)


def joint_state(Rs, ws):
    """Joint angles q0…q4 and rates from the rods' rotations Rs (5, 3, 3) and angular velocities
    ws (5, 3) in space: R_{k+1} = R_k Rot(s_k, q_k) (R_0 = I, the ground), and
    q'_k = (R_k s_k)·(ω_{k+1} − ω_k)."""
    q, qd = np.zeros(6), np.zeros(6)
    R_prev, w_prev = np.eye(3), np.zeros(3)
    for k in range(5):
        rel = R_prev.T @ Rs[k]
        sin = 0.5 * np.array([rel[2, 1] - rel[1, 2], rel[0, 2] - rel[2, 0], rel[1, 0] - rel[0, 1]])
        q[k] = math.atan2(float(sin @ phys.AXES[k]), 0.5 * (np.trace(rel) - 1.0))
        qd[k] = float((R_prev @ phys.AXES[k]) @ (ws[k] - w_prev))
        R_prev, w_prev = Rs[k], ws[k]
    return q, qd


def _state(mbs, nodes):
    Rs = np.array([np.asarray(mbs.GetNodeOutput(n, exu.OutputVariableType.RotationMatrix))
                   .reshape(3, 3) for n in nodes])
    ws = np.array([mbs.GetNodeOutput(n, exu.OutputVariableType.AngularVelocity) for n in nodes])
    return joint_state(Rs, ws)


def simulate(params: dict, t_out: np.ndarray, settings: dict | None = None) -> LeafResult:
    s = check_settings(settings)
    t_out = np.asarray(t_out, float)
    Q, QD, steps, status, t_fail, reason, dt = lc.exudyn_solve(
        lambda: build(params, s), _state, t_out, s, 6)
    Q[:, :5] = np.unwrap(Q[:, :5], axis=0) if status == "ok" else Q[:, :5]
    used = {**s, "dt": dt}
    return LeafResult(channels=phys.channels(Q, QD, phys.pack(params)), status=status,
                      t_fail=t_fail, reason=reason, stats={"steps": steps, "rhs_evals": -1},
                      settings=used)
