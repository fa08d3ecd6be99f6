"""MuJoCo model of the helicopter (seed 002, Tables 3 and 4) in multi-blade coordinates.
NOT registered in the scene yet (issue 23, step 2 in progress): see `modes` for what exists.

Route. The rotor spins relative to a fuselage and tail that are not axisymmetric about the
shaft (fuselage inertia about X 0.50× that about Y, centre of mass 0.4 m off the axis, tail
boom along −X), so no single frame makes the physical system time-invariant in physical
coordinates: in the rotor frame the support turns, in the fixed frame the blades do. With
four identical blades on an isotropic hub and a round shaft, multi-blade coordinates
(collective b₀, cyclic b_c, b_s, differential b_d per blade coordinate; the shaft's bending
turned into the fixed frame) make it exactly time-invariant (Coleman): one linearisation at
any rotor azimuth ψ, transformed with q = T(ψ) p,

    p̈ = T⁻¹[(A_q T + Ω A_v T′ − Ω² T″) p + (A_v T − 2Ω T′) ṗ],

gives constant matrices — `tests/test_helicopter_engines.py` checks that they do not depend
on ψ (1.9e-11 relative; the untransformed ones change by 8.7e-3). This needs neither a
time-domain identification (close roots 6.30–6.37 Hz would need records of minutes) nor
Floquet analysis (one linearisation instead of many).

The chain: the blades, shaft and tail boom in the rigid-finite-element layout of
beam_chain_common (blades as the rotating-beam model: torsion, flap, lag hinges and the
section's rotary inertia; shaft: two bending hinges and torsion, tail: torsion and two
bending hinges, both with their section's rotary inertia, which MuJoCo needs for a physical
body), the hub and fuselage rigid and welded, the drive at the shaft's foot a hinge about z
spinning at Ω with a large armature (speed held), the tail's far end clamped. No axial
flexibility (the paper's 24.1 Hz 'axial cyclic' root has none here). The frequencies are
fixed-frame; a cyclic mode at ω_F is seen on the blades at ω_F + Ω (regressive) or |ω_F − Ω|
(progressive), given in extra['rotating_frame_hz'] for comparison with mstmm, which writes
the whole aircraft in the rotor frame.
"""
from __future__ import annotations

import mujoco
import numpy as np
from scipy.optimize import linear_sum_assignment

from compare.contract import ModesResult, merge_settings
from compare.physics.mstmm import helicopter_layout
from reference_models import beam_chain_common as bc

MODES_SETTINGS = {"n_segments": 40, "extrapolate": True, "psi": 0.0}
SPIN_ARMATURE = 1e10
_FD_H, _FD_EPS = 1e-3, 1e-6
_HINGE = mujoco.mjtJoint.mjJNT_HINGE


def _inertia(m_line, ell, axial, b1, b2, axis):
    principal = bc.segment_inertia(m_line, ell, axial, b1, b2)    # [along, t1, t2]
    out = np.zeros(3)
    out[axis], out[[i for i in range(3) if i != axis]] = principal[0], principal[1:]
    return out


def _chain(parent, start, axis, L, n, m_line, inertia, joints, tag, names, sign=1.0):
    """n-hinge chain from `start` (parent frame) along unit axis `axis` (− with sign −1);
    returns the last body and the position of its hinge relative to `start`."""
    lay = bc.layout(L, n)
    e = sign * np.eye(3)[axis]
    body, prev = parent, None
    for i, x in enumerate(lay["hinges"]):
        pos = np.asarray(start) + x * e if prev is None else (x - prev) * e
        ell = lay["lengths"][i]
        body = body.add_body(pos=[float(v) for v in pos], mass=float(m_line * ell),
                             ipos=[float(v) for v in 0.5 * ell * e],
                             inertia=[float(v) for v in inertia(ell)], explicitinertial=True)
        for name, ax, stiffness in joints:
            body.add_joint(type=_HINGE, axis=[float(v) for v in np.eye(3)[ax]],
                           stiffness=float(stiffness / lay["dl"]))
            names.append((tag, name, i))
        prev = x
    return body, prev * e


