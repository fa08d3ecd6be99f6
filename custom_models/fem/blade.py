"""`fem` leaf for `rotating-beam`: the rotating cantilever blade by finite elements,
independent of the transfer matrices (only the physics is shared: the same tension
T(x) = m̄Ω²[r_H(L − x) + (L² − x²)/2], lag softening −Ω²m̄, torsion +Ω²I_α, extension −Ω²m̄,
and with tension_torsion on the torsion geometric stiffness ∫T k_A² φ'²).

Flap and lag: Hermite cubic elements with centrifugal geometric stiffness ∫T y'y'. Torsion and
extension: quadratic elements. Convergence: every family is solved on n and 2n elements and
Richardson-extrapolated with the h⁴ rate of both element types. The error estimate, per mode,
is built from that extrapolate's distance to the one from n/2 and n elements
(`richardson_pair`: the coarser extrapolate's discretisation error, 63 × the finer's in their
h⁶ regime). Flap and lag frequencies are their eigenvectors' Rayleigh quotients from the
curvatures (beam.bending_rayleigh): the solver's own eigenvalues carry the round-off of K·x,
∝ the stiffness's conditioning (n⁴), which dominated the low modes (lag 1 of rotating-beam:
n and 2n elements off mstmm by 2e-9 and up to 1e-7 of the frequency; the extrapolate up to
1.6e-8) — a doubled mesh measured that round-off, not the discretisation; the quotient's
extrapolate is within 2e-13.
"""
import numpy as np

from compare.contract import LeafModes, merge_settings
from compare.physics.mstmm import blade_section_from, tension_torsion_k2

from .beam import lowest_modes

MODES_SETTINGS = {"elements": 48, "stations": 13, "richardson": True}


def properties(params, prefix=""):
    s = blade_section_from(params, prefix)
    return dict(L=params[prefix + "L"], EI_flap=s["EI_flap"], EI_lag=s["EI_lag"], GJ=s["GJ"],
                EA=params[prefix + "E"] * s["A"], m=s["m"], I_alpha=s["I_alpha"],
                chord=params[prefix + "chord"], k_A2=tension_torsion_k2(params, prefix))


def family_problem(b, spin, r_h, family, n_el):
    """(K, M, sampler) of one family, root clamped; sampler maps an eigenvector to the
    displacement at the element-boundary nodes."""
    from .beam import bending, second_order
    L, m = b["L"], b["m"]
    tension = lambda x: m * spin**2 * (r_h * (L - x) + 0.5 * (L**2 - x**2))
    if family in ("flap", "lag"):
        nodes = np.linspace(0.0, L, n_el + 1)
        EI = b["EI_flap"] if family == "flap" else b["EI_lag"]
        K, KT, M = bending(nodes, EI, m, tension)
        K = K + KT
        if family == "lag":
            K = K - spin**2 * M
        free = slice(2, None)
        sample = lambda v: np.concatenate([[0.0], v[0::2]])
    else:
        stiff, inert = (b["GJ"], b["I_alpha"]) if family == "torsion" else (b["EA"], m)
        # the tension–torsion term: geometric stiffness ∫T k_A² φ'² (k_A2 = 0 when off)
        extra = (lambda x: b["k_A2"] * tension(x)) if family == "torsion" else None
        K, M = second_order(n_el, L, stiff, inert, extra)
        K = K + (spin**2 if family == "torsion" else -spin**2) * M
        free = slice(1, None)
        sample = lambda v: np.concatenate([[0.0], v[1::2]])
    return K[free, free], M[free, free], sample


def family_modes(b, spin, r_h, family, n_el, count):
    K, M, sample = family_problem(b, spin, r_h, family, n_el)
    lam, V = lowest_modes(K, M, count, shift=2 * spin**2)
    if family in ("flap", "lag"):
        # each eigenvalue as its vector's Rayleigh quotient, from the curvatures (beam.py):
        # the solver's own carries the round-off of K·x, ∝ the conditioning (n⁴)
        from .beam import bending_rayleigh
        L, m = b["L"], b["m"]
        tension = lambda x: m * spin**2 * (r_h * (L - x) + 0.5 * (L**2 - x**2))  # noqa: E731
        X = np.vstack([np.zeros((2, V.shape[1])), V])
        lam = bending_rayleigh(np.linspace(0.0, L, n_el + 1),
                               b["EI_flap"] if family == "flap" else b["EI_lag"], m, X,
                               tension) - (spin**2 if family == "lag" else 0.0)
    return np.sign(lam) * np.sqrt(np.abs(lam)), V, sample


FAMILIES = ("flap", "lag", "torsion", "axial")


