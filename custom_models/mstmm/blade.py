"""`mstmm` leaf for `rotating-beam`: the rotating cantilever blade of Table 1 (seed 002).

The blade's 12x12 transfer matrix (elements.rotating_blade) is block diagonal: flap, lag,
torsion and extension do not couple (centre of mass on the elastic axis, no Coriolis terms, as
in the paper). The clamped-root / free-tip characteristic function is therefore solved per
family — det of the (moment, force) block of the root→tip matrix, Hadamard-scaled — which
labels every root by construction. Frequencies in Hz, shapes sampled at 13 fixed stations.
"""
import numpy as np

from compare.contract import LeafModes, merge_settings
from compare.physics.mstmm import blade_section_from, tension_torsion_k2

from . import elements as el
from .roots import find_roots, root_error_hz

MODES_SETTINGS = {"rtol": 1e-12, "stations": 13}
FAMILIES = ("flap", "lag", "torsion", "axial")
BLOCKS = {"flap": el.FLAP, "lag": el.LAG, "torsion": el.TORSION, "axial": el.AXIAL}


def blade_properties(params: dict, prefix: str = "") -> dict:
    s = blade_section_from(params, prefix)
    return dict(L=params[prefix + "L"], EI_flap=s["EI_flap"], EI_lag=s["EI_lag"], GJ=s["GJ"],
                EA=params[prefix + "E"] * s["A"], m=s["m"], I_alpha=s["I_alpha"],
                chord=params[prefix + "chord"], k_A2=tension_torsion_k2(params, prefix))


def transfer(b: dict, omega: float, spin: float, hub_radius: float, x_a: float, x_b: float):
    return el.rotating_blade(omega, spin, b["L"], hub_radius, b["EI_flap"], b["EI_lag"],
                             b["GJ"], b["EA"], b["m"], b["I_alpha"], x_a, x_b, b["k_A2"])


def state_scale(b):
    """Scaled state diag(s)·Z: moments and forces divided by the flap stiffness (m³ → 1)."""
    s = np.ones(12)
    s[6:] = 1.0 / b["EI_flap"]
    return s


