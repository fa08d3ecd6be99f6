"""What both engine models of the whole helicopter (seed 002, Tables 3 and 4) are given alike:
the aircraft as a tree of rigid bodies with spring hinges, the multi-blade coordinate transform,
the eigen-solution and the labels. Each engine only turns the tree into its own model and
linearises it about steady spin (`reference_models/{mujoco,exudyn}/helicopter.py`).

Route. The rotor spins relative to a fuselage and tail that are not axisymmetric about the
shaft (fuselage inertia about X 0.50× that about Y, centre of mass 0.4 m off the axis, tail
boom along −X), so no single frame makes the physical system time-invariant in physical
coordinates: in the rotor frame the support turns, in the fixed frame the blades do. With
four identical blades on an isotropic hub and a round shaft, multi-blade coordinates
(collective b₀, cyclic b_c, b_s, differential b_d per blade coordinate; the shaft's bending
turned into the fixed frame) make it exactly time-invariant (Coleman): one linearisation at
any rotor azimuth ψ, q̈ = A_q q + A_v q̇, transformed with q = T(ψ) p,

    p̈ = T⁻¹[(A_q T + Ω A_v T′ − Ω² T″) p + (A_v T − 2Ω T′) ṗ],

gives constant matrices — `tests/engines/test_helicopter_engines.py` checks that they do not depend
on ψ. This needs neither a time-domain identification (close roots 6.30–6.37 Hz would need
records of minutes) nor Floquet analysis (one linearisation instead of many).

The tree: the blades, shaft and tail boom in the rigid-finite-element layout of
beam_chain_common (blades as the rotating-beam model: torsion, flap, lag hinges and the
section's rotary inertia, the torsion springs with the tension–torsion term when it is on;
shaft: two bending hinges and torsion, tail: torsion and two bending hinges, both with their
section's rotary inertia, which the engines need for a physical body),
the hub and fuselage rigid, the drive at the shaft's foot a hinge about z spinning at Ω (its
coordinate held: the speed is prescribed), the tail's far end clamped (Table 3) or the
fuselage free (Table 4). No axial flexibility (the paper's 24.1 Hz 'axial cyclic' root has
none here). The frequencies are fixed-frame; a cyclic mode at ω_F is seen on the blades at
ω_F + Ω (regressive) or |ω_F − Ω| (progressive), given in extra['rotating_frame_hz'] for
comparison with mstmm, which writes the whole aircraft in the rotor frame.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
from scipy.linalg import lu_factor, lu_solve
from scipy.optimize import linear_sum_assignment

from compare.contract import LeafModes, merge_settings
from compare.physics import eigen
from compare.physics.mstmm import blade_section_from, helicopter_layout, root_tension_wavenumber
from reference_models import beam_chain_common as bc

MODES_SETTINGS = {"n_segments": 40, "extrapolate": True, "psi": 0.0}
FD_VARY = bc.FD_VARY       # the finite-difference step × this: the linearisation's own error
# and × this: where the forward differences are rounding-bound (Exudyn's at 1e-8), the ×10
# probe's change can be small by chance, truncation there cancelling rounding (hover, `xval
# calibrate --seed 3030` set 0, root 1: Exudyn 7.5e-8 off MuJoCo, the ×10 bar 5e-8); rounding
# changes completely at a step ×3 away (the root moved 5.5e-8), truncation hardly
FD_NEAR = 3.0
SPIN = ("drive", "spin", 0)                # the coordinate held at speed Ω
TINY_MASS, TINY_INERTIA = 1e-9, 1e-12      # the massless frames (drive, blade roots)
# the aircraft's extrapolates in their 1/N² regime were off by up to 2.1 × diff/7 against the
# 2N–N one (helicopter-hover's ninth calibration set at 66 rad/s, a 4.46 Hz root, 7.9e-6 Hz
# off; clamped's second at 61 rad/s, 1.2 ×): its roots mix (veering clusters) more than the
# beams' chains. 1.9 × was read while Exudyn's 1e-9 finite-difference step added its rounding
# to the bar (exudyn/helicopter.py FD_SCALE); at 2.0 the root then sat at 1.02 × its bar.
EXTRAPOLATE_SAFETY = 2.5


@dataclass
class Body:
    """A rigid body of the tree: pose in its parent's frame, inertia about its centre of mass
    in its own frame (principal, diagonal), and the joints between parent and body, applied
    in order at the body's origin: (coordinate name, kind, axis, stiffness) with kind
    'hinge' (a spring hinge), 'slide' or 'spin' (the drive, held at speed)."""
    parent: int
    pos: np.ndarray
    mass: float
    com: np.ndarray
    inertia: np.ndarray
    rot: np.ndarray = field(default_factory=lambda: np.eye(3))
    joints: list = field(default_factory=list)


def _inertia(m_line, ell, axial, b1, b2, axis):
    principal = bc.segment_inertia(m_line, ell, axial, b1, b2)    # [along, t1, t2]
    out = np.zeros(3)
    out[axis], out[[i for i in range(3) if i != axis]] = principal[0], principal[1:]
    return out


def _chain(bodies, parent, start, axis, L, n, m_line, inertia, joints, tag, sign=1.0):
    """n-hinge chain from `start` (parent frame) along unit axis `axis` (− with sign −1);
    joints (name, axis, k): k the section stiffness (spring k/Δl) or a function of the layout
    giving the spring per hinge. Returns the index of the last body and the position of its
    hinge relative to `start`. The piece before the first hinge (ΔL/2) moves with the parent
    — a hub, a free fuselage — so it is a body welded to it: dropped, the hub lacked four
    blade roots' mass, and the modes that move it converged as ΔL, not ΔL²
    (helicopter-clamped's tenth calibration set at rest, lag collective 1 at N = 10…80: 2.9757,
    3.0451, 3.0249, 3.0152 Hz toward mstmm's 3.0057, its h² Richardson bar 1.9 × short)."""
    lay = bc.layout(L, n)
    e = sign * np.eye(3)[axis]
    springs = [k(lay) if callable(k) else np.full(n, k / lay["dl"]) for _, _, k in joints]
    if parent >= 0:                    # a chain from the ground has its root piece clamped
        root = lay["hinges"][0]
        bodies.append(Body(parent, np.asarray(start, float), m_line * root, 0.5 * root * e,
                           inertia(root)))
    prev = None
    for i, x in enumerate(lay["hinges"]):
        ell = lay["lengths"][i]
        bodies.append(Body(parent, np.asarray(start) + x * e if prev is None else (x - prev) * e,
                           m_line * ell, 0.5 * ell * e, inertia(ell),
                           joints=[((tag, name, i), "hinge", ax, float(k[i]))
                                   for (name, ax, _), k in zip(joints, springs)]))
        parent, prev = len(bodies) - 1, x
    return parent, prev * e


def tree(params: dict, n: int, free: bool = False, sections: float = 1.0) -> list:
    """The aircraft as bodies (parents before children). Clamped: the tree grows from the
    tail's far end (parent −1 is the ground); free: from the fuselage on six joints, the
    tail boom hanging from its rear face. N hinges per blade and tail, N/2 on the shaft.
    `sections`: the factor on the sections' rotary inertia about their bending axes, which
    the Euler–Bernoulli beams of the paper's model have not (torsion keeps its own)."""
    lay = helicopter_layout(params)
    t, f, s, b = lay["tail"], lay["fuselage"], lay["shaft"], lay["blade"]
    on = sections
    half = on * t["I_alpha"] / 2
    out: list = []

    def tail_chain(parent, start, sign):
        return _chain(out, parent, start, 0, t["L"], n, t["m"],
                      lambda ell: _inertia(t["m"], ell, t["I_alpha"], half, half, 0),
                      (("torsion", 0, t["GJ"]), ("bend_y", 1, t["EI_flap"]),
                       ("bend_z", 2, t["EI_lag"])), "tail", sign)
    ground, spin = -1, [(SPIN, "spin", 2, 0.0)]
    if free:                        # six coordinates: x, y, z, then turns about x, y, z
        out.append(Body(ground, f["rear"], f["m"], f["cm"] - f["rear"], f["I"],
                        joints=[(("fuselage", "free", a), "slide", a, 0.0) for a in range(3)]
                        + [(("fuselage", "free", 3 + a), "hinge", a, 0.0) for a in range(3)]))
        fus = len(out) - 1
        tail_chain(fus, np.zeros(3), -1.0)
    else:
        last, tip = tail_chain(ground, t["end"], 1.0)
        out.append(Body(last, f["rear"] - (t["end"] + tip), f["m"], f["cm"] - f["rear"],
                        f["I"]))
        fus = len(out) - 1
    out.append(Body(fus, s["bottom"] - f["rear"], TINY_MASS, np.zeros(3), [TINY_INERTIA] * 3,
                    joints=spin))
    rot = on * s["I_p"] / 2
    top, tip = _chain(out, len(out) - 1, np.zeros(3), 2, s["L"], max(n // 2, 2), s["m"],
                      lambda ell: _inertia(s["m"], ell, s["I_p"], rot, rot, 2),
                      (("bend_x", 0, s["EI"]), ("bend_y", 1, s["EI"]), ("torsion", 2, s["GJ"])),
                      "shaft")
    out.append(Body(top, s["top"] - (s["bottom"] + tip), lay["hub"]["m"],
                    np.array([0.0, 0.0, -s["top"][2]]), lay["hub"]["I"]))
    hub, centre, rho = len(out) - 1, -s["top"], on * params["blade_rho"]

    def blade_inertia(ell):
        return _inertia(b["m"], ell, b["I_alpha"], rho * b["I_flap"], rho * b["I_lag"], 0)

    def blade_torsion(bl):        # GJ + T_i k_A² per hinge (the tension–torsion term)
        return bc.torsion_springs(bl, b["GJ"], b["k_A2"], b["m"], params["speed"],
                                  params["hub_radius"])
    for k in range(4):
        c, sn = np.cos(k * np.pi / 2), np.sin(k * np.pi / 2)
        out.append(Body(hub, centre + lay["roots"][k], TINY_MASS, np.zeros(3),
                        [TINY_INERTIA] * 3, rot=np.array([[c, -sn, 0], [sn, c, 0], [0, 0, 1]])))
        _chain(out, len(out) - 1, np.zeros(3), 0, b["L"], n, b["m"], blade_inertia,
               (("torsion", 0, blade_torsion), ("flap", 1, b["EI_flap"]),
                ("lag", 2, b["EI_lag"])), f"blade{k}")
    return out


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


def mbc_matrices(linearised, params: dict, n: int, psi: float = 0.0, free: bool = False):
    """p̈ = K p + D ṗ in multi-blade coordinates (constant when the route is exact), from an
    engine's `linearised(params, n, psi, free) -> (A_q, A_v, names, seconds)`."""
    Aq, Av, names, secs = linearised(params, n, psi, free)
    om = params["speed"]
    T, T1, T2 = mbc_transform(names, psi)
    Ti = np.linalg.inv(T)
    return (Ti @ (Aq @ T + om * Av @ T1 - om**2 * T2), Ti @ (Av @ T - 2 * om * T1), names,
            secs)


# A root grows when Re s exceeds this. Numerical noise of Re s (both engines, both scenes,
# N = 20 and 40): at rest ≤ 9.1e-10 1/s on the oscillating roots, ≤ 1.4e-11 on the free
# aircraft's rigid-body roots; spinning ≤ 4.1e-5 (oscillating) and ≤ 1.04e-4 (rigid-body): the
# finite differences of the velocity Jacobian (2.5e-5 relative, see the engines' modules).
# 10 × the largest noise; a growth time of 1000 s. The high roots' noise grows with |s|:
# MuJoCo's at helicopter-hover, `xval calibrate --seed 4242` set 15 (Ω 69 rad/s, N = 40): up to
# 1.9e-7 |s| (Re 1.03e-3 at 5567 rad/s, 52 roots above 1e-4 between 3e3 and 2.3e4 rad/s;
# Exudyn's none), so a growth also exceeds GROWTH_REL |s|, 5 × that.
GROWTH_TOL = 1e-3
GROWTH_REL = 1e-6
RIGID_BODY = 1e-3       # |s| [1/s] below: the free aircraft's rigid-body roots (noise ≤ 1.1e-4)


def _state(K, D):
    m = K.shape[0]
    return np.block([[np.zeros((m, m)), np.eye(m)], [K, D]])


def roots(linearised, params: dict, n: int, psi: float = 0.0, free: bool = False,
          vary: int = 0, sections: bool = False):
    """Every root s of p̈ = K p + D ṗ with Im s ≥ 0 — oscillating, real (growing or decaying)
    and rigid-body alike — and its eigenvector in multi-blade coordinates, the coordinate
    names, the seconds the engine spent linearising and, for the lowest `vary` oscillating
    roots, (|δs| the engine's finite-difference step × FD_VARY makes, or × FD_NEAR's rescaled
    to it where larger — first order, a cluster by its Gershgorin discs:
    compare.physics.eigen.change —, the eigen solve's spread
    (eigen.solve_spread), |δs| the sections' rotary inertia makes where `sections`, first
    order: the change on removing it), NaN for the others; None where `vary` is 0. The
    sections' shift is taken at rest only: there, removing them leaves the paper's beams
    exactly (Exudyn without them meets mstmm on the differential modes to 1e-7); spinning, a
    rigid segment keeps its torsion inertia's centrifugal moment on flap, which the paper's
    blade has not (helicopter-hover at its defaults: flap differential 1 moves 9.0e-4 without
    them, while mstmm sits 3.8e-5 from the engine with them)."""
    K, D, names, secs = mbc_matrices(linearised, params, n, psi, free)
    m = len(names)
    A = _state(K, D)
    lam, V = np.linalg.eig(A)
    # the shape from the velocity half, v/s: LAPACK's position half carries its backward
    # error, ε‖A‖ (‖A‖ ~ 1e11 by the 1e-9 kg frames), on a shape |s| times smaller — on
    # Exudyn's free aircraft (its ignorable coordinates' columns exactly zero) it misses
    # (K + sD − s²)p = 0 by 0.6 % of s²p at the median mode, 99 % at the worst, v/s by 5e-10
    # (helicopter-hover, `xval calibrate --seed 4242` set 4); MuJoCo's by 1e-8 either way
    away = np.abs(lam) > RIGID_BODY
    V[:m, away] = V[m:, away] / lam[away]
    keep = lam.imag >= 0
    moved = None
    if vary:     # the oscillating roots only (the free aircraft's rigid-body roots are nearly
        idx = np.nonzero(_is_mode(lam) & keep)[0]     # defective, their dual rows huge), their
        idx = idx[np.argsort(lam[idx].imag)][:vary]   # dual rows alone
        W = lu_solve(lu_factor(V), np.eye(len(lam))[:, idx], trans=1).T
        lam_v, V_v = lam[idx], V[:, idx]
        change = []
        for scale in (FD_VARY, FD_NEAR):
            K2, D2, _, secs2 = mbc_matrices(
                lambda *a, scale=scale: linearised(*a, fd_scale=scale), params, n, psi, free)
            secs += secs2
            change.append(eigen.change(_state(K2, D2) - A, lam_v, V_v, W)[1])
        moved = np.full((3, len(lam)), np.nan)
        # the step's error read off either probe as the ×FD_VARY one is read (its change over
        # 1 − 1/FD_VARY): the near one's change over 1 − 1/FD_NEAR
        near = change[1] * (1 - 1 / FD_VARY) / (1 - 1 / FD_NEAR)
        moved[:2, idx] = np.maximum(change[0], near), eigen.solve_spread(A, lam_v)
        if sections and params["speed"] == 0:      # their own shift: at rest only (above)
            K3, D3, _, secs3 = mbc_matrices(
                lambda *a: linearised(*a, sections=0.0), params, n, psi, free)
            secs += secs3
            moved[2, idx] = eigen.change(_state(K3, D3) - A, lam_v, V_v, W)[1]
        moved = moved[:, keep]
    return lam[keep], V[:m, keep], names, secs, moved


def _is_mode(lam):
    """The oscillating roots that are modes: Im s > 0 beyond round-off, not rigid-body."""
    return (lam.imag > 1e-9 * np.max(np.abs(lam))) & (np.abs(lam) > RIGID_BODY)


def growing(lam: np.ndarray) -> np.ndarray:
    """Re s of the roots that grow (Re s > GROWTH_TOL + GROWTH_REL |s|), oscillating or real,
    largest first."""
    g = lam.real[(lam.real > GROWTH_TOL + GROWTH_REL * np.abs(lam)) & (np.abs(lam) > RIGID_BODY)]
    return np.sort(g)[::-1]


def oscillating(linearised, params: dict, n: int, psi: float = 0.0, free: bool = False,
                vary: int = 0, sections: bool = False):
    """The oscillating roots (Im > 0, ascending) and their eigenvectors in multi-blade
    coordinates, the coordinate names, the seconds the engine spent linearising, every root
    (`roots`: real ones included, for the stability finding) and, for the lowest `vary`, each
    oscillating root's linearisation error (Hz; NaN beyond): the change the step × FD_VARY
    makes over 1 − 1/FD_VARY (or × FD_NEAR's over 1 − 1/FD_NEAR, where larger),
    × LINEARISATION_SAFETY, plus the eigen solve's spread (with its
    own safety: compare.physics.eigen.solve_spread) — and the first-order
    shift its sections' rotary inertia makes (Hz; `roots`). The aircraft's finite
    differences are bound by rounding, not by their h² truncation as the beams' chains are
    (beam_chain_common.quadratic_modes): M is ill-conditioned by the 1e-9 kg frames (Exudyn's
    step: exudyn/helicopter.py FD_SCALE, measured against MuJoCo). Rigid-body roots
    (|s| < RIGID_BODY) are not modes."""
    lam, V, names, secs, moved = roots(linearised, params, n, psi, free, vary, sections)
    sel = _is_mode(lam)
    order = np.argsort(lam.imag[sel])
    err = shift = None
    if moved is not None:
        moved = moved[:, sel][:, order] / (2 * np.pi)
        # the safety on the step's change only: the spread carries its own (SPREAD_SAFETY)
        err = bc.LINEARISATION_SAFETY * moved[0] / (1 - 1 / FD_VARY) + moved[1]
        shift = None if np.isnan(moved[2]).all() else moved[2]
    return lam[sel][order], V[:, sel][:, order], names, secs, lam, err, shift


SECTIONS = "the sections' rotary inertia"   # about their bending axes: the paper's beams have none
BLADE_SHARE = 0.3   # a mode whose blades hold this share of |p|² is named after the blades


def _in_order_sum(rows):
    """Sum over the first axis one row after another, as a Python loop adds (numpy's own sum
    is pairwise: other roundings, which could tip a tie between two shares)."""
    return np.cumsum(rows, axis=0)[-1]


def classify(V: np.ndarray, names: list) -> list:
    """(family, kind, sense) of each mode (column of V) from its multi-blade coordinates: the
    blade family and multi-blade kind with the largest share of |p|² when the blades hold at
    least BLADE_SHARE of it (a lag collective coupled with shaft torsion is a lag mode), else
    the aircraft part that holds most; sense of a cyclic mode: 'progressive' when b_c + i b_s
    dominates b_c − i b_s, else 'regressive'. All modes at once, over the coordinates grouped
    once: 0.004 s against 0.13 s for a loop over each mode's coordinates (MuJoCo's hovering
    aircraft at N = 20: 331 modes, 336 coordinates), which was ~12 % of the engines' helicopter
    tests. Every sum runs in coordinate order (`_in_order_sum`) and the first group wins a
    tie, as such a loop does: the names are the loop's (test_helicopter_engines)."""
    groups: dict = {}                                    # (family, kind) -> coordinate rows
    cyc: dict = {}                                       # (family, h) -> [b_c row, b_s row]
    for i, (part, fam, h) in enumerate(names):
        if part.startswith("blade"):
            kind = ("collective", "cyclic", "cyclic", "differential")[int(part[-1])]
            groups.setdefault((fam, kind), []).append(i)
            if kind == "cyclic":
                cyc.setdefault((fam, h), [-1, -1])[int(part[-1]) - 1] = i
        else:
            groups.setdefault((part, ""), []).append(i)
    a2 = np.abs(V) ** 2
    keys = list(groups)
    share = np.array([_in_order_sum(a2[groups[k]]) for k in keys])
    blade_rows = sorted(i for k in keys if k[1] for i in groups[k])
    blades = _in_order_sum(a2[blade_rows]) if blade_rows else np.zeros(V.shape[1])
    total = _in_order_sum(share)
    is_blade = np.array([bool(k[1]) for k in keys])
    on_blades = blades >= BLADE_SHARE * total
    pick = np.where(on_blades, np.argmax(np.where(is_blade[:, None], share, -np.inf), axis=0),
                    np.argmax(np.where(is_blade[:, None], -np.inf, share), axis=0))
    zero = np.zeros(V.shape[1], complex)
    pairs = [[V[j] if j >= 0 else zero for j in cs] for cs in cyc.values()]
    prog = _in_order_sum([np.abs(c + 1j * sn) ** 2 for c, sn in pairs]) if pairs else 0
    regr = _in_order_sum([np.abs(c - 1j * sn) ** 2 for c, sn in pairs]) if pairs else 0
    sense = np.where(regr >= prog, "regressive", "progressive")
    return [(*keys[g], str(sense[i]) if keys[g][1] == "cyclic" else "")
            for i, g in enumerate(pick)]


def richardson_pairs(f, kinds, f2, kinds2):
    """(rows, cols): each root of the fine model paired with the same root of the coarse one,
    by the least total |Δf| where a pair of two (family, kind) counts double. A cluster's
    roots move by more than their spacing between N/2 and N, so frequency alone can pair the
    flap differential root of one with the lag collective of the other (helicopter-clamped's
    first calibration set: 3.70413/3.72545 Hz and 3.70609/3.70736 Hz tie at 0.02259 Hz either
    way, the extrapolated flap differential then 3.70305 Hz where the chain's isolated blade,
    which a reactionless mode must equal, has 3.69702). A mismatch is only penalised, not
    barred: at rest the four blades' roots are degenerate and their names arbitrary, and a
    root may change kind between N/2 and N where two kinds mix."""
    same = np.array([[a[:2] == b[:2] for b in kinds2] for a in kinds])
    return linear_sum_assignment(np.abs(f[:, None] - f2[None, :]) * np.where(same, 1.0, 2.0))


# The chains resolve the blade's root boundary layer, √(EI_flap/T) under the centrifugal tension
# T, only while the N/2 chain's segments span at most ENGINE_TENSION_SPAN of it (the Richardson
# pair is N/2 and N). helicopter-clamped, `xval calibrate --seed 777` set 17 (a 10 m blade at
# 66 rad/s, span 12.2): flap differential 1 0.079 Hz off mstmm against its bar 0.0071 at N =
# 40, 0.0117 against 0.0152 at N = 80; at 7.4 (seed 11 set 9) both aircraft agreed.
ENGINE_TENSION_SPAN = 10.0


def segment_refinement(params: dict, n: int) -> int:
    """The factor on n_segments that keeps the N/2 chain's blade segments within
    ENGINE_TENSION_SPAN tension lengths at the root (1 at the defaults)."""
    sec, L = blade_section_from(params, "blade_"), params["blade_L"]
    span = (2 * L / n) * root_tension_wavenumber(sec["m"], sec["EI_flap"], L, params["speed"],
                                                 params["hub_radius"])
    return max(1, int(np.ceil(span / ENGINE_TENSION_SPAN)))


def _frequencies(linearised, params, s, free):
    """Frequencies (Hz, Richardson-extrapolated from N/2 when asked: `richardson_pairs`), the
    extrapolation's change, the extrapolate's error (against the N/2–N/4 extrapolate:
    bc.extrapolate_error), the (family, kind, sense) of each mode, the seconds spent
    linearising, the number of coordinates, every root (the finer model's), each frequency's
    linearisation error (what one engine's finite differences add, which the other engine of
    this one model does not share) and the first-order shift of its sections' rotary inertia,
    in ascending order."""
    n = bc.checked_segments(s)
    # the linearisation error of the roots Richardson pairs, which hold every one reported
    m = 3 * params["n_modes"] + 12
    lam, V, names, secs, every, lin, sections = oscillating(linearised, params, n, s["psi"],
                                                            free, m, sections=True)
    f = lam.imag / (2 * np.pi)
    kinds = classify(V, names)
    change = np.zeros_like(f)
    error = np.zeros_like(f)
    undecided = np.zeros(0)
    if s["extrapolate"]:
        lam2, V2, names2, secs2, _, lin2, _ = oscillating(linearised, params, n // 2,
                                                          s["psi"], free, m)
        secs += secs2
        f2 = lam2.imag / (2 * np.pi)
        kinds2 = classify(V2, names2)
        m = min(len(f), len(f2), m)
        rows, cols = richardson_pairs(f[:m], kinds[:m], f2[:m], kinds2[:m])
        ext = f.copy()
        ext[rows] = (4 * f[rows] - f2[cols]) / 3
        change[rows] = ext[rows] - f[rows]
        # the extrapolate's own error: against the N/2–N/4 extrapolate, as the beams' chains
        # (bc.extrapolate_error); the whole change where there is no N/4 model or root
        diff, ratio = np.full_like(f, np.inf), np.full_like(f, np.nan)
        if n % 4 == 0 and n // 4 >= 2:
            lam4, V4, names4, secs4, *_ = oscillating(linearised, params, n // 4, s["psi"],
                                                      free)
            secs += secs4
            f4 = lam4.imag / (2 * np.pi)
            k = min(m, len(f4))
            low, coarse = np.full_like(f2, np.nan), np.full_like(f2, np.nan)
            r2, c4 = richardson_pairs(f2[:k], kinds2[:k], f4[:k], classify(V4[:, :k], names4))
            low[r2] = (4 * f2[r2] - f4[c4]) / 3
            coarse[r2] = f4[c4] - f2[r2]
            diff[rows] = np.nan_to_num(np.abs(ext[rows] - low[cols]), nan=np.inf)
            with np.errstate(divide="ignore", invalid="ignore"):
                ratio[rows] = coarse[cols] / (f2[cols] - f[rows])
        error = bc.extrapolate_error(diff, np.abs(change), ratio, EXTRAPOLATE_SAFETY)
        f = ext
        # 4/3 of the N model's and 1/3 of the N/2 one's, each its own: the coarse model's
        # rounding can be the larger (helicopter-hover's ninth calibration set at 66 rad/s, a
        # 16.24 Hz root: Exudyn–MuJoCo 1.7e-8 apart at N = 40, 1.7e-6 at N = 20)
        bar, undecided = coalescence_error(lam, lam2, rows, cols)
        error = np.maximum(error, bar)
        lin_ext = np.full_like(lin, np.nan)
        lin_ext[rows] = (4 * lin[rows] + lin2[cols]) / 3
        lin = lin_ext
    return f, change, error, kinds, secs, len(names), every, lin, sections, undecided


# Two roots coalesce where a regressive lag root meets a body mode (ground resonance, the
# undamped aircraft's own instability): one Im, Re ±a. Near that edge the chain's length moves
# the pair through the bifurcation, not along a 1/N² curve — helicopter-hover, `xval calibrate
# --seed 4242` set 8 (an 11.7 m blade at 44 rad/s): coalesced at N = 20 and 40 (Re 1.23 and
# 0.36 /s), split at N = 80 (2.541/2.790 Hz), the N = 40 extrapolate 0.18 Hz off the 2N–N one
# against a Richardson bar of 0.023. What changes smoothly is the pair's discriminant δ — a²
# coalesced, −(gap/2)² split (s = c ± √δ) —: 1.517, 0.127, −0.613 (1/s)² at N = 20, 40, 80,
# each change about half the last: δ's remaining change is about its last one, which moves
# the pair's roots by up to √|δ_N − δ_N/2| (× COALESCENCE_SAFETY).
COALESCED = 1e-8            # relative Im spread within which two roots are one coalesced pair
COALESCENCE_SAFETY = 2.0


def discriminants(lam):
    """Per oscillating root (Im ascending): δ of the pair it belongs to — a² where a root of
    the same Im (within COALESCED of |s|) mirrors it, Re ±a; else −(gap/2)², the gap to its
    nearest root in Im (rad/s) — and whether it is coalesced."""
    lam = np.asarray(lam, complex)
    d, co = np.zeros(len(lam)), np.zeros(len(lam), bool)
    for i, s in enumerate(lam):
        gaps = np.abs(lam.imag - s.imag)
        gaps[i] = np.inf
        j = int(np.argmin(gaps)) if len(lam) > 1 else i
        grows = abs(s.real) > GROWTH_TOL + GROWTH_REL * abs(s)
        if j != i and gaps[j] <= COALESCED * abs(s) and grows and s.real * lam[j].real < 0:
            d[i], co[i] = s.real ** 2, True
        elif j != i:
            d[i] = -(gaps[j] / 2) ** 2
    return d, co


def coalescence_error(lam, lam2, rows, cols):
    """(the frequency error (Hz) of each root Richardson paired — rows at N, cols at N/2 —
    that is coalesced in either model: COALESCENCE_SAFETY · √|δ_N − δ_N/2| / 2π, 0 elsewhere;
    Re s of the N model's growing coalesced roots whose growth that change can undo: δ_N within
    COALESCENCE_SAFETY · |δ_N − δ_N/2| of zero)."""
    d, co = discriminants(lam)
    d2, co2 = discriminants(lam2)
    out = np.zeros(len(lam))
    moves = np.abs(d[rows] - d2[cols])
    near = co[rows] | co2[cols]
    out[rows[near]] = COALESCENCE_SAFETY * np.sqrt(moves[near]) / (2 * np.pi)
    undone = rows[co[rows] & (d[rows] <= COALESCENCE_SAFETY * moves) & (lam.real[rows] > 0)]
    return out, lam.real[undone]


def _on_blades(f, kinds, speed_hz):
    """The frequency each fixed-frame mode shows on the blades (the rotor frame the paper
    writes): a regressive cyclic mode at f + Ω, a progressive one at |f − Ω|."""
    shift = {"regressive": speed_hz, "progressive": -speed_hz, "": 0.0}
    return np.abs(f + np.array([shift[k[2]] for k in kinds]))


def _labels(kinds):
    """mstmm's names, numbered in the given order within each family and kind: 'flap cyclic
    1', 'lag collective 1', 'fuselage 2'."""
    count: dict = {}
    out = []
    for fam, kind, _ in kinds:
        key = f"{fam} {kind}".strip()
        count[key] = count.get(key, 0) + 1
        out.append(f"{key} {count[key]}")
    return out


def aircraft_modes(linearised, params: dict, settings: dict | None, free: bool,
                   note: str) -> LeafModes:
    """The helicopter at params['speed'] as the paper reports it: each mode's frequency on the
    blades (Hz, ascending; fixed-frame cyclic modes shifted by ±Ω), named as mstmm names them
    (numbered by frequency within each family and kind).
    N segments per blade and tail (N/2 on the shaft), Richardson-extrapolated from N/2.

    extra: `fixed_frame_hz` (the frequency an observer on the fuselage sees), `whirl`
    (regressive / progressive for cyclic modes), `richardson_change_hz` (the extrapolation's
    change), `frequency_error_hz` (the extrapolate's error against the N/2–N/4 one,
    bc.extrapolate_error; the linearisation's apart: at rest its first-order bound on the
    free aircraft's degenerate blade roots reaches Hz), the stability finding: `finding`
    ('stable', 'unstable', or 'undecided' where the only growing roots are a coalesced pair
    the chains' refinement can split: `coalescence_error`), `unstable` (Re s of every growing
    root but those, 1/s, also in the notes), `coalescing` (theirs),
    `max_re_per_s` (the largest Re s of any root), `real_roots_per_s` (the non-oscillating
    roots beyond the rigid-body ones), `linearisation_error_hz` (what the engine's finite
    differences add: the error the two engines of this model do not share); `roots_hz`,
    `roots_error_hz`, `roots_linearisation_error_hz`: every fixed-frame root up to the highest
    one reported, ascending and unnamed (compare.analysis.metrics.by_root);
    `model_differences` (at rest): {SECTIONS: how far the sections' rotary inertia moves
    each mode, first order} (the paper's Euler–Bernoulli beams have none:
    metrics.model_allowance)."""
    s = merge_settings(settings, MODES_SETTINGS, ())
    # the chains a run uses, refined where the blade is a string (its settings say so)
    refine = segment_refinement(params, bc.checked_segments(s))
    s = {**s, "n_segments": refine * s["n_segments"]}
    t0 = time.perf_counter()
    f, change, error, kinds, secs, n_dof, every, lin, sections, undecided = _frequencies(
        linearised, params, s, free)
    grow = growing(every)
    edge = np.isin(grow, undecided)
    grow, edge = grow[~edge], grow[edge]
    real = np.sort(every.real[(np.abs(every.imag) <= 1e-9 * np.max(np.abs(every)))
                              & (np.abs(every) > RIGID_BODY)])
    notes = [note] + ([f"unstable: {len(grow)} growing root(s), Re s = "
                       f"{np.round(grow, 4).tolist()} 1/s (> {GROWTH_TOL:g} + "
                       f"{GROWTH_REL:g} |s|)"] if len(grow) else [])
    if len(edge):
        notes.append(f"undecided: {len(edge)} coalesced root(s) at the edge of ground "
                     f"resonance, Re s = {np.round(edge, 4).tolist()} 1/s, which the chains' "
                     f"refinement can undo (the pair's discriminant moves by as much from N/2 "
                     f"to N)")
    if refine > 1:
        notes.append(f"chains ×{refine}: the N/2 chain's blade segments within "
                     f"{ENGINE_TENSION_SPAN:g} tension lengths at the root")
    blade_f = _on_blades(f, kinds, params["speed"] / (2 * np.pi))
    order = np.argsort(blade_f)
    k = params["n_modes"]
    kinds = [kinds[i] for i in order]
    up = np.argsort(f)                 # the roots up to the highest one reported, unnamed
    up = up[f[up] <= np.max(f[order][:k])]
    return LeafModes(frequencies_hz=blade_f[order][:k], labels=_labels(kinds)[:k],
                       settings=s, notes=notes,
                       extra={"finding": "unstable" if len(grow) else
                              "undecided" if len(edge) else "stable",
                              "unstable": grow.tolist(), "coalescing": edge.tolist(),
                              "max_re_per_s": float(every.real.max()),
                              "real_roots_per_s": real.tolist(),
                              "fixed_frame_hz": f[order][:k],
                              "whirl": [w for _, _, w in kinds][:k],
                              "richardson_change_hz": change[order][:k],
                              "frequency_error_hz": error[order][:k],
                              "linearisation_error_hz": lin[order][:k],
                              **({} if sections is None else {"model_differences": {
                                  SECTIONS: sections[order][:k]}}),
                              "roots_hz": f[up], "roots_error_hz": error[up],
                              "roots_linearisation_error_hz": lin[up],
                              "linearise_s": secs, "modes_s": time.perf_counter() - t0,
                              "n_dof": n_dof + 1})
