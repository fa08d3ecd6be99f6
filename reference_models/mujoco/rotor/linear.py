"""The linearised whirl: `modes` and `whirl_sweep` from mjd_transitionFD about steady spin."""
import math

import mujoco
import numpy as np

from compare.contract import LeafModes
from compare.physics import eigen

from .callback import Callback
from .kernel import U_FLAG
from .model import build
from .settings import check_settings

FD_H = 1e-3        # Euler step used for transitionFD; the extraction below is h-independent
FD_EPS = 1e-6
FD_VARY = 10.0      # the FD step × this: the linearisation's own error


def linearisation_model(params, settings, model=None):
    """(settings, model, data) of the linearisations: Euler at FD_H, no drive torque; `model`:
    one compiled for the same MODEL_FIELDS (else compiled here)."""
    s = check_settings({**(settings or {}), "integrator": "euler", "dt": FD_H})
    m, d, _ = build(params, s, "euler", torque=0.0, model=model)
    return s, m, d


def continuous_A(m, d, spin, eps=FD_EPS):
    """The continuous-time state matrix (δ, v: body-frame tangent rotation and angular
    velocity) about steady spin Ω e_z at tilt 0."""
    ud = d.userdata.copy()
    mujoco.mj_resetData(m, d)        # (this also zeroes userdata: restore it)
    d.userdata[:] = ud
    d.qpos[:] = (1.0, 0.0, 0.0, 0.0)
    d.qvel[:] = (0.0, 0.0, spin)
    d.act[0] = 0.0
    d.userdata[U_FLAG] = 0.0
    nv = m.nv
    ns = 2 * nv + m.na
    A = np.zeros((ns, ns))
    mujoco.mjd_transitionFD(m, d, eps, True, A, None, None, None)
    h = m.opt.timestep
    # Euler: v' = v + h·a(q, v) exactly, so Aq = A21/h and Av = (A22 − I)/h are exact. The
    # kinematic blocks are taken analytically: ball tangent coordinates are body-frame,
    # q = q_ref(t) ⊗ exp(δ), so δ' = −[ω×]δ + δω (the discrete map has exp(−h[ω×]) there,
    # which (A11 − I)/h would only approximate to O(hΩ)).
    A21 = A[nv:2 * nv, :nv]
    A22 = A[nv:2 * nv, nv:2 * nv]
    Aq = A21 / h
    Av = (A22 - np.eye(nv)) / h
    om = np.array(d.qvel, dtype=float)
    wx = np.array([[0, -om[2], om[1]], [om[2], 0, -om[0]], [-om[1], om[0], 0]])
    return np.block([[-wx, np.eye(nv)], [Aq, Av]])


def _whirl_at(m, d, spin):
    """Continuous-time eigen-analysis at steady spin; returns [(signed inertial rad/s, Re λ)]
    (the body-frame tangent coordinates shift the frequency by Ω, not the real part)."""
    lam, vec = np.linalg.eig(continuous_A(m, d, spin))
    out = []
    for j in np.argsort(-np.abs(lam.imag)):
        lj = lam[j]
        if lj.imag <= 1e-9 * max(1.0, abs(lj)):
            continue
        v = vec[:, j]
        tilt_part = np.linalg.norm(v[0:2])
        if tilt_part < 1e-6 * np.linalg.norm(v[:3]):
            continue
        # body-frame rotation sense of δ(t) = Re(v e^{λt}) in the (x, y) tangent plane
        sense_b = -(v[0].real * v[1].imag - v[1].real * v[0].imag)
        mu = lj.imag
        signed_body = mu if sense_b > 0 else -mu
        if abs(sense_b) < 1e-9 * (abs(v[0]) ** 2 + abs(v[1]) ** 2):
            signed_body = mu    # linear (non-circular) mode: no sense
        out.append((signed_body + spin, lj.real, sense_b, lj))
    return out


