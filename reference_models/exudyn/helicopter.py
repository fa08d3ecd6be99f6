"""Exudyn model of the whole helicopter (seed 002, Tables 3 and 4): the aircraft tree of
`reference_models/helicopter_common.py` (the route, multi-blade coordinates, is described
there) as one `ObjectKinematicTree`, linearised with `ComputeLinearizedSystem`.

One link per joint coordinate (a body's joints in order, zero offset after the first); the
body's mass sits on its last link. A tree has no welded link, so a body without joints
(fuselage when clamped, hub, the massless blade-root frames) is merged into its parent's
last link as one rigid body (mass, centre of mass and inertia by the parallel-axis rule),
its children re-hung from there.

`ComputeLinearizedSystem` gives M and the derivatives of the tree's forces about steady spin
(q = 0, drive angle ψ, drive speed Ω): K = −∂f/∂q holds the centrifugal stiffening and
softening, D = −∂f/∂q̇ the Coriolis and gyroscopic coupling (finite differences: D moves
with ψ by 2.5e-5 after the transform, K by 2e-11); nothing rotating-frame is added by hand.
The drive's row and column are deleted (its speed prescribed), then A_q = −M⁻¹K,
A_v = −M⁻¹D.
"""
from __future__ import annotations

import time

import exudyn as exu
import numpy as np
from exudyn.itemInterface import NodeGenericODE2, ObjectKinematicTree

from reference_models import helicopter_common as hc

MODES_SETTINGS = hc.MODES_SETTINGS
_REV = (exu.JointType.RevoluteX, exu.JointType.RevoluteY, exu.JointType.RevoluteZ)
_PRIS = (exu.JointType.PrismaticX, exu.JointType.PrismaticY, exu.JointType.PrismaticZ)


def _merge(link, pos, rot, mass, com, inertia):
    """Add a rigid body at (pos, rot) in the link's frame to the link, in place."""
    c_new = rot @ com + pos
    m = link["mass"] + mass
    c = (link["mass"] * link["com"] + mass * c_new) / m
    J = np.zeros((3, 3))
    for mi, ci, Ji in ((link["mass"], link["com"], link["inertia"]),
                       (mass, c_new, rot @ np.diag(inertia) @ rot.T)):
        d = ci - c
        J += Ji + mi * (d @ d * np.eye(3) - np.outer(d, d))
    link.update(mass=m, com=c, inertia=J)


def links(params: dict, n: int, free: bool = False, sections: float = 1.0):
    """The tree's links (type, parent, offset, rotation, mass, com, inertia, stiffness) and,
    per link, its coordinate name (`sections`: hc.tree's)."""
    out, names = [], []
    home = {}             # body index -> (its last link, its pose in that link's frame)
    for i, b in enumerate(hc.tree(params, n, free, sections)):
        if b.parent < 0:
            parent, pos, rot = -1, np.asarray(b.pos, float), b.rot
        else:
            parent, p_pos, p_rot = home[b.parent]
            pos, rot = p_pos + p_rot @ b.pos, p_rot @ b.rot
        if not b.joints:
            _merge(out[parent], pos, rot, b.mass, np.asarray(b.com, float), b.inertia)
            home[i] = (parent, pos, rot)
            continue
        coords = [((_PRIS if kind == "slide" else _REV)[axis], name, k)
                  for name, kind, axis, k in b.joints]
        for j, (jt, name, k) in enumerate(coords):
            first = j == 0
            out.append({"type": jt, "parent": parent, "offset": pos if first else np.zeros(3),
                        "rot": rot if first else np.eye(3), "mass": 0.0, "com": np.zeros(3),
                        "inertia": np.zeros((3, 3)), "P": k})
            names.append(name)
            parent = len(out) - 1
        last = out[-1]
        last.update(mass=b.mass, com=np.asarray(b.com, float), inertia=np.diag(b.inertia))
        home[i] = (parent, np.zeros(3), np.eye(3))
    return out, names


