"""Closed forms shared by every solver of the MSTMM scenes (seed 002: Yao, Rui, Wang 2021).

One implementation each, numpy only: cantilever roots, the isotropic spinning shaft's
ω* = λᵢ² ± Ω*, the blade's section properties from the scene parameters.
"""
from __future__ import annotations

import numpy as np

TORSION_BETA = 0.333   # the paper's β for a thin rectangle (h/b ≫ 10): J = β·(long)·(short)³


def cantilever_roots(n: int) -> np.ndarray:
    """The first n roots λᵢ of cos λ cosh λ = −1 (1.8751, 4.6941, 7.8548, …).

    Solved as cos λ + 1/cosh λ = 0 (bounded for large λ) by Newton from the asymptote
    (2i−1)π/2."""
    lam = (2 * np.arange(1, n + 1) - 1) * np.pi / 2
    lam[0] = 1.8751
    for _ in range(50):
        f = np.cos(lam) + 1 / np.cosh(lam)
        df = -np.sin(lam) - np.tanh(lam) / np.cosh(lam)
        step = f / df
        lam = lam - step
        if np.all(np.abs(step) < 1e-15 * lam):
            break
    return lam


def spinning_shaft_omega0(EI: float, m: float, L: float) -> float:
    """ω₀ = √(EI/(m L⁴)) [rad/s], the shaft's frequency scale (Table 2's ω* = ω/ω₀)."""
    return float(np.sqrt(EI / (m * L**4)))