def _classify(pairs, spin):
    """Pick the two whirl modes; return (backward, forward) as (freq_rad_s, Re λ, λ of A)."""
    if len(pairs) < 2:
        raise RuntimeError(f"expected two whirl modes, found {len(pairs)}")
    pairs = pairs[:2]
    if abs(spin) < 1e-12:
        a, b = sorted(((abs(p[0]), p[1], p[3]) for p in pairs), key=lambda t: t[:2])
        return a, b
    fw = [p for p in pairs if np.sign(p[0]) == np.sign(spin)]
    bw = [p for p in pairs if np.sign(p[0]) != np.sign(spin)]
    if len(fw) != 1 or len(bw) != 1:   # fall back to the closed-form ordering: backward lower
        a, b = sorted(((abs(p[0]), p[1], p[3]) for p in pairs), key=lambda t: t[:2])
        return a, b
    return (abs(bw[0][0]), bw[0][1], bw[0][3]), (abs(fw[0][0]), fw[0][1], fw[0][3])


def modes(params: dict, settings: dict) -> dict:
    """Linearised whirl frequencies at steady spin params['spin'] (rad/s) about the upright axis.

    Linearisation: mjd_transitionFD under Euler (no drive torque), continuous-time blocks
    recovered exactly, ball-joint body-frame tangent frequencies converted to the inertial frame
    (+Ω), backward/forward labelled from the eigenvector's rotation sense. With c_ext = 0 the
    internal-damping threshold whirl is synchronous (ω = Ω): still in the body-frame
    coordinates, its root is real there and not found within ~1e-9 of that speed."""
    spin = float(params["spin"])
    s, m, d = linearisation_model(params, settings)
    with Callback(s["callback"]) as cbk:
        pairs = _whirl_at(m, d, spin)
        (wb, sb, lam_b), (wf, sf, lam_f) = _classify(pairs, spin)
        # ζ's and the frequencies' errors: eigen round-off plus the change when the FD step is
        # varied, mode by mode. The body-frame root moves by |δλ|, and so does the inertial
        # frequency |Im λ ± Ω|: backward whirl's (Ω + ω_b)/ω_b magnifies it, relative
        A, A_varied = (continuous_A(m, d, spin, e) for e in (FD_EPS, FD_VARY * FD_EPS))
        z_err = eigen.root_zeta_errors(A, [lam_b, lam_f], A_varied,
                                       reported=[sb + 1j * wb, sf + 1j * wf])
        f_err = eigen.root_errors(A, [lam_b, lam_f], A_varied) / (2 * math.pi)
        kind = cbk.kind
    used = {"integrator": "euler", "dt": FD_H, "fd_eps": FD_EPS, "spring": s["spring"],
            "callback": kind, "linearisation": "mjd_transitionFD, ball joint, inertial frame"}
    notes = (["approximate: steady spin is no equilibrium of an eccentric rotor"]
             if spin != 0 and params["eccentricity"] != 0 else [])
    return LeafModes(frequencies_hz=np.array([wb, wf]) / (2 * math.pi),
                       labels=["backward whirl", "forward whirl"], whirl=["backward", "forward"],
                       damping=-np.array([sb, sf]) / np.hypot([sb, sf], [wb, wf]),
                       settings=used, notes=notes,
                       extra={"max_re_per_s": float(max(sb, sf)),
                              "damping_error": z_err, "frequency_error_hz": f_err})


def whirl_sweep(params: dict, spins, settings: dict | None = None):
    """Campbell sweep: (backward_rad_s, forward_rad_s) arrays over ``spins``, one compiled model."""
    spins = np.asarray(spins, dtype=float)
    s, m, d = linearisation_model(params, settings)
    bw = np.empty(spins.size)
    fw = np.empty(spins.size)
    with Callback(s["callback"]):
        for i, om in enumerate(spins):
            (b, *_), (f, *_) = _classify(_whirl_at(m, d, float(om)), float(om))
            bw[i], fw[i] = b, f
    return bw, fw