# Exudyn's step, relativeEpsilon × max(minimumCoordinateSize, |x|), is 1e-9 at its defaults,
# where the aircraft's forward differences are rounding: over 240 roots of five aircraft
# (N = 20, 40) its roots sat 9.8e-9 Hz off MuJoCo's at the median, 1.1e-6 at the 90th;
# at 1e-8, 2e-9 and 8.6e-8 (truncation takes over by 1e-6). At 1e-9 the ×10 probe can miss it:
# hover's seed-4242 set 17 root at 0.0714 Hz, 4.8e-8 off, moved 2e-9 (docs/commands/calibrate.md).
FD_SCALE = 10.0


def linearised(params: dict, n: int, psi: float = 0.0, free: bool = False,
               fd_scale: float = 1.0, sections: float = 1.0):
    """A_q = ∂q̈/∂q and A_v = ∂q̈/∂q̇ about steady spin at rotor azimuth ψ (drive removed), in
    the model's own coordinates, the coordinate names and the seconds of the linearisation;
    the finite-difference step × fd_scale (`sections`: hc.tree's)."""
    lk, names = links(params, n, free, sections)
    nq = len(lk)
    d = names.index(hc.SPIN)
    q0, v0 = [0.0] * nq, [0.0] * nq
    q0[d], v0[d] = float(psi), float(params["speed"])
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    node = mbs.AddNode(NodeGenericODE2(referenceCoordinates=[0.0] * nq, initialCoordinates=q0,
                                       initialCoordinates_t=v0, numberOfODE2Coordinates=nq))
    mbs.AddObject(ObjectKinematicTree(
        nodeNumber=node, jointTypes=[x["type"] for x in lk],
        linkParents=[x["parent"] for x in lk],
        # the joint frame's orientation in its parent (its transpose puts blades 1 and 3 at
        # −90° and +90°: the multi-blade matrices then depend on ψ by 3e-3; as given they do
        # not and equal MuJoCo's, tests/engines/test_helicopter_engines.py)
        jointTransformations=exu.Matrix3DList([np.asarray(x["rot"]) for x in lk]),
        jointOffsets=exu.Vector3DList([list(map(float, x["offset"])) for x in lk]),
        linkInertiasCOM=exu.Matrix3DList([x["inertia"] for x in lk]),
        linkCOMs=exu.Vector3DList([list(map(float, x["com"])) for x in lk]),
        linkMasses=[float(x["mass"]) for x in lk],
        jointPControlVector=[float(x["P"]) for x in lk], jointDControlVector=[0.0] * nq,
        jointPositionOffsetVector=[0.0] * nq, jointVelocityOffsetVector=[0.0] * nq))
    mbs.Assemble()
    t0 = time.perf_counter()
    ss = exu.SimulationSettings()
    ss.staticSolver.newton.numericalDifferentiation.relativeEpsilon *= FD_SCALE * fd_scale
    M, K, D = (np.asarray(x, float) for x in mbs.ComputeLinearizedSystem(ss)[:3])
    secs = time.perf_counter() - t0
    keep = [i for i in range(nq) if i != d]
    M, K, D = (X[np.ix_(keep, keep)] for X in (M, K, D))
    if params["speed"] == 0.0:
        # at rest the tree's velocity forces are quadratic in q̇ (it has no dampers), so D is
        # zero; the forward differences leave O(step) of them (6.9e-8), which spoiled the free
        # aircraft's eigenvectors: at N = 20 (K − s²)p missed by ~100 % at the median mode
        # and every mode was named 'fuselage'; 1.6e-13 with D = 0, as MuJoCo's central
        # differences give it
        D = np.zeros_like(D)
    MinvK, MinvD = np.split(np.linalg.solve(M, np.hstack([K, D])), 2, axis=1)
    return -MinvK, -MinvD, [names[i] for i in keep], secs


def modes(params: dict, settings: dict | None = None):
    """The clamped helicopter (Table 3), fixed-frame frequencies in multi-blade coordinates."""
    return hc.aircraft_modes(linearised, params, settings, False, NOTE)


def hover_modes(params: dict, settings: dict | None = None):
    """The hovering (free) helicopter (Table 4), rigid-body roots dropped."""
    return hc.aircraft_modes(linearised, params, settings, True, NOTE)


NOTE = "Exudyn ObjectKinematicTree, ComputeLinearizedSystem; fixed frame, multi-blade coordinates"
