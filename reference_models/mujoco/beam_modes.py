"""MuJoCo reference models of the MSTMM beams: the rotating cantilever blade (`rotating-beam`,
this module's `modes`) and the spinning cantilever shaft (`spinning-shaft`, `shaft_modes`,
registered through `reference_models/mujoco/shaft_modes.py`).

Both are chains of rigid bodies built with MjSpec in the rigid-finite-element layout of
`reference_models/beam_chain_common.py` (hinges at the segment mid-points, native joint
stiffness EI/Δl and GJ/Δl; the blade has three hinges per body — torsion x, flap y, lag z —
the shaft two — about x and y), hung from a hub hinge about z. The hub spins at the rotor speed
Ω; its armature (HUB_ARMATURE, ~1e10 × the chain's inertia about the axis) makes the speed
constant. `mjd_transitionFD` under the Euler integrator linearises about the straight chain
spinning steadily (MuJoCo notes §4): with hinges only, Aq = A21/h and Av = (A22 − I)/h are the
exact continuous-time Jacobians, independent of h. The centrifugal stiffening and softening,
the torsion propeller term and the Coriolis/gyroscopic coupling all come from MuJoCo's
rigid-body dynamics in the inertial frame; nothing rotating-frame is added by hand.

Then the hub row and column are deleted (its perturbation held at zero) and
q̈ = Aq q + Av q̇ is solved as a quadratic eigenproblem; frequencies are those seen in the
rotating frame (Tables 1 and 2). Labels, shapes and the Richardson extrapolation of N and N/2
are shared with the Exudyn model (beam_chain_common).

Wall time per `modes` call (defaults N = 40 and 20): 0.1–0.2 s (OPENBLAS_NUM_THREADS=1).
"""
from __future__ import annotations

import mujoco
import numpy as np

from compare.contract import LeafModes, merge_settings
from reference_models import beam_chain_common as bc

# Same chain and convergence as the Exudyn model (see there: default N = 40 with Richardson
# from N = 20, ≤ 5.4e-5 on the first five blade modes at 40 rad/s, ≤ 9.1e-7 on the shaft);
# the two engines agree to ≤ 7e-9.
MODES_SETTINGS = {"n_segments": 40, "extrapolate": True, "rotary_inertia": True}
SHAFT_MODES_SETTINGS = {"n_segments": 40, "extrapolate": True}

HUB_ARMATURE = 1e10     # × the chain's inertia about the spin axis: hub speed held to ~1e-10
# MuJoCo refuses a moving body's inertia below mjMINVAL (1e-15 kg·m²): a short light segment's
# token polar inertia (the chain's 1e-9 of its transverse one) is raised to 10 mjMINVAL
MIN_INERTIA = 1e-14
_FD_H = 1e-3            # Euler step of transitionFD; the extraction is h-independent
_FD_EPS = 1e-6


def _model(chain: dict) -> mujoco.MjModel:
    a = chain["axis"]
    e_a = np.eye(3)[a]
    spec = mujoco.MjSpec()
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_EULER
    spec.option.timestep = _FD_H
    spec.option.gravity = [0.0, 0.0, 0.0]
    x_far = chain["root"] + chain["L"]
    i_axis = float(np.sum(chain["masses"]) * x_far**2) if a != 2 else 1.0
    hub = spec.worldbody.add_body(name="hub", mass=1.0, inertia=[1.0, 1.0, 1.0],
                                  explicitinertial=True)
    hub.add_joint(type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 0, 1],
                  armature=HUB_ARMATURE * max(i_axis, 1.0))
    parent, prev_x = hub, -chain["root"]
    for i, x in enumerate(chain["hinges"]):
        body = parent.add_body(pos=list((x - prev_x) * e_a), mass=float(chain["masses"][i]),
                               ipos=list(0.5 * chain["lengths"][i] * e_a),
                               inertia=list(map(float, np.maximum(chain["inertia"][i],
                                                                  MIN_INERTIA))),
                               explicitinertial=True)
        for _, axis, k in chain["joints"]:
            body.add_joint(type=mujoco.mjtJoint.mjJNT_HINGE, axis=list(np.eye(3)[axis]),
                           stiffness=float(k[i]))     # per hinge
        parent, prev_x = body, x
    return spec.compile()


def _linearised(chain: dict, fd_scales=(1.0,)) -> list:
    """M (= I), K = −∂q̈/∂q and D = −∂q̈/∂q̇ about steady spin, hub coordinate removed, one
    (M, K, D) per factor in `fd_scales` on the finite-difference step (another step's change
    is the linearisation's error)."""
    m = _model(chain)
    d = mujoco.MjData(m)
    d.qvel[0] = chain["spin"]
    mujoco.mj_forward(m, d)
    nv = m.nv
    h = m.opt.timestep
    out = []
    for scale in fd_scales:
        A = np.zeros((2 * nv, 2 * nv))
        mujoco.mjd_transitionFD(m, d, _FD_EPS * scale, True, A, None, None, None)
        Aq = A[nv:, :nv] / h
        Av = (A[nv:, nv:] - np.eye(nv)) / h
        out.append((np.eye(nv - 1), -Aq[1:, 1:], -Av[1:, 1:]))
    return out


def _package(out: dict, settings: dict, note: str, extra: dict) -> LeafModes:
    return bc.package(out, {**settings, "fd_eps": _FD_EPS, "hub_armature_factor": HUB_ARMATURE,
                            "linearisation": "mjd_transitionFD (Euler), hub removed"},
                      note, extra)


def _physical_segments(params, s, section, n):
    """MuJoCo accepts physical rigid bodies only (I_x ≤ I_y + I_z); the Euler–Bernoulli segment
    (I_y = I_z = m̄ℓ³/12, I_x = I_α ℓ) breaks it for ℓ < 6 I_α/m̄."""
    if s["rotary_inertia"]:
        return
    ell = 0.5 * params["L"] / n / (2 if s["extrapolate"] else 1)
    if ell < 6 * section["I_alpha"] / section["m"]:
        raise ValueError("rotary_inertia=False: MuJoCo rejects Euler–Bernoulli segments "
                         f"shorter than 6·I_α/m̄ = {6 * section['I_alpha'] / section['m']:.4g}"
                         " m (I_x > I_y + I_z); use the Exudyn model or fewer segments")


def modes(params: dict, settings: dict | None = None) -> LeafModes:
    """Rotating blade: flap/lag/torsion frequencies (Hz, rotating frame) at params['speed']."""
    return bc.blade_result(params, merge_settings(settings, MODES_SETTINGS, ()), _linearised,
                           _package, "rigid-body hinge chain linearised with mjd_transitionFD "
                           "about steady spin, hub speed held; lag modes carry the section's "
                           "rotary inertia ρI_lag", check=_physical_segments)


def shaft_modes(params: dict, settings: dict | None = None) -> LeafModes:
    """Spinning shaft: whirl frequencies (Hz, co-rotating frame) at Ω = spin_ratio·ω₀;
    extra['omega_star'] = ω/ω₀ (Table 2)."""
    return bc.shaft_result(params, merge_settings(settings, SHAFT_MODES_SETTINGS, ()),
                           _linearised, _package, "rigid-body hinge chain spinning about its "
                           "axis, linearised with mjd_transitionFD about steady spin")