def build(params: dict, n: int, free: bool = False):
    """The MjModel and, per degree of freedom, (part, joint family, hinge index). Clamped: the
    tree grows from the tail's far end; free: from the fuselage, on a free joint, the tail
    boom hanging from its rear face."""
    lay = helicopter_layout(params)
    spec = mujoco.MjSpec()
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_EULER
    spec.option.timestep = _FD_H
    spec.option.gravity = [0.0, 0.0, 0.0]
    names: list = []
    t, f, s, b = lay["tail"], lay["fuselage"], lay["shaft"], lay["blade"]
    half = t["I_alpha"] / 2

    def tail_chain(parent, start, sign):
        return _chain(parent, start, 0, t["L"], n, t["m"],
                      lambda ell: _inertia(t["m"], ell, t["I_alpha"], half, half, 0),
                      (("torsion", 0, t["GJ"]), ("bend_y", 1, t["EI_flap"]),
                       ("bend_z", 2, t["EI_lag"])), "tail", names, sign)
    fuselage = {"mass": float(f["m"]), "ipos": [float(v) for v in f["cm"] - f["rear"]],
                "inertia": [float(v) for v in f["I"]], "explicitinertial": True}
    if free:
        fus = spec.worldbody.add_body(pos=[float(v) for v in f["rear"]], **fuselage)
        fus.add_joint(type=mujoco.mjtJoint.mjJNT_FREE)
        names += [("fuselage", "free", i) for i in range(6)]
        tail_chain(fus, np.zeros(3), -1.0)
    else:
        last, tip = tail_chain(spec.worldbody, t["end"], 1.0)
        fus = last.add_body(pos=[float(v) for v in f["rear"] - (t["end"] + tip)], **fuselage)
    drive = fus.add_body(pos=[float(v) for v in s["bottom"] - f["rear"]], mass=1e-9,
                         inertia=[1e-12] * 3, explicitinertial=True)
    drive.add_joint(type=_HINGE, axis=[0, 0, 1], armature=SPIN_ARMATURE, name="spin")
    names.append(("drive", "spin", 0))
    rot = s["I_p"] / 2
    top, tip = _chain(drive, np.zeros(3), 2, s["L"], max(n // 2, 2), s["m"],
                      lambda ell: _inertia(s["m"], ell, s["I_p"], rot, rot, 2),
                      (("bend_x", 0, s["EI"]), ("bend_y", 1, s["EI"]), ("torsion", 2, s["GJ"])),
                      "shaft", names)
    hub = top.add_body(pos=[float(v) for v in s["top"] - (s["bottom"] + tip)],
                       mass=float(lay["hub"]["m"]), ipos=[0.0, 0.0, float(-s["top"][2])],
                       inertia=[float(v) for v in lay["hub"]["I"]], explicitinertial=True)
    centre = -s["top"]
    rho = params["blade_rho"]

    def blade_inertia(ell):
        return _inertia(b["m"], ell, b["I_alpha"], rho * b["I_flap"], rho * b["I_lag"], 0)
    for k in range(4):
        root = hub.add_body(pos=[float(v) for v in centre + lay["roots"][k]],
                            quat=[float(np.cos(k * np.pi / 4)), 0.0, 0.0,
                                  float(np.sin(k * np.pi / 4))],
                            mass=1e-9, inertia=[1e-12] * 3, explicitinertial=True)
        _chain(root, np.zeros(3), 0, b["L"], n, b["m"], blade_inertia,
               (("torsion", 0, b["GJ"]), ("flap", 1, b["EI_flap"]), ("lag", 2, b["EI_lag"])),
               f"blade{k}", names)
    return spec.compile(), names


def mbc_transform(names: list, psi: float):
    """T(ψ), T′, T″ with q = T p over the coordinates in `names`: per blade coordinate the four
    blades' (b₀, b_c, b_s, b_d) in the four blades' slots; the shaft's rotating-frame bending
    angles from its fixed-frame ones; everything else unchanged."""
    idx = {nm: i for i, nm in enumerate(names)}
    n = len(names)
    T, T1, T2 = np.zeros((n, n)), np.zeros((n, n)), np.zeros((n, n))
    for i, (part, fam, h) in enumerate(names):
        if part == "blade0":
            rows = [idx[(f"blade{k}", fam, h)] for k in range(4)]
            for k, r in enumerate(rows):
                a = psi + k * np.pi / 2
                T[r, rows] = [1.0, np.cos(a), np.sin(a), (-1.0) ** k]
                T1[r, rows] = [0.0, -np.sin(a), np.cos(a), 0.0]
                T2[r, rows] = [0.0, -np.cos(a), -np.sin(a), 0.0]
        elif part == "shaft" and fam == "bend_x":
            j = [i, idx[("shaft", "bend_y", h)]]
            c, s = np.cos(psi), np.sin(psi)
            T[np.ix_(j, j)] = [[c, s], [-s, c]]
            T1[np.ix_(j, j)] = [[-s, c], [-c, -s]]
            T2[np.ix_(j, j)] = [[-c, -s], [s, -c]]
        elif not part.startswith("blade") and not (part == "shaft" and fam == "bend_y"):
            T[i, i] = 1.0
    return T, T1, T2


def linearised(params: dict, n: int, psi: float = 0.0, free: bool = False):
    """A_q = ∂q̈/∂q and A_v = ∂q̈/∂q̇ about steady spin at rotor azimuth ψ (drive removed), in
    the model's own coordinates (blades rotating, shaft bending rotating, the rest fixed), the
    coordinate names and the seconds spent in mjd_transitionFD."""
    import time
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


def mbc_matrices(params: dict, n: int, psi: float = 0.0, free: bool = False):
    """p̈ = K p + D ṗ in multi-blade coordinates (constant when the route is exact)."""
    Aq, Av, names, fd_s = linearised(params, n, psi, free)
    om = params["speed"]
    T, T1, T2 = mbc_transform(names, psi)
    Ti = np.linalg.inv(T)
    return (Ti @ (Aq @ T + om * Av @ T1 - om**2 * T2), Ti @ (Av @ T - 2 * om * T1), names,
            fd_s)


def fixed_frame_modes(params: dict, n: int, psi: float = 0.0, free: bool = False):
    """Eigenvalues (Im > 0, ascending) and eigenvectors in multi-blade coordinates, the
    coordinate names, and the seconds spent in mjd_transitionFD. Free: rigid-body roots
    (|s| < 1e-3 rad/s) dropped."""
    K, D, names, fd_s = mbc_matrices(params, n, psi, free)
    m = len(names)
    lam, V = np.linalg.eig(np.block([[np.zeros((m, m)), np.eye(m)], [K, D]]))
    scale = np.max(np.abs(lam))
    sel = (lam.imag > 1e-9 * scale) & (np.abs(lam) > 1e-3)
    order = np.argsort(lam.imag[sel])
    return lam[sel][order], V[:m, sel][:, order], names, fd_s


def classify(v: np.ndarray, names: list, speed_hz: float, f_hz: float):
    """Label and rotating-frame frequency of one fixed-frame mode from its coordinates: the
    share of |p|² in each blade family and multi-blade kind (cyclic: progressive when
    b_c + i b_s dominates b_c − i b_s) against the rest of the aircraft."""
    share: dict = {}
    cyc = {}
    for i, (part, fam, h) in enumerate(names):
        if part.startswith("blade"):
            kind = ("collective", "cyclic", "cyclic", "differential")[int(part[-1])]
            share[fam, kind] = share.get((fam, kind), 0.0) + abs(v[i]) ** 2
            if kind == "cyclic":
                cyc.setdefault((fam, h), [0j, 0j])[int(part[-1]) - 1] = v[i]
        else:
            share["aircraft", part] = share.get(("aircraft", part), 0.0) + abs(v[i]) ** 2
    (fam, kind) = max(share, key=share.get)
    if fam == "aircraft":
        return f"{kind} (fixed frame)", f_hz
    if kind != "cyclic":
        return f"{fam} {kind}", f_hz
    prog = sum(abs(c + 1j * s) ** 2 for c, s in cyc.values())
    regr = sum(abs(c - 1j * s) ** 2 for c, s in cyc.values())
    if regr >= prog:
        return f"{fam} cyclic regressive", f_hz + speed_hz
    return f"{fam} cyclic progressive", abs(f_hz - speed_hz)


def modes(params: dict, settings: dict | None = None) -> ModesResult:
    """The clamped helicopter (Table 3): see `aircraft_modes`."""
    return aircraft_modes(params, settings, free=False)


def hover_modes(params: dict, settings: dict | None = None) -> ModesResult:
    """The hovering (free) helicopter (Table 4), rigid-body roots dropped: see `aircraft_modes`."""
    return aircraft_modes(params, settings, free=True)


def aircraft_modes(params: dict, settings: dict | None, free: bool) -> ModesResult:
    """Fixed-frame frequencies (Hz) of the helicopter at params['speed'], N segments per
    blade and tail (N/2 on the shaft), Richardson-extrapolated from N/2 (pairs by nearest
    frequency); extra: the rotating-frame frequency each mode shows on the blades, the
    extrapolation's change per mode (its error estimate), the transitionFD seconds."""
    s = merge_settings(settings, MODES_SETTINGS, ())
    n = bc.checked_segments(s)
    lam, V, names, fd_s = fixed_frame_modes(params, n, s["psi"], free)
    f = lam.imag / (2 * np.pi)
    change = np.zeros_like(f)
    if s["extrapolate"]:
        lam2, _, _, fd2 = fixed_frame_modes(params, n // 2, s["psi"], free)
        fd_s += fd2
        f2 = lam2.imag / (2 * np.pi)
        k = min(len(f), len(f2), 3 * params["n_modes"])
        rows, cols = linear_sum_assignment(np.abs(f[:k, None] - f2[None, :k]))
        ext = f.copy()
        ext[rows] = (4 * f[rows] - f2[cols]) / 3
        change[rows] = ext[rows] - f[rows]
        f = ext
    order = np.argsort(f)
    speed_hz = params["speed"] / (2 * np.pi)
    rows = [classify(V[:, i], names, speed_hz, f[i]) for i in order]
    k = 3 * params["n_modes"]
    return ModesResult(frequencies_hz=f[order][:k], labels=[r[0] for r in rows][:k],
                       settings=s, notes=["fixed frame, multi-blade coordinates"],
                       extra={"rotating_frame_hz": [r[1] for r in rows][:k],
                              "richardson_change_hz": list(change[order][:k]),
                              "transition_fd_s": fd_s, "n_dof": len(names) + 1})
