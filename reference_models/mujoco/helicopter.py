"""MuJoCo model of the whole helicopter (seed 002, Tables 3 and 4): the aircraft tree of
`reference_models/helicopter_common.py` (the route, multi-blade coordinates, is described
there) as nested bodies, linearised with `mjd_transitionFD`.

The drive is a hinge about z with a large armature (its speed held; its row and column are
then dropped); the massless frames carry 1e-9 kg (MuJoCo wants a physical body). The
transition matrix of one explicit-Euler step of h = 1e-3 s gives A_q = ∂q̈/∂q and
A_v = ∂q̈/∂q̇ exactly (q̈ enters the Euler step linearly), from central differences of
ε = 1e-6.
"""
from __future__ import annotations

import time

import mujoco
import numpy as np

from reference_models import helicopter_common as hc

MODES_SETTINGS = hc.MODES_SETTINGS
SPIN_ARMATURE = 1e10
_FD_H, _FD_EPS = 1e-3, 1e-6
_KIND = {"hinge": mujoco.mjtJoint.mjJNT_HINGE, "spin": mujoco.mjtJoint.mjJNT_HINGE,
         "slide": mujoco.mjtJoint.mjJNT_SLIDE}


def _quat(R):
    q = np.empty(4)
    mujoco.mju_mat2Quat(q, np.ascontiguousarray(R).ravel())
    return [float(v) for v in q]


def build(params: dict, n: int, free: bool = False):
    """The MjModel and, per degree of freedom, its coordinate name (part, family, index)."""
    spec = mujoco.MjSpec()
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_EULER
    spec.option.timestep = _FD_H
    spec.option.gravity = [0.0, 0.0, 0.0]
    names: list = []
    made: list = []
    for b in hc.tree(params, n, free):
        parent = spec.worldbody if b.parent < 0 else made[b.parent]
        body = parent.add_body(pos=[float(v) for v in b.pos], quat=_quat(b.rot),
                               mass=float(b.mass), ipos=[float(v) for v in b.com],
                               inertia=[float(v) for v in b.inertia], explicitinertial=True)
        for name, kind, axis, k in b.joints:
            j = body.add_joint(type=_KIND[kind], axis=[float(v) for v in np.eye(3)[axis]],
                               stiffness=float(k))
            if kind == "spin":
                j.armature, j.name = SPIN_ARMATURE, "spin"
            names.append(name)
        made.append(body)
    return spec.compile(), names


def linearised(params: dict, n: int, psi: float = 0.0, free: bool = False):
    """A_q = ∂q̈/∂q and A_v = ∂q̈/∂q̇ about steady spin at rotor azimuth ψ (drive removed), in
    the model's own coordinates (blades rotating, shaft bending rotating, the rest fixed), the
    coordinate names and the seconds spent in mjd_transitionFD."""
    model, names = build(params, n, free)
    data = mujoco.MjData(model)
    spin = model.joint("spin")
    data.qpos[spin.qposadr[0]] = psi
    data.qvel[spin.dofadr[0]] = params["speed"]
    mujoco.mj_forward(model, data)
    nv = model.nv
    A = np.zeros((2 * nv, 2 * nv))
    t0 = time.perf_counter()
    mujoco.mjd_transitionFD(model, data, _FD_EPS, True, A, None, None, None)
    fd_s = time.perf_counter() - t0
    keep = [i for i in range(nv) if i != spin.dofadr[0]]
    Aq = (A[nv:, :nv] / _FD_H)[np.ix_(keep, keep)]
    Av = ((A[nv:, nv:] - np.eye(nv)) / _FD_H)[np.ix_(keep, keep)]
    return Aq, Av, [names[i] for i in keep], fd_s


def modes(params: dict, settings: dict | None = None):
    """The clamped helicopter (Table 3), fixed-frame frequencies in multi-blade coordinates."""
    return hc.aircraft_modes(linearised, params, settings, False, NOTE)


def hover_modes(params: dict, settings: dict | None = None):
    """The hovering (free) helicopter (Table 4), rigid-body roots dropped."""
    return hc.aircraft_modes(linearised, params, settings, True, NOTE)


NOTE = "MuJoCo nested bodies, mjd_transitionFD; fixed frame, multi-blade coordinates"
