"""Exudyn model of the N four-bar mechanism (scene `n-four-bar`).

2N + 1 planar rigid bodies (`NodeRigidBody2D`/`ObjectRigidBody2D`, node at the rod's centre,
m L²/12 about it; gravity −g ŷ as `LoadMassProportional`): cranks 0 … N and couplers 0 … N−1
at the library's start (every crank at φ0, the couplers level, the velocities of the rigid
mechanism with B_k's horizontal velocity vx0), joined by `RevoluteJoint2D`s: crank k to the
ground at (kL, 0), crank k's tip to coupler k's start, coupler k's end to crank k+1's tip.
6N + 3 coordinates, 6N + 2 constraint equations, independent away from the singular positions
(one degree of freedom); where every rod is horizontal the constraint Jacobian loses N in rank
and the solver works on a near-singular iteration matrix there. An index-3 DAE solved by
generalized-α (position-level constraints: no drift) output interval by output interval with
the sparse linear solver; the crank and coupler angles and rates are the nodes' rotation
coordinates.
"""
from __future__ import annotations

import math

import exudyn as exu
import numpy as np
from exudyn import itemInterface as ii

from compare.contract import LeafResult
from compare.physics import nfourbar as phys

from .. import loop_common as lc

# Newton's relative tolerance 1e-6: at a singular position (all rods horizontal) the iteration
# matrix is near-singular and the iteration stagnates, at a relative residual that varies with
# the passage and the step, so on the run's own grid a tighter tolerance stops the solver there
# (measured at the library's case, N = 40 over 10 s: 1e-10 stops it at the first φ = −π; at
# dt 5e-4 s, the error estimate's halving, 1e-7, 1.5e-7 and 2e-7 stop it at φ = −8π, t = 8.58 s,
# while 3e-7 and 1e-6 pass at dt 1e-3, 5e-4 and 2.5e-4 s). 1e-6 moves φ by 1.3e-6 rad before
# the first singular position (the step's own error there 1.9e-6 rad) and by 2e-5 rad over 10 s
# (the step's 2.0e-4); the absolute tolerance does not decide it (1e-7 or 1e-6: the same run).
# Where a step still lands on one, the interval is solved again on another grid
# (`loop_common.exudyn_solve`; docs/scenes/n-four-bar.md).
DEFAULT_SETTINGS = {"integrator": "generalized_alpha", "dt": 1e-3, "spectral_radius": 1.0,
                    "newton_tol": 1e-6, "newton_abs_tol": 1e-7}
INTEGRATORS = ("generalized_alpha", "trapezoidal")
# the error estimate's Newton jitter (compare/solvers.py `_unseen_error`): Newton's error moves
# in whole iterations, and at 1e-6 the half step's can dwarf the run's (`xval calibrate
# n-four-bar --seed 4242` set 6: energy balance 5.2e-5 J off Newton 1e-8 at dt/2, 2.8e-7 J at
# dt), so the halving falls short; the tight run again at 3e-7 (×0.3 moved it 4.9e-5 J there;
# 3e-7 still passes every singular position of the library's case, 1e-7 stops at 8.58 s), and
# 10× looser where even that stops
JITTER_PROBE = {"newton_tol": (0.3, 10.0)}


def check_settings(settings: dict | None, t_out: np.ndarray | None = None) -> dict:
    """The settings merged and checked before anything runs (ValueError with one line)."""
    return lc.exudyn_settings(settings, DEFAULT_SETTINGS, INTEGRATORS)


def build(params: dict, s: dict):
    """(SystemContainer, mbs, [node per rod: cranks, then couplers], simulation settings)."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    m, L, g, n = float(params["m"]), float(params["L"]), float(params["g"]), int(params["N"])
    phi, rate = float(params["phi0"]), phys.initial_rate(params)
    c, sn = math.cos(phi), math.sin(phi)
    ground = mbs.AddObject(ii.ObjectGround())
    rods = [((k * L + 0.5 * L * c, 0.5 * L * sn), phi, (-0.5 * L * sn * rate, 0.5 * L * c * rate),
             rate) for k in range(n + 1)]
    rods += [((k * L + L * c + 0.5 * L, L * sn), 0.0, (-L * sn * rate, L * c * rate), 0.0)
             for k in range(n)]
    nodes, bodies = [], []
    for (x, y), ang, (vx, vy), w in rods:
        nd = mbs.AddNode(ii.NodeRigidBody2D(referenceCoordinates=[x, y, ang],
                                            initialCoordinates=[0, 0, 0],
                                            initialVelocities=[vx, vy, w]))
        b = mbs.AddObject(ii.ObjectRigidBody2D(nodeNumber=nd, mass=m, inertia=m * L * L / 12))
        mm = mbs.AddMarker(ii.MarkerBodyMass(bodyNumber=b))
        mbs.AddLoad(ii.LoadMassProportional(markerNumber=mm, loadVector=[0, -g, 0]))
        nodes.append(nd)
        bodies.append(b)

    def end(b, side):
        return mbs.AddMarker(ii.MarkerBodyPosition(bodyNumber=b,
                                                   localPosition=[0.5 * side * L, 0.0, 0.0]))
    for k in range(n + 1):
        pin = mbs.AddMarker(ii.MarkerBodyPosition(bodyNumber=ground,
                                                  localPosition=[k * L, 0.0, 0.0]))
        mbs.AddObject(ii.RevoluteJoint2D(markerNumbers=[pin, end(bodies[k], -1)]))
    for k in range(n):
        cp = bodies[n + 1 + k]
        mbs.AddObject(ii.RevoluteJoint2D(markerNumbers=[end(bodies[k], 1), end(cp, -1)]))
        mbs.AddObject(ii.RevoluteJoint2D(markerNumbers=[end(cp, 1), end(bodies[k + 1], 1)]))
    mbs.Assemble()
    ss = lc.ga_simulation_settings(s)
    ss.linearSolver.solverType = exu.LinearSolverType.EigenSparse
    return SC, mbs, nodes, ss


def _state(mbs, nodes):
    q = np.array([mbs.GetNodeOutput(nd, exu.OutputVariableType.Rotation)[2] for nd in nodes])
    qd = np.array([mbs.GetNodeOutput(nd, exu.OutputVariableType.AngularVelocity)[2]
                   for nd in nodes])
    return q, qd


def simulate(params: dict, t_out: np.ndarray, settings: dict | None = None) -> LeafResult:
    s = check_settings(settings)
    t_out = np.asarray(t_out, float)
    n = int(params["N"])
    Q, QD, steps, status, t_fail, reason, dt = lc.exudyn_solve(
        lambda: build(params, s), _state, t_out, s, 2 * n + 1)
    k = n + 1
    return LeafResult(channels=phys.channels(Q[:, :k], QD[:, :k], Q[:, k:], QD[:, k:], params),
                      status=status, t_fail=t_fail, reason=reason,
                      stats={"steps": steps, "rhs_evals": -1}, settings={**s, "dt": dt})