def spinning_shaft_star(n_modes: int, spin_ratio: float) -> np.ndarray:
    """Nondimensional frequencies ω* of an isotropic cantilever Euler–Bernoulli shaft spinning
    at Ω* = Ω/ω₀, in the rotating frame, ascending: the pairs |λᵢ² − Ω*| (forward whirl: λᵢ²
    seen from the ground, turning with the spin) and λᵢ² + Ω* (backward) — compare.physics.whirl.

    Exact: with w = u + iv the shaft equation EI w'''' + m(ẅ − 2iΩẇ − Ω²w) = 0 (rotating frame)
    has the non-rotating cantilever shapes with (ω ± Ω)² = ω_i²; the Ω² term cancels."""
    lam2 = cantilever_roots((n_modes + 1) // 2 + 1) ** 2
    w = np.concatenate([np.abs(lam2 - abs(spin_ratio)), lam2 + abs(spin_ratio)])
    return np.sort(w)[:n_modes]


def blade_section(chord: float, thickness: float, rho: float, E: float, G: float) -> dict:
    """Section properties of the rectangular blade (chord b in the rotor plane, thickness h).

    A = b h; I_flap = b h³/12 (bending out of the rotor plane); I_lag = h b³/12 (in plane);
    J = β b h³ with β = 0.333 (the paper's It = βhb³ names the long side h); polar mass
    moment per length I_α = ρ (I_flap + I_lag); line mass m̄ = ρ A."""
    A = chord * thickness
    I_flap = chord * thickness**3 / 12
    I_lag = thickness * chord**3 / 12
    J = TORSION_BETA * chord * thickness**3
    return {"A": A, "m": rho * A, "I_flap": I_flap, "I_lag": I_lag, "J": J,
            "EI_flap": E * I_flap, "EI_lag": E * I_lag, "GJ": G * J,
            "I_alpha": rho * (I_flap + I_lag)}


def blade_section_from(params: dict, prefix: str = "") -> dict:
    """blade_section from a resolved scene dict (keys chord/thickness/rho/E/G, optionally with
    a prefix such as 'blade_')."""
    return blade_section(*(params[prefix + k] for k in ("chord", "thickness", "rho", "E", "G")))


def root_tension_wavenumber(m_line: float, EI_flap: float, L: float, spin: float,
                            hub_radius: float) -> float:
    """√(T/EI_flap) [1/m] at the blade root, T = m̄Ω²(r_H L + L²/2) the centrifugal tension: the
    inverse length of the boundary layer it sets there, which a discretisation resolves while
    its root elements span a few of it (fem's TENSION_SPAN, the engines' ENGINE_TENSION_SPAN)."""
    return float(np.sqrt(m_line * spin**2 * (hub_radius * L + L**2 / 2) / EI_flap))


def nonrotating_blade_hz(params: dict, n: int = 3, prefix: str = "") -> dict:
    """Cantilever blade at rest: flap/lag λᵢ² √(EI/(m̄L⁴))/2π and torsion (2i−1)π/(2L)·√(GJ/I_α)
    /2π, in Hz."""
    s = blade_section_from(params, prefix)
    L = params[prefix + "L"]
    lam2 = cantilever_roots(n) ** 2
    k = 2 * np.arange(1, n + 1) - 1
    return {"flap": lam2 * np.sqrt(s["EI_flap"] / (s["m"] * L**4)) / (2 * np.pi),
            "lag": lam2 * np.sqrt(s["EI_lag"] / (s["m"] * L**4)) / (2 * np.pi),
            "torsion": k * np.pi / (2 * L) * np.sqrt(s["GJ"] / s["I_alpha"]) / (2 * np.pi)}


def tension_torsion_k2(params: dict, prefix: str = "") -> float:
    """k_A² [m²] of the tension–torsion (trapeze) term, 0 when the scene's `tension_torsion`
    is 'off'. The blade's torsional stiffness under the centrifugal tension T(x) is
    GJ + T·k_A², k_A² = I_p/A the polar radius of gyration squared of the section about the
    elastic axis: the fibres off the axis turn helical when the section twists, and their
    tension resists it (Houbolt & Brooks, NACA Report 1346, 1958; Hodges & Dowell, NASA TN
    D-7818, 1974: the torsion equation's [(GJ + T k_A²) φ′]′). Rectangle b × h: (b² + h²)/12
    (uniform density: I_α = m̄ k_A²)."""
    if params["tension_torsion"] == "off":
        return 0.0
    s = blade_section_from(params, prefix)
    return (s["I_flap"] + s["I_lag"]) / s["A"]


def torsion_rotating_hz(f0_hz: np.ndarray, speed: float) -> np.ndarray:
    """Torsion of the paper's eq. 30, (GJφ')' − I_α(φ̈ + Ω²φ) = 0: ω² = ω₀² + Ω² exactly
    (uniform blade, any boundary conditions)."""
    return np.sqrt(np.asarray(f0_hz) ** 2 + (speed / (2 * np.pi)) ** 2)


SQUARE_TORSION_BETA = 0.1406   # J = β a⁴ for a solid square (Saint-Venant), the tail boom


# The paper's beams stretch; the engines' rigid-segment chains do not. EA × this stands for
# "rigid": its remaining flexibility moves a mode by 1e-3 of the whole axial shift, while the
# members' conditioning stays that of a thousandfold stiffer section (helicopter-clamped's
# seventh calibration set at rest: mstmm so puts flap cyclic 3 at 16.53025 Hz, the engines'
# chain converges to 16.5303 without its sections' rotary inertia; 16.51053 as it stretches)
AXIAL_RIGID = 1e3
AXIAL = "the members' axial flexibility"     # the name of the difference (metrics.model_allowance)


def axial_shift(w, w_rigid) -> np.ndarray:
    """|Δf| (Hz) per mode, in frequency order, that making every member axially rigid moves
    it (NaN where the rigid model has no such mode below the search's limit)."""
    k = min(len(w), len(w_rigid))
    out = np.full(len(w), np.nan)
    out[:k] = np.abs(np.asarray(w_rigid[:k]) - np.asarray(w[:k])) / (2 * np.pi)
    return out


def helicopter_layout(p: dict, axial: float = 1.0) -> dict:
    """Geometry, masses and sections of the helicopter model (seed 002, Fig. 2), in the hub
    frame: z up along the shaft, origin at the hub centre, blade k along azimuth k·90°.

    Decisions where the paper is silent (every solver uses these):
    - blade roots at radius r_H in the hub mid-plane; the shaft hangs from the hub's bottom
      face centre (0, 0, −hub_height/2) down to the fuselage top;
    - the fuselage is a uniform box whose top face holds the shaft; its centre of mass is
      fuselage_cm_offset along +X from the shaft attachment and fuselage_height/2 below it;
    - the tail boom leaves the fuselage's rear face (−X) at the centre-of-mass height and runs
      along −X; its far end is clamped (Table 3) or free (Table 4);
    - solid circular shaft (J = 2I), solid square tail boom (J = 0.1406 a⁴ when width =
      height, else β = 0.333 of the thin-rectangle rule), polar mass moment ρ(I_y + I_z).

    `axial` scales every member's EA (the engines' chains are axially rigid: `AXIAL_RIGID`)."""
    hub_h = p["hub_height"]
    m_hub = p["hub_rho"] * p["hub_length"] * p["hub_width"] * hub_h
    I_hub = m_hub / 12 * np.array([p["hub_width"] ** 2 + hub_h**2,
                                   p["hub_length"] ** 2 + hub_h**2,
                                   p["hub_length"] ** 2 + p["hub_width"] ** 2])
    d = p["shaft_diameter"]
    A_s = np.pi * d**2 / 4
    I_s = np.pi * d**4 / 64
    shaft_top = np.array([0.0, 0.0, -hub_h / 2])
    shaft_bottom = shaft_top - np.array([0.0, 0.0, p["shaft_L"]])
    fl, fw, fh = p["fuselage_length"], p["fuselage_width"], p["fuselage_height"]
    m_f = p["fuselage_rho"] * fl * fw * fh
    I_f = m_f / 12 * np.array([fw**2 + fh**2, fl**2 + fh**2, fl**2 + fw**2])
    cm_f = shaft_bottom + np.array([p["fuselage_cm_offset"], 0.0, -fh / 2])
    tail_joint = cm_f - np.array([fl / 2, 0.0, 0.0])
    tw, th = p["tail_width"], p["tail_height"]
    A_t = tw * th
    Iy_t, Iz_t = tw * th**3 / 12, th * tw**3 / 12
    a, b = max(tw, th), min(tw, th)
    J_t = SQUARE_TORSION_BETA * a**4 if tw == th else TORSION_BETA * a * b**3
    blade = blade_section_from(p, "blade_")
    return {
        "blade": dict(blade, L=p["blade_L"], EA=axial * p["blade_E"] * blade["A"],
                      chord=p["blade_chord"], k_A2=tension_torsion_k2(p, "blade_")),
        "roots": [p["hub_radius"] * np.array([np.cos(k * np.pi / 2), np.sin(k * np.pi / 2),
                                              0.0]) for k in range(4)],
        "hub": {"m": m_hub, "I": I_hub, "cm": np.zeros(3)},
        "shaft": {"top": shaft_top, "bottom": shaft_bottom, "L": p["shaft_L"],
                  "m": p["shaft_rho"] * A_s, "EI": p["shaft_E"] * I_s,
                  "EA": axial * p["shaft_E"] * A_s, "GJ": p["shaft_G"] * 2 * I_s,
                  "I_p": p["shaft_rho"] * 2 * I_s},
        "fuselage": {"m": m_f, "I": I_f, "cm": cm_f, "top": shaft_bottom,
                     "rear": tail_joint},
        "tail": {"root": tail_joint, "end": tail_joint - np.array([p["tail_L"], 0.0, 0.0]),
                 "L": p["tail_L"], "m": p["tail_rho"] * A_t, "EA": axial * p["tail_E"] * A_t,
                 "EI_flap": p["tail_E"] * Iy_t, "EI_lag": p["tail_E"] * Iz_t,
                 "GJ": p["tail_G"] * J_t, "I_alpha": p["tail_rho"] * (Iy_t + Iz_t)},
    }