def solve(b, spin, r_h, n_modes, n_el, richardson=True, stations=13):
    """Lowest n_modes: list of (ω, family, index, node samples), the error estimate and the
    mesh per family. A coarse pass tells how many modes each family contributes; each family
    is then meshed with ≥ 8 elements per mode (a multiple of stations − 1, so the stations
    are nodes)."""
    coarse = sorted((w, fam) for fam in FAMILIES
                    for w in family_modes(b, spin, r_h, fam, n_el, n_modes)[0])[:n_modes]
    rows, err, meshes = [], 0.0, {}
    for fam in FAMILIES:
        # one extra mode per family: the coarse order near the cut may be wrong
        count = sum(1 for _, f in coarse if f == fam) + 1
        k = stations - 1
        n_f = max(n_el, k * int(np.ceil(8 * count / k)))
        meshes[fam] = n_f
        w, V, sample = family_modes(b, spin, r_h, fam, n_f, count)
        bar = np.zeros(len(w))
        if richardson:
            w2, V, sample = family_modes(b, spin, r_h, fam, 2 * n_f, count)
            half, quarter = (family_modes(b, spin, r_h, fam, n_f // k, count)[0] for k in (2, 4))
            # torsion and extension (no quotient: their conditioning ∝ n² only) keep the
            # round-off of their lowest mode as every mode's floor
            w, bar = richardson_pair(half, w, w2, lowest=0 if fam in ("flap", "lag") else 1,
                                     quarter=quarter)
            err = max(err, float(np.max(bar / np.abs(w))))
        rows += [(w[i], fam, i + 1, sample(V[:, i]), bar[i]) for i in range(len(w))]
    rows.sort(key=lambda r: r[0])
    return rows[:n_modes], err, meshes


ROUND_OFF_SAFETY = 3.0
H6 = 2.0**6 - 1      # the extrapolates' own error goes as h⁶: the n/2–n one's is 63 × the n–2n's
H6_RULES = 48.0      # successive distances shrinking by this (of 64) show the h⁶ term rules
# what a Rayleigh quotient (beam.bending_rayleigh) keeps of round-off, relative: measured ≤ 1.8e-13
# on the blade's flap 1 and lag 1 at 96 elements (11 sets), where the solver's own λ was 1e-8 off
QUOTIENT_ROUND_OFF = 1e3 * np.finfo(float).eps


def richardson_pair(half, w, w2, rate=15.0, lowest=0, carry=0, quarter=None):
    """The h⁴ extrapolate of the n and 2n meshes' ω (rate 2⁴ − 1 for both element types) and
    its error estimate per mode, × ROUND_OFF_SAFETY: the larger of
    - its discretisation error: its distance to the n/2–n extrapolate / 63 (the h⁶ term;
      measured 60–67 × between the two at rotating-beam's flap 3 and spinning-shaft's whirl 5,
      and, the round-off gone, equal to the true error at flap 2 and 3 of 11 sets) — where
      the n/4 mesh's `quarter` is given, the ratio q of the extrapolates' successive
      distances says whether that term rules: from H6_RULES the h⁶ claim, else the distance
      over q − 1 (an order read off the meshes: a long, thin blade's flap at speed, whose
      tension leaves bending a boundary layer, converges at q = 8.5 → 20.6 → 64 from n = 48,
      `xval calibrate rotating-beam --seed 2027` set 18 at 38 rad/s, where /63 fell 1.05 ×
      short), and below q = 4 (no order) the distance as it is;
    - its round-off: QUOTIENT_ROUND_OFF where ω is a Rayleigh quotient; where it is not (an
      unsymmetric state-space solve: a spinning anisotropic shaft), `lowest` > 0 takes the
      largest distance of the `lowest` modes (2 for the shaft's two bending planes: there the
      discretisation error is least and the round-off, ∝ the conditioning, largest) to every
      mode, scaled by (ω_low/ω_k)^carry (0: as it is; a whirl σ = ±ν − Ω is shifted from the ν
      that carries it).
    The safety: where round-off dominated, the distance was 0.45–1.1 × the true error."""
    ext = w2 + (w2 - w) / rate
    mid = w + (w - half) / rate
    dist = np.abs(ext - mid)
    over = np.full(len(ext), H6)
    if quarter is not None:
        with np.errstate(divide="ignore", invalid="ignore"):
            q = (half + (half - quarter) / rate - mid) / (mid - ext)
        over = np.where(q >= H6_RULES, H6, np.where(q >= 4, q - 1, 1.0))
    floor = QUOTIENT_ROUND_OFF * np.abs(ext)
    if lowest:
        low = np.argsort(np.abs(ext))[:lowest]
        floor = np.maximum(floor, np.max(dist[low] * np.abs(ext[low]) ** carry)
                           / np.abs(ext) ** carry)
    return ext, ROUND_OFF_SAFETY * np.maximum(dist / over, floor)


def modes(params: dict, settings: dict) -> LeafModes:
    s = merge_settings(settings, MODES_SETTINGS, ())
    b = properties(params)
    n_st = s["stations"]
    # a mesh whose element boundaries include the stations, ≥ 4 elements per half wavelength
    # of the highest requested mode (checked by the Richardson error estimate)
    n_el = int(s["elements"])
    n_el = (n_el + n_st - 2) // (n_st - 1) * (n_st - 1)
    rows, err, meshes = solve(b, params["speed"], params["hub_radius"], params["n_modes"], n_el,
                              s["richardson"], n_st)
    shapes = []
    for _, fam, _, y, _ in rows:
        step = (2 if s["richardson"] else 1) * meshes[fam] // (n_st - 1)
        col = {"axial": 0, "lag": 1, "flap": 2, "torsion": 3}[fam]
        sh = np.zeros((n_st, 4))
        sh[:, col] = y[::step] * (b["chord"] / 2 if fam == "torsion" else 1.0)
        sh = sh.ravel()
        shapes.append(sh / sh[np.argmax(np.abs(sh))])
    return LeafModes(frequencies_hz=np.array([r[0] for r in rows]) / (2 * np.pi),
                       labels=[f"{fam} {i}" for _, fam, i, _, _ in rows], shapes=np.array(shapes),
                       settings=dict(s, elements=meshes),
                       # per mode: the two extrapolates' distance (richardson_pair)
                       extra={"frequency_error_hz": np.array([r[4] for r in rows])
                              / (2 * np.pi)} if s["richardson"] else {},
                       notes=[f"Richardson error estimate {err:.1e} (elements per family "
                              f"{meshes}, half and twice that)"])
