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

import exudyn as exu
import numpy as np
from exudyn import itemInterface as ii

from compare.contract import LeafResult, check_once
from compare.physics import andrews as phys

from .. import loop_common as lc

# Newton's tolerances well under the step's error: the index-3 accelerations carry Newton's
# residual over dt², and at 1e-10 (absolute 1e-12) that noise set the step's halving changes —
# at `xval calibrate andrews-squeezer --seed 2026` set 5 the kinetic energy's change from dt to
# dt/2 was 3.4e-10 J where the step's own (order 2, at 1e-13) is 9.6e-10, an estimate 2.2 ×
# short of Exudyn's distance to MuJoCo (a false `disagree`); at 1e-13 the changes shrink by
# 3.9 and 4.2 down to dt/4 and the run costs the same (0.1 s)
DEFAULT_SETTINGS = {"integrator": "generalized_alpha", "dt": 2e-6, "spectral_radius": 1.0,
                    "newton_tol": 1e-13, "newton_abs_tol": 1e-15}
INTEGRATORS = ("generalized_alpha", "trapezoidal")
# Newton's relative tolerance is a knob of its own (error ∝ it): at a drawn squeezer (seed 11,
# set 18, 3 ms) 1e-10 → 1e-12 moved β by 4.8e-8 rad at the step 1e-6 s, more than the step's
# error (1.5e-8 against dt/16)
KNOBS = {"newton_tol": 1}
# the error estimate's Newton jitter (compare/solvers.py `_unseen_error`): the index-3 velocities
# carry the positions' Newton error over the step, a scatter the halving's runs sample but need
# not span — `xval calibrate andrews-squeezer --seed 8080` set 8: the energy balance 3.8e-12 J
# off MuJoCo's far run at dt, 2.9e-12 at dt/2 and 3.1e-12 at dt/4 (no order), a bar of 1.8e-12.
# Newton's last iterate moves in whole iterations: there 100× tighter stops the run, 10× moves
# dt/2's by 4.5e-12 J and 10× looser not at all; at seed 2026 set 19 (3.1e-11 J against a bar
# of 2.9e-11) only 100× tighter moves it (1.1e-11 J)
JITTER_PROBE = {"newton_tol": (0.01, 0.1, 10.0)}
BODIES = ("K1", "K2", "K3", "K4", "K5", "K6", "K7")


@check_once
def check_settings(settings: dict | None, t_out: np.ndarray | None = None) -> dict:
    """The settings merged and checked before anything runs (ValueError with one line)."""
    return lc.exudyn_settings(settings, DEFAULT_SETTINGS, INTEGRATORS)


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

    return SC, mbs, nodes, lc.ga_simulation_settings(s)


def _angles_and_rates(mbs, nodes):
    sd = mbs.systemData
    ref = np.array(sd.GetODE2Coordinates(configuration=exu.ConfigurationType.Reference))
    C = exu.ConfigurationType.Current
    q = np.array(sd.GetODE2Coordinates(configuration=C)) + ref
    v = np.array(sd.GetODE2Coordinates_t(configuration=C))
    idx = [mbs.GetNodeODE2Index(nodes[k]) + 2 for k in BODIES]
    return phys.angles_from_bodies(q[idx]), phys.angles_from_bodies(v[idx])


def simulate(params: dict, t_out: np.ndarray, settings: dict | None = None) -> LeafResult:
    s = check_settings(settings)
    t_out = np.asarray(t_out, float)
    Q, QD, steps, status, t_fail, reason, dt = lc.exudyn_solve(
        lambda: build(params, s), _angles_and_rates, t_out, s, 7)
    used = {**s, "dt": dt}
    return LeafResult(channels=phys.channels(Q, QD, phys.pack(params)), status=status,
                      t_fail=t_fail, reason=reason, stats={"steps": steps, "rhs_evals": -1},
                      settings=used)
