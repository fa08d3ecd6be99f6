"""What both engine models of the MSTMM beams (`rotating-beam`, `spinning-shaft`) are given
alike: the rigid-finite-element layout of a cantilever, the per-segment inertia, the stations
where mode shapes are sampled, and the post-processing of the linearised system (quadratic
eigenproblem, labels, shapes). The dynamics (centrifugal, Coriolis, the chain's inertia) stay in
each engine.

Layout (the MuJoCo notes §4, "rigid-finite-element" layout, second order in 1/N): N hinges at
x_i = (i − ½)Δl, Δl = L/N, each with springs EI/Δl (bending) and GJ/Δl (torsion, plus
T_i k_A²/Δl with the tension–torsion term); the root
piece [0, Δl/2] is clamped, N − 1 bodies of length Δl and the last of length Δl/2.
"""
from __future__ import annotations

import numpy as np

from compare.physics import eigen, mstmm
from compare.physics.whirl import whirl_labels

N_STATIONS = 10     # mode shapes sampled at x_k = k·L/10, k = 1..10 (every speed alike)


def layout(L: float, n: int) -> dict:
    """Hinge positions (from the root), body lengths and body centres of an n-hinge chain."""
    dl = L / n
    hinges = (np.arange(1, n + 1) - 0.5) * dl
    ends = np.append(hinges[1:], L)
    lengths = ends - hinges
    return {"dl": dl, "hinges": hinges, "lengths": lengths}


def segment_inertia(m_line: float, length: float, axial: float, bend1: float, bend2: float
                    ) -> np.ndarray:
    """Principal inertia about the segment's centre (axis 0 along the beam): the line mass's
    m ℓ²/12 about both transverse axes plus the section terms ρ·ℓ·(∫ dA) given per length:
    `axial` about the beam axis, `bend1`/`bend2` about transverse axes 1 and 2."""
    m = m_line * length
    return np.array([axial * length, m * length**2 / 12 + bend1 * length,
                     m * length**2 / 12 + bend2 * length])


def chain_tension(lay: dict, m_line: float, spin: float, root: float) -> np.ndarray:
    """The chain's own centrifugal tension at each hinge: Ω² Σ m_j r_j over the bodies
    outboard of it (r_j the body's centre radius, root offset r_H included)."""
    centres = root + lay["hinges"] + 0.5 * lay["lengths"]
    pull = spin**2 * m_line * lay["lengths"] * centres
    return np.cumsum(pull[::-1])[::-1]


def torsion_springs(lay: dict, GJ: float, k_A2: float, m_line: float, spin: float,
                    root: float) -> np.ndarray:
    """Torsion hinge stiffness per hinge, (GJ + T_i k_A²)/Δl: the tension–torsion term
    (k_A2 = 0 when off) from the chain's own tension T_i at the hinge. A rigid-segment chain
    has no such term of its own (a hinge on the axis: the tension passes through it)."""
    return (GJ + k_A2 * chain_tension(lay, m_line, spin, root)) / lay["dl"]


def blade_chain(params: dict, section: dict, n: int, rotary_inertia: bool = True) -> dict:
    """Rigid-segment blade along x from the root at x = r_H, spinning about z at `speed`.

    Joints per hinge, in this order: torsion (about x, GJ/Δl, or (GJ + T_i k_A²)/Δl with the
    tension–torsion term), flap (about y: out of the rotor plane, EI_flap/Δl), lag (about z:
    in the plane, EI_lag/Δl); stiffness per hinge. Segment inertia: the line mass
    plus the section's ρ∫z²dA = ρI_flap (about y), ρ∫y²dA = ρI_lag (about z), I_α (about x).
    These section terms are what make the rotating-frame terms of a rigid section come out
    right: the torsion 'propeller' stiffness Ω²(I_zz − I_yy) = Ω²ρ(I_lag − I_flap) per length
    (the paper's eq. 30 writes Ω²I_α = Ω²ρ(I_lag + I_flap): 1.3 % more on the Ω² part, 0.03 %
    on the torsion frequency at 40 rad/s) and no flap–torsion gyroscopic coupling
    Ω(I_xx + I_yy − I_zz) = 2Ωρ I_flap ≈ 0. They also give the lag modes a rotary inertia
    ρI_lag the Euler–Bernoulli closed forms lack (−0.13 % on lag 1 at rest).
    `rotary_inertia=False` drops the section terms in bending (Euler–Bernoulli exactly, I_α kept
    in torsion); it is only consistent at rest: spinning, that body would carry a spurious
    flap–torsion coupling ΩI_α and flap softening −Ω²I_α."""
    lay = layout(params["L"], n)
    rho = params["rho"]
    b1, b2 = (rho * section["I_flap"], rho * section["I_lag"]) if rotary_inertia else (0, 0)
    inertia = np.array([segment_inertia(section["m"], ell, section["I_alpha"], b1, b2)
                        for ell in lay["lengths"]])
    dl, ones = lay["dl"], np.ones(n)
    k_t = torsion_springs(lay, section["GJ"], mstmm.tension_torsion_k2(params), section["m"],
                          params["speed"], params["hub_radius"])
    return {**lay, "axis": 0, "root": params["hub_radius"], "spin": params["speed"],
            "joints": (("torsion", 0, k_t), ("flap", 1, section["EI_flap"] / dl * ones),
                       ("lag", 2, section["EI_lag"] / dl * ones)),
            "masses": section["m"] * lay["lengths"], "inertia": inertia,
            "L": params["L"], "chord": params["chord"]}


