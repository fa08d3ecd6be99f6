"""MuJoCo model of the whole helicopter (seed 002, Tables 3 and 4): the aircraft tree of
`reference_models/helicopter_common.py` (the route, multi-blade coordinates, is described
there) as nested bodies, linearised by central differences (ε = 1e-6) of its inverse dynamics.

The drive is a hinge about z with a large armature; its speed is held — its row and column
are taken out of M before M is inverted, as Exudyn deletes them (the armature alone left the
rotor coupled to a finite drive inertia: 1.4e-7 of a root at 66 rad/s) — and the massless
frames carry 1e-9 kg (MuJoCo wants a physical body).
Linearisation: M(q) q̈(q, q̇) = f(q, q̇), so with f_inv = RNE(q, q̇, a = q̈₀) − passive(q, q̇)
(MuJoCo's stage functions; armature·q̈₀ is constant) A_q = −M⁻¹ ∂f_inv/∂q and A_v =
−M⁻¹ ∂f_inv/∂q̇ at (q₀, q̈₀), the a = q̈₀ term carrying ∂M/∂q·q̈₀: the Jacobian that
mjd_transitionFD's Euler step gives, without its 2·nv re-factorisations of M (one here).
Against it at N = 40: A_q to 9.5e-10, A_v to 1.4e-4 — rounding at ε = 1e-6 amplified by
the ill-conditioned M (1e-9 kg frames, the drive's armature), each route 1.2e-4 from ε = 1e-3,
exact for q̈ quadratic in q̇ — and the frequencies to 1e-8.
"""
from __future__ import annotations

import time

import mujoco
import numpy as np

from reference_models import helicopter_common as hc

MODES_SETTINGS = hc.MODES_SETTINGS
SPIN_ARMATURE = 1e10
_FD_EPS = 1e-6
_KIND = {"hinge": mujoco.mjtJoint.mjJNT_HINGE, "spin": mujoco.mjtJoint.mjJNT_HINGE,
         "slide": mujoco.mjtJoint.mjJNT_SLIDE}


def _quat(R):
    q = np.empty(4)
    mujoco.mju_mat2Quat(q, np.ascontiguousarray(R).ravel())
    return [float(v) for v in q]


def build(params: dict, n: int, free: bool = False, sections: float = 1.0):
    """The MjModel and, per degree of freedom, its coordinate name (part, family, index).
    `sections` (hc.tree's) ≠ 1 is written into the compiled model's body inertias: the
    compiler refuses a body whose inertia breaks the triangle inequality, as a segment
    without its section's rotary inertia may (a thick shaft's polar inertia exceeds its
    segments' m ℓ²/6), while the dynamics take any."""
    spec = mujoco.MjSpec()
    spec.option.gravity = [0.0, 0.0, 0.0]
    names: list = []
    made: list = []
    bodies = hc.tree(params, n, free)
    for i, b in enumerate(bodies):
        parent = spec.worldbody if b.parent < 0 else made[b.parent]
        body = parent.add_body(name=f"b{i}", pos=[float(v) for v in b.pos], quat=_quat(b.rot),
                               mass=float(b.mass), ipos=[float(v) for v in b.com],
                               inertia=[float(v) for v in b.inertia], explicitinertial=True)
        for name, kind, axis, k in b.joints:
            j = body.add_joint(type=_KIND[kind], axis=[float(v) for v in np.eye(3)[axis]],
                               stiffness=float(k))
            if kind == "spin":
                j.armature, j.name = SPIN_ARMATURE, "spin"
            names.append(name)
        made.append(body)
    model = spec.compile()
    if sections != 1.0:
        for i, b in enumerate(hc.tree(params, n, free, sections)):
            model.body(f"b{i}").inertia = b.inertia
    return model, names


def _inverse_dynamics(model, data, out):
    """f_inv = RNE(q, q̇, a = data.qacc) − qfrc_passive at data's state, without the inertia
    stage: mj_rne needs cinert, cdof (comPos) and cvel, cdof_dot (comVel); it has no armature."""
    mujoco.mj_kinematics(model, data)
    mujoco.mj_comPos(model, data)
    mujoco.mj_comVel(model, data)
    mujoco.mj_passive(model, data)
    mujoco.mj_rne(model, data, 1, out)
    return out - data.qfrc_passive


def jacobians(model, data, eps=_FD_EPS, held=()):
    """(∂q̈/∂q, ∂q̈/∂q̇) at data's state by central differences (step `eps`) of the inverse
    dynamics; with the degrees of freedom `held` at their speed (a prescribed motion: their
    q̈ = 0, whatever torque that takes), over the others only."""
    if model.nq != model.nv:               # a ball or free joint: qpos is not qvel's tangent
        raise ValueError("jacobians: hinge and slide joints only")
    mujoco.mj_forward(model, data)             # q̈₀ in data.qacc, M factorised in data.qLD
    out = np.empty(model.nv)
    jac = []
    for x in (data.qpos, data.qvel):
        df = np.empty((model.nv, model.nv))    # row i: ∂f_inv/∂x_i
        for i in range(model.nv):
            x0 = x[i]
            x[i] = x0 + eps
            fp = _inverse_dynamics(model, data, out)
            x[i] = x0 - eps
            df[i] = (fp - _inverse_dynamics(model, data, out)) / (2 * eps)
            x[i] = x0
        jac.append(df)
    if not held:
        for df in jac:
            mujoco.mj_solveM(model, data, df, df.copy())    # row i: M⁻¹ ∂f_inv/∂x_i
        return [-df.T for df in jac]
    # the held rows and columns out of M before it is inverted: the drive's armature alone
    # would leave it a finite inertia, coupled to the rotor (I_rotor/armature: 1.4e-7 of a
    # hovering root at 66 rad/s against Exudyn, which removes them so)
    keep = [i for i in range(model.nv) if i not in held]
    M = np.empty((model.nv, model.nv))
    mujoco.mj_fullM(model, data, M)
    M = M[np.ix_(keep, keep)]
    return [-np.linalg.solve(M, df[np.ix_(keep, keep)].T) for df in jac]


def linearised(params: dict, n: int, psi: float = 0.0, free: bool = False,
               fd_scale: float = 1.0, sections: float = 1.0):
    """A_q = ∂q̈/∂q and A_v = ∂q̈/∂q̇ about steady spin at rotor azimuth ψ (drive removed), in
    the model's own coordinates (blades rotating, shaft bending rotating, the rest fixed), the
    coordinate names and the seconds spent linearising; the finite-difference step × fd_scale
    (`sections`: hc.tree's)."""
    model, names = build(params, n, free, sections)
    data = mujoco.MjData(model)
    spin = model.joint("spin")
    data.qpos[spin.qposadr[0]] = psi
    data.qvel[spin.dofadr[0]] = params["speed"]
    t0 = time.perf_counter()
    d = int(spin.dofadr[0])
    Aq, Av = jacobians(model, data, _FD_EPS * fd_scale, held=(d,))
    secs = time.perf_counter() - t0
    return Aq, Av, [nm for i, nm in enumerate(names) if i != d], secs


def modes(params: dict, settings: dict | None = None):
    """The clamped helicopter (Table 3), fixed-frame frequencies in multi-blade coordinates."""
    return hc.aircraft_modes(linearised, params, settings, False, NOTE)


def hover_modes(params: dict, settings: dict | None = None):
    """The hovering (free) helicopter (Table 4), rigid-body roots dropped."""
    return hc.aircraft_modes(linearised, params, settings, True, NOTE)


NOTE = ("MuJoCo nested bodies, inverse-dynamics finite differences; fixed frame, "
        "multi-blade coordinates")