def tip_basis(b, omega, spin, hub_radius, family):
    """Orthonormal basis (scaled state) at the tip of the solutions with a clamped root."""
    idx = BLOCKS[family]
    res = idx[len(idx) // 2:]
    S = np.zeros((12, len(res)))
    for j, r in enumerate(res):
        S[r, j] = 1.0
    return el.blade_subspace(omega, spin, b["L"], hub_radius, b["EI_flap"], b["EI_lag"],
                             b["GJ"], b["EA"], b["m"], b["I_alpha"], 0.0, b["L"], S,
                             state_scale(b), b["k_A2"]), res


def family_function(b, spin, hub_radius, family):
    """g(ω): det of the tip resultants of the orthonormal clamped-root basis (bounded by 1,
    zero exactly at the roots, continuous in ω). Bending families propagate only their own
    4x4 block (elements.bending_tip_det); torsion and extension are the closed-form 2x2
    cos/sin matrix (torsion with the tension–torsion term: its power-series 2x2), whose
    (resultant, resultant) entry is the characteristic function."""
    if family in ("flap", "lag"):
        EI = b["EI_flap"] if family == "flap" else b["EI_lag"]
        flap = family == "flap"
        return lambda omega: el.bending_tip_det(EI, b["m"], omega, spin, hub_radius, b["L"],
                                                flap)
    if family == "torsion" and b["k_A2"] > 0 and spin != 0:
        return lambda omega: el.tension_torsion_transfer(
            b["GJ"], b["k_A2"], b["I_alpha"], b["m"], omega, spin, hub_radius, b["L"], 0.0,
            b["L"])[1, 1]
    stiff, inert, sgn = ((b["GJ"], b["I_alpha"], -1.0) if family == "torsion"
                         else (b["EA"], b["m"], 1.0))
    return lambda omega: el.second_order_transfer(
        stiff, inert * (omega**2 + sgn * spin**2) / stiff, b["L"])[1, 1]


def family_grid(b, spin, family, omega_max):
    """Grid fine enough that consecutive roots of one family are ≥ 3 steps apart: uniform in
    the wavenumber (bending ∝ √ω, torsion/extension ∝ √(ω² ∓ Ω²))."""
    L = b["L"]
    if family in ("flap", "lag"):
        EI = b["EI_flap"] if family == "flap" else b["EI_lag"]
        beta_max = (b["m"] * omega_max**2 / EI) ** 0.25 * L
        n = int(np.ceil(beta_max / 0.25)) + 4
        w = (np.linspace(0, 1, n) ** 2) * omega_max
    else:
        stiff, inert = (b["GJ"], b["I_alpha"]) if family == "torsion" else (b["EA"], b["m"])
        kmax = np.sqrt(inert / stiff) * omega_max * L
        n = int(np.ceil(kmax / 0.25)) + 4
        w = np.linspace(0, 1, n) * omega_max
    w[0] = 1e-9 * omega_max
    return w


def root_state(b, omega, spin, hub_radius, family):
    """Null vector of the family block: root state (zero displacement/rotation)."""
    idx = BLOCKS[family]
    half = len(idx) // 2
    U = transfer(b, omega, spin, hub_radius, 0.0, b["L"])
    A = U[np.ix_(idx[half:], idx[half:])]
    _, _, vt = np.linalg.svd(A)
    z = np.zeros(12)
    z[idx[half:]] = vt[-1]
    return z


def shape(b, z0, omega, spin, hub_radius, stations):
    """[u, v, w, φ·chord/2] at the stations (x = 0 … L), normalised to max |·| = 1."""
    xs = np.linspace(0.0, b["L"], stations)
    rows = []
    for x in xs:
        z = transfer(b, omega, spin, hub_radius, 0.0, x) @ z0 if x > 0 else z0
        rows.append([z[el.X], z[el.Y], z[el.Z], z[el.TX] * b["chord"] / 2])
    s = np.array(rows).ravel()
    k = np.argmax(np.abs(s))
    return s / s[k]


def blade_modes(b, spin, hub_radius, n_modes, rtol=1e-12):
    """The lowest n_modes (ω [rad/s], family, index) of the clamped-free rotating blade."""
    from compare.physics.mstmm import cantilever_roots
    lam = cantilever_roots(1)[0]
    omega_max = max(2 * lam**2 * np.sqrt(b["EI_flap"] / (b["m"] * b["L"] ** 4)), 4 * spin)
    while True:
        found = []
        for fam in FAMILIES:
            g = family_function(b, spin, hub_radius, fam)
            roots = find_roots(g, family_grid(b, spin, fam, omega_max), rtol)
            found += [(r, fam, i + 1) for i, r in enumerate(roots)]
        found.sort()
        if len(found) >= n_modes:
            return found[:n_modes]
        omega_max *= 1.6


def modes(params: dict, settings: dict) -> LeafModes:
    s = merge_settings(settings, MODES_SETTINGS, ())
    b = blade_properties(params)
    spin, rh = params["speed"], params["hub_radius"]
    found = blade_modes(b, spin, rh, params["n_modes"], s["rtol"])
    shapes = np.array([shape(b, root_state(b, w, spin, rh, fam), w, spin, rh, s["stations"])
                       for w, fam, _ in found])
    f_hz = np.array([w for w, _, _ in found]) / (2 * np.pi)
    return LeafModes(frequencies_hz=f_hz, extra={"frequency_error_hz": root_error_hz(
                           f_hz, s["rtol"])},
                       labels=[f"{fam} {i}" for _, fam, i in found], shapes=shapes,
                       settings=s, notes=["shapes: [u, v, w, φ·chord/2] at "
                                          f"{s['stations']} equal stations root→tip"])