def shaft_chain(params: dict, n: int, spin: float) -> dict:
    """Rigid-segment shaft along z spinning about z at `spin` (rad/s). Joints per hinge: about
    x (bending v along y, EI_xx/Δl), about y (bending u along x, EI_yy/Δl); Euler–Bernoulli:
    segment inertia m ℓ²/12 about x and y only (no section rotary or polar inertia)."""
    lay = layout(params["L"], n)
    m = params["m"]
    tiny = 1e-9 * m * lay["dl"] ** 3 / 12     # engines want a positive polar inertia
    inertia = np.array([[m * ell**3 / 12, m * ell**3 / 12, tiny] for ell in lay["lengths"]])
    dl, ones = lay["dl"], np.ones(n)
    return {**lay, "axis": 2, "root": 0.0, "spin": spin,
            "joints": (("bend_v", 0, params["EI_xx"] / dl * ones),
                       ("bend_u", 1, params["EI_yy"] / dl * ones)),
            "masses": m * lay["lengths"], "inertia": inertia, "L": params["L"]}


def joint_table(chain: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per coordinate (hinge-major, joints in chain order): family, hinge index, stiffness."""
    n, js = len(chain["hinges"]), chain["joints"]
    fam = np.array([j[0] for _ in range(n) for j in js])
    hinge = np.repeat(np.arange(n), len(js))
    k = np.array([j[2][i] for i in range(n) for j in js])
    return fam, hinge, k


def state_matrix(M: np.ndarray, K: np.ndarray, D: np.ndarray) -> np.ndarray:
    """A of ẋ = A x, x = (q, q̇), for M q̈ + D q̇ + K q = 0."""
    n = M.shape[0]
    MinvK, MinvD = np.split(np.linalg.solve(M, np.hstack([K, D])), 2, axis=1)
    return np.block([[np.zeros((n, n)), np.eye(n)], [-MinvK, -MinvD]])


def quadratic_modes(M: np.ndarray, K: np.ndarray, D: np.ndarray, varied=None,
                    first: int = 0):
    """Eigenvalues s and eigenvectors (coordinates only) of M q̈ + D q̇ + K q = 0: the
    oscillatory ones (Im s > 0) ascending in Im s, the count of eigenvalues with
    Re s > 0 beyond round-off (divergence or flutter: an unstable linearisation), the growth
    rates σ > 0 of the real pairs ±σ (a divergent mode: inside an instability band), and, given
    `varied` (M, K, D linearised at another finite-difference step), the error bound of ζ of
    the `first` roots: eigen round-off (compare.physics.eigen) plus the first-order change
    `varied` makes (None without `varied`), and the same bound on the frequency (Hz): what the
    one linearisation adds to the chain's own discretisation error."""
    n = M.shape[0]
    A = state_matrix(M, K, D)
    s, V = np.linalg.eig(A)          # standard form: ~20x faster than the QZ of (A, B)
    fin = np.isfinite(s)
    scale = np.max(np.abs(s[fin]))
    n_unstable = int(np.sum(s[fin].real > 1e-7 * scale))
    keep = np.nonzero(fin & (s.imag > 1e-9 * scale))[0]
    keep = keep[np.argsort(s[keep].imag)]
    z_err = f_err = None
    if varied is not None:
        W, mine = eigen.left_rows(V), keep[:first]
        d_re, d_abs = eigen.change(state_matrix(*varied) - A, s, V, W, mine)
        rounding = eigen.round_off(A, s, V, W, mine)
        z_err = eigen.zeta_error(rounding, s[mine]) + eigen.zeta_error(d_abs, s[mine], d_re)
        # the frequency's: the FD step alone (the eigen round-off bound, ~1e3 × the engines'
        # measured difference at torsion 1, is left to the scenes' round-off floor). The
        # engines' derivatives are central differences: the change at FD_VARY × the step is
        # FD_VARY² − 1 = 99 × the error at it (exudyn–mujoco differ by 0.0068–0.0081 of their
        # summed changes at every mode of 9 sets of both beams: an h² error, not h)
        f_err = d_abs / (FD_VARY**2 - 1) / (2 * np.pi)
    growth = s[fin & (np.abs(s.imag) <= 1e-9 * scale) & (s.real > 0)].real
    return s[keep], V[:n, keep], n_unstable, growth, z_err, f_err


def stations(L: float) -> np.ndarray:
    return L * np.arange(1, N_STATIONS + 1) / N_STATIONS


def _arms(chain: dict) -> np.ndarray:
    return np.clip(stations(chain["L"])[:, None] - chain["hinges"][None, :], 0.0, None)


def real_shape(v: np.ndarray) -> np.ndarray:
    """A complex mode shape made comparable: phase turned so the first entry of at least half
    the largest magnitude is real positive, unit max-abs; returns [Re, Im] (Im ≈ 0 for a
    standing mode). Not the largest entry itself: a circular whirl has |u| = |v| at the tip,
    and which one wins by rounding would turn the phase by 90° from one speed to the next
    (its [Re, Im] then no longer correlates with itself across a Campbell sweep)."""
    a = np.abs(v)
    k = int(np.argmax(a >= 0.5 * a.max()))
    v = v * np.exp(-1j * np.angle(v[k])) / max(a.max(), 1e-300)
    return np.concatenate([v.real, v.imag])


def family_labels(families: list) -> list:
    """'flap 1', 'lag 1', 'flap 2', … numbered per family in the given (ascending) order."""
    count: dict = {}
    out = []
    for f in families:
        count[f] = count.get(f, 0) + 1
        out.append(f"{f} {count[f]}")
    return out


def blade_modes(chain: dict, M, K, D, n_modes: int, varied=None) -> dict:
    """Frequencies (Hz), labels by the family holding most of the kinetic energy at the
    stations (line mass m̄ on flap z and lag y, I_α on the twist: the chain's own, the same
    for both engines), shapes [flap z, lag y, (chord/2)·twist] at the stations (Re then Im),
    damping −Re s/|s| and its error bound (`quadratic_modes`).

    Kinetic, not the hinge springs' energy: spinning, flap is stiffened mostly by the
    centrifugal tension, which the springs do not hold. In mid-veering (seed 11 set 2 of
    `xval calibrate rotating-beam`, 28 rad/s, N = 40) the two modes share flap and torsion
    about 1/4 and 3/4 each way by kinetic energy, 1/99 % and 13/87 % by the springs': both were
    named torsion, every higher flap mode's number shifted by one, and the extrapolation by
    label paired the N chain's flap 3 with the N/2 chain's flap 2."""
    s, V, n_unstable, _, z_err, f_err = quadratic_modes(M, K, D, varied, n_modes)
    fam = joint_table(chain)[0]
    families, shares, shapes = [], [], []
    arm = _arms(chain)
    on = (arm > 0).astype(float)
    m_line = chain["masses"][0] / chain["lengths"][0]
    i_alpha = chain["inertia"][0][0] / chain["lengths"][0]
    for i in range(V.shape[1]):
        v = V[:, i]
        z = -arm @ v[fam == "flap"]           # R_y(θ) x̂ = (cos θ, 0, −sin θ)
        y = arm @ v[fam == "lag"]             # R_z(θ) x̂ = (cos θ, sin θ, 0)
        twist = on @ v[fam == "torsion"]
        e = {"flap": m_line * np.sum(np.abs(z) ** 2), "lag": m_line * np.sum(np.abs(y) ** 2),
             "torsion": i_alpha * np.sum(np.abs(twist) ** 2)}
        families.append(max(e, key=e.get))
        shares.append({f: x / sum(e.values()) for f, x in e.items()})
        shapes.append(real_shape(np.concatenate([z, y, 0.5 * chain["chord"] * twist])))
    s, shapes = s[:n_modes], np.array(shapes[:n_modes])
    return {"frequencies_hz": s.imag / (2 * np.pi),
            "labels": family_labels(families)[:n_modes], "shares": shares[:n_modes],
            "shapes": shapes,
            "damping": -s.real / np.abs(s), "damping_error": z_err,
            "linearisation_error_hz": f_err, "n_unstable": n_unstable}


def whirl_sense(u: np.ndarray, v: np.ndarray) -> float:
    """Sense of the whirl of the section centres (u, v) about +z for the motion Re(φ e^{iωt}),
    ω > 0, summed over the stations: > 0 counter-clockwise (x → y). (u, v) = (1, −i) is
    u = cos ωt, v = sin ωt, counter-clockwise, and Im(u·conj(v)) = +1."""
    return float(np.sum(np.imag(u * np.conj(v))))


def shaft_modes(chain: dict, M, K, D, n_modes: int, varied=None) -> dict:
    """Whirl modes of the spinning shaft, frequencies in the co-rotating frame (as Table 2).

    Labels: the whirl seen from the ground turns at ω_inertial = sense·ω + Ω (sense of the
    co-rotating whirl, see `whirl_sense`, returned as "sense"); 'forward whirl n' when it turns
    with the spin, 'backward whirl n' against it, numbered per kind by that inertial frequency
    (compare.physics.whirl); 'whirl n' for the degenerate pairs at rest, one label per mode as
    mstmm and fem number them, so every solver pairs mode by mode. For the isotropic shaft the
    forward whirl is the lower branch |λ² − Ω*| (its inertial frequency is λ²ω₀ turning with
    the spin) and the backward the upper λ² + Ω*. Shapes: [u, v] at the stations (Re then
    Im); damping −Re s/|s| and its error bound (`quadratic_modes`).

    A divergent mode (a real pair ±σ: inside an anisotropic shaft's instability band) is not
    listed, and the next mode of its kind takes its label, as mstmm and fem number them; the
    chains of N and N/2 segments put a band's edges apart, so they are matched by
    "pair_labels", which number the divergent modes too (at rotating-frame frequency 0), and
    "band" gives each divergent one's −(σ/2π)²: the continuation of f² through the edge
    (`richardson`)."""
    s, V, n_unstable, growth, z_err, f_err = quadratic_modes(M, K, D, varied, n_modes)
    fam, hinge, k = joint_table(chain)
    arm = _arms(chain)
    spin = chain["spin"]
    sense, shapes = [], []
    for i in range(V.shape[1]):
        v = V[:, i]
        u_x = arm @ v[fam == "bend_u"]        # R_y(θ) ẑ = (sin θ, 0, cos θ)
        v_y = -arm @ v[fam == "bend_v"]       # R_x(θ) ẑ = (0, −sin θ, cos θ)
        shapes.append(real_shape(np.concatenate([u_x, v_y])))
        sense.append(1.0 if spin == 0 else float(np.sign(whirl_sense(u_x, v_y))))
    labels = whirl_labels(s.imag / (2 * np.pi), sense, spin / (2 * np.pi))
    every = whirl_labels(np.r_[s.imag, 0 * growth] / (2 * np.pi), sense + [1.0] * len(growth),
                         spin / (2 * np.pi))
    band = dict(zip(every[len(s):], -(growth / (2 * np.pi)) ** 2))
    s = s[:n_modes]
    return {"frequencies_hz": s.imag / (2 * np.pi), "labels": labels[:n_modes],
            "pair_labels": every[:n_modes], "band": band,
            "sense": np.array(sense[:n_modes]), "shapes": np.array(shapes[:n_modes]),
            "damping": -s.real / np.abs(s), "damping_error": z_err,
            "linearisation_error_hz": f_err, "n_unstable": n_unstable}


def signed_hz(model: dict) -> np.ndarray:
    """A model's frequencies with their whirl sense where it has one (the spinning shaft): the
    quantity that is smooth in N. Near a forward whirl's rotating-frame zero the chains of N and
    N/2 segments sit on opposite sides of it; extrapolating magnitudes there gave 2.96e-4 for
    the true 9.85e-4 (Ω* = 3.517) and −3.4e-3 for 1.55e-2 (Ω* = 22.05)."""
    return model["frequencies_hz"] * model.get("sense", 1.0)


def richardson(coarse: dict, fine: dict, n_modes: int) -> np.ndarray:
    """Second-order Richardson extrapolation (4 f_fine − f_coarse)/3 per mode label of the
    signed frequencies (`signed_hz`; the chain converges as 1/N²; fine has twice the segments).
    Where the coarse chain's mode is divergent (its band edge lies past the fine one's), of
    f², continued through the edge by −(σ/2π)² (`shaft_modes` "band"), which is smooth in
    N there: the frequency beside an anisotropic shaft's band edge. Modes of `fine` the coarse
    model lacks otherwise keep their fine value."""
    labels = pairing(fine)
    f, c = signed_hz(fine), by_label(coarse, labels)
    q = np.array([coarse.get("band", {}).get(lab, np.nan) for lab in labels])
    through = np.sign(f) * np.sqrt(np.maximum(4 * f**2 - q, 0.0) / 3)
    return np.where(np.isnan(c), np.where(np.isnan(q), f, through), (4 * f - c) / 3)[:n_modes]


def pairing(model: dict) -> list:
    """The labels by which chains of N and N/2 segments match modes (`shaft_modes`)."""
    return model.get("pair_labels", model["labels"])


def by_label(model: dict, labels: list, values=None) -> np.ndarray:
    """The model's `values` (default its signed frequencies, `signed_hz`) at `labels` (a
    repeated label in its order), NaN where it lacks one."""
    own: dict = {}
    for lab, f in zip(pairing(model), signed_hz(model) if values is None else values):
        own.setdefault(lab, []).append(f)
    out, used = [], {}
    for lab in labels:
        j = used.get(lab, 0)
        used[lab] = j + 1
        cands = own.get(lab, [])
        out.append(cands[j] if j < len(cands) else np.nan)
    return np.array(out, float)


def raw_ratio(models: list, labels: list) -> np.ndarray:
    """(f_N/4 − f_N/2)/(f_N/2 − f_N) per label of the N chain, `models` = (N, N/2, N/4): 4 in
    the chain's 1/N² regime (ASYMPTOTIC_RATIO); NaN where a chain lacks the mode."""
    f1, f2, f4 = (by_label(m, labels) for m in models)
    with np.errstate(divide="ignore", invalid="ignore"):
        return (f4 - f2) / (f2 - f1)


def checked_segments(settings: dict) -> int:
    """The discretisation setting: an integer ≥ 4, even when extrapolating (N and N/2)."""
    n = settings["n_segments"]
    if isinstance(n, bool) or int(n) != n or n < 4 or (settings["extrapolate"] and n % 2):
        raise ValueError(f"n_segments must be an integer >= 4 (even with extrapolate): {n!r}")
    return int(n)


SPREAD_NOTE = 5e-3   # Richardson spread above this: the chain is too coarse at this speed
# the order of the term the 1/N² extrapolation leaves, at least (the chain's error has odd
# terms where the segments' ends break the symmetry): 2^3 − 1 = 7
EXTRAPOLATED_ORDER = 3
LINEARISATION_SAFETY = 3.0    # the h² law of the varied step holds to ±10 %; the rest margin
FD_VARY = 10.0       # the engines' finite-difference step × this: the linearisation's own error


# the raw changes' ratio (f_N/4 − f_N/2)/(f_N/2 − f_N) of a chain in its 1/N² regime: 4 within
# this (the aircraft's roots at 66 rad/s that converge at 3.0–3.5 from N = 10: their N/2–N
# extrapolate was off by 1.6–2.5 × its diff/7)
ASYMPTOTIC_RATIO = (3.8, 4.2)
# the extrapolates' successive differences of a residual of order 3–6 shrink by 8–64; from 7
# (= 2^3 − 1, what the claim divides by)
SHRINK_RANGE = (7.0, 64.0)


def extrapolate_error(diff, change, ratio=None, safety=1.0, shrink=None):
    """The error of a 1/N² extrapolate from N and N/2: `diff`, its difference from the
    extrapolate of N/2 and N/4 (the coarser one's error), over 2^p − 1 where the extrapolation
    leaves an order-p ≥ EXTRAPOLATED_ORDER term — claimed only where the extrapolation acts:
    the two extrapolates nearer each other than the N chain to its own (`change`) and, where
    given, the raw changes' `ratio` in ASYMPTOTIC_RATIO. Short of it (the blade's flap at 80
    rad/s, N = 40: 5.1e-3 apart, the N chain 2.8e-3 from its extrapolate, whose true error is
    2.0e-3, not the 7.2e-4 the 1/7 claimed) the difference as it is. Never above `change`
    (the N chain's error, an upper bound of the extrapolate's), alone where the N/4 chain
    lacks the mode (diff = inf). `safety` multiplies the claim where it is made.

    `shrink`, where given, is the ratio of the extrapolates' successive differences (N/8–N/4
    against N/4–N/2, over `diff`): an order-p residual shrinks by 2^p, 16–34 in the shaft's
    modes, where the claim holds (true/claimed 0.44–0.47). Where the residual's leading term
    changes sign along the sweep it is no longer one order: the spinning shaft's forward
    whirl 2 at Ω* = 20 (`xval calibrate spinning-shaft --seed 11` set 4) had shrink −91 and
    an error 1.35 × the claim. The claim is made only for a shrink in SHRINK_RANGE (NaN,
    where the N/8 chain lacks the mode: not checked). Outside it `diff` itself may be small by
    chance (shrink −5079, `xval calibrate spinning-shaft --seed 2027` set 18 at Ω* = 18: the
    two extrapolates 8e-7 apart, the N/2–N one 5.1e-6 off): the bar is then the larger of
    `diff` and what the coarser difference d1 = shrink·diff bounds if the extrapolates' errors
    shrink at least as the chain's 1/N² does, |e| ≤ |d1|/((4 − 1)·4)."""
    diff, change = np.asarray(diff, float), np.asarray(change, float)
    acts = diff <= change
    if ratio is not None:
        lo, hi = ASYMPTOTIC_RATIO
        acts &= (np.asarray(ratio) >= lo) & (np.asarray(ratio) <= hi)
    unclaimed = diff
    if shrink is not None:
        shrink = np.asarray(shrink, float)
        lo, hi = SHRINK_RANGE
        one_order = (shrink >= lo) & (shrink <= hi)
        acts &= np.isnan(shrink) | one_order
        unclaimed = np.where(np.isnan(shrink) | one_order, diff,
                             np.maximum(diff, np.abs(shrink) * diff / 12))
    return np.minimum(np.where(acts, diff * safety / (2 ** EXTRAPOLATED_ORDER - 1), unclaimed),
                      change)


def damping_change(coarse: dict, fine: dict) -> np.ndarray:
    """|ζ_fine − ζ_coarse| per mode of `fine`, matched by label as `richardson` matches them
    (0 where the coarse model lacks the label): the discretisation's share of ζ's error."""
    c = by_label(coarse, pairing(fine), coarse["damping"])
    return np.where(np.isnan(c), 0.0, np.abs(np.asarray(fine["damping"], float) - c))


def _shrink(models: list, low: dict, f_all: np.ndarray, idx) -> np.ndarray:
    """Per mode of the N chain, (R(N/8, N/4) − R(N/4, N/2)) / (R(N/4, N/2) − R(N/2, N)) of the
    extrapolates R, `low` the middle one by pair label: `extrapolate_error`'s shrink; NaN
    where the N/8 chain lacks the mode."""
    quarter = models[2]
    labels = pairing(quarter)
    lowest = np.where(np.isnan(by_label(models[3], labels)), np.nan,
                      richardson(models[3], quarter, len(labels)))
    lower = dict(zip(labels, lowest))
    pair = pairing(models[0])
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.array([(lower.get(pair[i], np.nan) - low.get(pair[i], np.nan))
                         / (low.get(pair[i], np.nan) - f_all[i]) for i in idx])


def veering_error(fine: dict, coarse: dict, f_all: np.ndarray, idx) -> np.ndarray:
    """Per mode of the N chain (`idx`), what a veering with a mode of another family adds to
    the extrapolate's error: 2c²/max(g, c), c the pair's coupling, g its least gap over the N
    and N/2 chains and the extrapolates (0 without "shares": a chain whose families do not mix).

    Two modes coupled by c veer as the eigenvalues of [[a, c], [c, b]]: each is pushed by
    √((a − b)²/4 + c²) − |a − b|/2, c at the crossing, c²/|a − b| apart from it. Each chain
    holds its own push (its a − b moves with N), and the 1/N² extrapolation of the pushes does
    not give the converged chain's. c is read off the N chain: its two modes, g apart, share
    s(1 − s) of each family, so c = g √(s(1 − s)), s the mode's share of the partner's family
    and the partner the nearest mode of that family (measured at seed 11 set 2 of `xval
    calibrate rotating-beam`, flap 2 and torsion 1: c = 1.3e-3 Hz at 28.0 rad/s, mid-veering, and
    1.5e-3 at 28.1, 3.4e-2 apart). There the extrapolated torsion 1 sat 9.3e-4 and 1.7e-4 Hz
    off the N = 320 chain against its 1/N² bar of 4.0e-4 and 3.6e-5; this term adds 1.1e-3 and
    3.9e-4 (twice the push at g: the converged chain's gap may be narrower than all three)."""
    if "shares" not in fine:
        return np.zeros(len(idx))
    f_n = np.abs(signed_hz(fine))
    f_c = np.abs(by_label(coarse, pairing(fine)))
    fams = [max(share, key=share.get) for share in fine["shares"]]     # as the labels name them
    out = []
    for i in idx:
        add = 0.0
        for fam in set(fams) - {fams[i]}:
            js = [j for j, f in enumerate(fams) if f == fam]
            j = min(js, key=lambda k: abs(f_n[k] - f_n[i]))
            s = fine["shares"][i][fam]
            c = abs(f_n[i] - f_n[j]) * np.sqrt(max(s * (1 - s), 0.0))
            g_n, g_c = abs(f_n[i] - f_n[j]), abs(f_c[i] - f_c[j])
            g = np.nanmin([g_n, g_c, abs(abs(f_all[i]) - abs(f_all[j]))])
            # away from the crossing the push is smooth in N: what the extrapolation leaves
            # of c²/g(h), g = g₀ + κh², is its h⁴ term, ~ c²(g_c − g_n)²/g³ (×4/9)
            far = min(1.0, ((g_c - g_n) / g) ** 2) if np.isfinite(g_c) and g > 0 else 1.0
            add += 2 * c**2 / max(g, c) * far if c > 0 else 0.0
        out.append(add)
    return np.array(out)


def solve(make_chain, linearise, post, n: int, extrapolate: bool, n_modes: int) -> dict:
    """Modes of the N-segment chain, Richardson-extrapolated with the N/2 chain when asked;
    returns the LeafModes fields (frequencies ascending) plus notes and extra.

    With extrapolation, the N/4 chain gives a second extrapolate (the N/8 chain a third: is
    their difference a residual's? `_shrink`); their largest relative
    difference (`richardson_spread_rel`) bounds the error of the first from above where the
    chain is in its 1/N² regime (measured: spread 6e-4 for a true error 5.4e-5 at 40 rad/s).
    A spread above SPREAD_NOTE adds a note to raise n_segments.

    ζ's error (extra "damping_error", per mode): the eigen round-off floor, the change when the
    engine's finite-difference step is varied (× FD_VARY: `linearise(chain, fd_scales)` gives
    one (M, K, D) per factor), and with extrapolation the change from N/2 to N."""
    want = n_modes + 6              # margin so the coarser models have every label of the fine
    models = []
    for k in ((n, n // 2, n // 4, n // 8) if extrapolate else (n,)):
        chain = make_chain(max(k, 2))
        mats = linearise(chain, (1.0, FD_VARY) if k == n else (1.0,))
        models.append(post(chain, *mats[0], want, varied=mats[1] if k == n else None))
    fine = models[0]
    z_error = fine["damping_error"] + (damping_change(models[1], fine) if extrapolate else 0.0)
    extra, notes = {}, []
    if extrapolate:
        f_all = richardson(models[1], fine, want)
        idx = np.argsort(np.abs(f_all))[:n_modes]
        signed = f_all[idx]
        f = np.abs(signed)
        f_low = richardson(models[2], models[1], want + 6)
        low = dict(zip(pairing(models[1]), f_low))
        # per mode: the two extrapolates' difference (N/4–N/2 against N/2–N)
        change = np.abs(signed - signed_hz(fine)[idx])
        pair = pairing(fine)
        diff = np.array([abs(low[pair[i]] - f_all[i]) if pair[i] in low else np.inf
                         for i in idx])
        spread = max((d / abs(f_all[i]) for d, i in zip(diff, idx) if np.isfinite(d)),
                     default=0.0)
        ratio = raw_ratio(models[:3], [pair[i] for i in idx])
        extra = {"unextrapolated_hz": fine["frequencies_hz"][idx],
                 "richardson_spread_rel": float(spread),
                 "frequency_error_hz": extrapolate_error(diff, change, ratio,
                                                         shrink=_shrink(models, low, f_all, idx))
                 + veering_error(fine, models[1], f_all, idx)}
        if spread > SPREAD_NOTE:
            notes.append(f"discretisation: extrapolations from N/4–N/2 and N/2–N differ by "
                         f"{spread:.1e} here; raise n_segments")
    else:
        idx = np.arange(min(n_modes, len(fine["labels"])))
        signed = signed_hz(fine)[idx]
        f = np.abs(signed)
    if fine.get("linearisation_error_hz") is not None:
        # what the engine's own linearisation adds (round-off, the FD step): the error two
        # engines of this one chain do not share; the extrapolate (4f_N − f_N/2)/3 carries
        # 4/3 of the N chain's and 1/3 of the N/2 chain's, taken alike
        lin = fine["linearisation_error_hz"][idx]
        extra["linearisation_error_hz"] = LINEARISATION_SAFETY * lin * (5 / 3 if extrapolate
                                                                        else 1)
    if "sense" in fine:
        extra["whirl_sense"] = np.where(signed < 0, -1.0, 1.0)
    if fine["n_unstable"]:
        notes.append(f"unstable: {fine['n_unstable']} eigenvalues with Re s > 0 (steady spin is "
                     "not a stable equilibrium here)")
    return {"frequencies_hz": np.asarray(f, float), "labels": [fine["labels"][i] for i in idx],
            "damping": np.asarray(fine["damping"])[idx], "shapes": fine["shapes"][idx],
            "notes": notes, "extra": {**extra, "damping_error": z_error[idx]}}


def shaft_result(params: dict, s: dict, linearised, package, method: str):
    """The spinning shaft through one engine's linearisation (`linearised`) and result
    packaging (`package`): both engines run it the same way; ω* = ω/ω₀ in extra."""
    import time

    n = checked_segments(s)
    w0 = mstmm.spinning_shaft_omega0(params["EI_xx"], params["m"], params["L"])
    spin = params["spin_ratio"] * w0
    t0 = time.perf_counter()
    out = solve(lambda k: shaft_chain(params, k, spin), linearised, shaft_modes, n,
                bool(s["extrapolate"]), int(params["n_modes"]))
    res = package(out, s, method, {"stations_m": stations(params["L"]), "omega0_rad_s": w0,
                                   "linearise_s": time.perf_counter() - t0})
    res.extra["omega_star"] = res.frequencies_hz * 2 * np.pi / w0
    if spin == 0:      # the extrapolation may swap a degenerate pair: number in final order
        res.labels = family_labels(["whirl"] * len(res.labels))
    return res


def package(out: dict, settings: dict, note: str, extra: dict):
    """The chain's solution as the leaf contract's LeafModes."""
    from compare.contract import LeafModes
    return LeafModes(frequencies_hz=out["frequencies_hz"], labels=out["labels"],
                       damping=out["damping"], shapes=out["shapes"], settings=settings,
                       notes=[note] + out["notes"], extra={**extra, **out["extra"]})


def blade_result(params: dict, s: dict, linearised, package, method: str, check=None):
    """The rotating blade through one engine's linearisation and packaging; `check(params, s,
    section, n)` raises ValueError for what that engine cannot model."""
    import time

    n = checked_segments(s)
    if not s["rotary_inertia"] and params["speed"] != 0:
        raise ValueError("rotary_inertia=False (Euler–Bernoulli segments) is consistent only "
                         "at rest: spinning, its rigid sections have a spurious flap–torsion "
                         "coupling Ω·I_α")
    section = mstmm.blade_section_from(params)
    if check is not None:
        check(params, s, section, n)
    t0 = time.perf_counter()
    out = solve(lambda k: blade_chain(params, section, k, bool(s["rotary_inertia"])),
                linearised, blade_modes, n, bool(s["extrapolate"]), int(params["n_modes"]))
    return package(out, s, method, {"stations_m": stations(params["L"]),
                                    "linearise_s": time.perf_counter() - t0})
