"""Rotor on a spherical joint (scenes `rotor-spinup`, `rotor-whirl`): the inertias, the effective
stiffness and every channel, defined once for all four solvers.

Each solver supplies only a common kinematic output — rotations R (n, 3, 3) body → fixed, the
fixed-frame angular velocity ω (n, 3) and the drive work A (n,) — and `channels` turns it into
the scene's channels. A solver that models a different spring (MuJoCo's `spring=cardan` variant)
passes its own spring potential; everything else is shared.
"""
from __future__ import annotations

import functools
from types import MappingProxyType

import numpy as np


def constants(p: dict) -> dict:
    """Closed-form rotor numbers from the scene parameters.

    rc0: centre of mass in the body frame (eccentricity along body y, disk at l on the shaft);
    I_c: central inertia of the disk, I_o: inertia about the pivot O (Steiner), both body frame;
    I_t, I_p: transverse and polar inertia about O of the axisymmetric rotor (eccentricity 0);
    k_eff = k + m·l·g_z: gravity enters the tilt stiffness only through its axial component
    (disk above O and g_z < 0 soften the spring). The arrays are read-only: one map's points
    share them (remembered per set of numbers: a map asks twice a point, and its grid repeats
    the numbers along the axes that do not enter here)."""
    g = np.asarray(p["gravity"], float)
    return _constants(float(p["m"]), float(p["R"]), float(p["l"]), float(p["eccentricity"]),
                      float(p["k"]), float(g[0]), float(g[1]), float(g[2]))


@functools.lru_cache(maxsize=4096)
def _constants(m, R, l, e, k, gx, gy, gz):
    g = np.array([gx, gy, gz])
    rc0 = np.array([0.0, e, l])
    I_c = np.diag([m * R**2 / 4, m * R**2 / 4, m * R**2 / 2])
    I_o = I_c + m * ((rc0 @ rc0) * np.eye(3) - np.outer(rc0, rc0))
    for a in (g, rc0, I_c, I_o):
        a.flags.writeable = False
    I_t = m * R**2 / 4 + m * l**2
    I_p = m * R**2 / 2
    k_eff = k + m * l * g[2]
    return MappingProxyType({
        "rc0": rc0, "I_c": I_c, "I_o": I_o, "I_t": I_t, "I_p": I_p, "k_eff": k_eff,
        "gravity": g,
        "omega_tilt": np.sqrt(k / I_t),                         # the paper's 38.8 rad/s
        "omega_tilt_eff": np.sqrt(max(k_eff, 0.0) / I_t),
        "forward_critical": np.sqrt(max(k_eff, 0.0) / (I_t - I_p))})


def tilt(Rs: np.ndarray) -> np.ndarray:
    """Angle between the body axis R·e_z and the fixed z axis (= |γ|, the transverse turn)."""
    n = Rs[:, :, 2]
    return np.arctan2(np.hypot(n[:, 0], n[:, 1]), n[:, 2])


def channels(p: dict, Rs: np.ndarray, omegas: np.ndarray, work: np.ndarray,
             spring_potential: np.ndarray | None = None) -> dict:
    """The scene channels from rotations (n,3,3), fixed-frame ω (n,3) and drive work (n,).

    U = ½k|γ|² − m r_c·g (the paper's spring −kγ), unless a solver's model variant passes its
    own spring potential. T = ½ ω·(R I_o Rᵀ)·ω."""
    c = constants(p)
    with np.errstate(over="ignore", invalid="ignore"):   # a blown-up run overflows; the adapter
        body_w = (Rs.transpose(0, 2, 1) @ omegas[:, :, None])[:, :, 0]   # marks it diverged
        kinetic = 0.5 * np.sum((body_w @ c["I_o"]) * body_w, axis=1)     # (Rᵀω, body frame)
        tl = tilt(Rs)
        u_spring = 0.5 * p["k"] * tl**2 if spring_potential is None else spring_potential
        potential = u_spring - p["m"] * (Rs @ c["rc0"]) @ c["gravity"]
        return {"omega_norm": np.linalg.norm(omegas, axis=1), "spin_rate": omegas[:, 2].copy(),
                "tilt": tl, "work": np.array(work, float), "kinetic": kinetic,
                "potential": potential, "energy_balance": kinetic + potential - work}


ENERGY_CHANNELS = ("energy_balance", "kinetic", "potential", "work")


def regime_summaries(t: np.ndarray, runs: list, reach, stay, window: float) -> dict:
    """A leaf's `regimes` answer from full runs (LeafResults on the grid t): per run the
    integrator's code (0: ok), t_fail, the regime (0: |ω| never reaches `reach` after t = 0,
    2: it stays above `stay` from `window`·t_end on, else 1 — the rule of the scene's
    SpeedRegime, which the compiled custom batch applies in `custom_models.rotor.batch`), whether
    the channels are finite, the largest drift of the energy balance from its first value and
    the largest |value| of each ENERGY_CHANNELS (the adapter's energy rule applies to those).
    `reach`, `stay`: one per run."""
    n = len(runs)
    out = {"code": np.zeros(n, np.int64), "t_fail": np.full(n, np.nan),
           "regime": np.zeros(n, np.int64), "finite": np.zeros(n, bool),
           "drift": np.zeros(n), "max_abs": {c: np.zeros(n) for c in ENERGY_CHANNELS}}
    late = t >= window * t[-1]
    for i, r in enumerate(runs):
        ch = r.channels
        if r.status != "ok":
            out["code"][i], out["t_fail"][i] = 1, r.t_fail
            continue
        w, e = ch["omega_norm"], ch["energy_balance"]
        out["finite"][i] = all(np.isfinite(ch[c]).all() for c in ch)
        out["drift"][i] = np.max(np.abs(e - e[0]))
        for c in ENERGY_CHANNELS:
            out["max_abs"][c][i] = np.max(np.abs(ch[c]))
        above = np.nonzero(w >= reach[i])[0]
        out["regime"][i] = 0 if not len(above) or above[0] == 0 else \
            2 if np.min(w[late]) > stay[i] else 1
    return out


def whirl_closed_form(p: dict, spins) -> tuple[np.ndarray, np.ndarray]:
    """(backward, forward) whirl frequencies [rad/s] of I_t w² ∓ I_p Ω w − k_eff = 0.
    Exact for eccentricity 0 and gravity along the shaft."""
    c = constants(p)
    W = np.abs(np.asarray(spins, float))
    root = np.sqrt((c["I_p"] * W) ** 2 + 4 * c["I_t"] * c["k_eff"])
    return (root - c["I_p"] * W) / (2 * c["I_t"]), (root + c["I_p"] * W) / (2 * c["I_t"])


def whirl_damped(p: dict, spin: float) -> np.ndarray:
    """The two whirl roots λ = σ + iω of the damped rotor at spin Ω (θ ∝ e^{λt}; ω > 0 whirls
    counter-clockwise about +z, forward where it has Ω's sign; σ > 0 grows).

    θ = θx + iθy, the small tilt (transverse Euler vector) in the fixed frame. The transverse
    angular momentum is I_t θ̇ − i I_p Ω θ (the spin I_p Ω along the tilted axis n, whose
    transverse part is γ × e_z = −iθ). External damping c_ext opposes the fixed-frame tilt rate
    θ̇; internal damping c_int opposes the tilt rate seen in the spinning body's frame,
    e^{iΩt} d/dt(θ e^{−iΩt}) = θ̇ − iΩθ. Euler's law then reads
        I_t θ̈ + (c_e + c_i − i I_p Ω) θ̇ + (k_eff − i c_i Ω) θ = 0,
    whose undamped roots are `whirl_closed_form`'s ±w."""
    c = constants(p)
    ce, ci = p.get("c_ext", 0.0), p.get("c_int", 0.0)
    return np.roots([c["I_t"], ce + ci - 1j * c["I_p"] * spin, c["k_eff"] - 1j * ci * spin])


def instability_speed(p: dict) -> float:
    """Spin |Ω_th| above which internal damping makes forward whirl grow (inf: never).

    Neutral root λ = iω in `whirl_damped`'s quadratic: its imaginary part gives ω = rΩ,
    r = c_i/(c_e + c_i) (where the internal damper's drive c_i(Ω − ω) balances the external
    drag c_e ω); its real part −I_t r²Ω² + I_p rΩ² + k_eff = 0
    gives Ω_th = √(k_eff / (r (r I_t − I_p))), real only where r I_t > I_p — otherwise the
    gyroscopic stiffening keeps the rotor stable at every spin. Jeffcott limit (I_p = 0,
    I_t = m): Ω_th = ω_n (1 + c_e/c_i)."""
    c = constants(p)
    ce, ci = p.get("c_ext", 0.0), p.get("c_int", 0.0)
    if ci <= 0 or c["k_eff"] <= 0:
        return np.inf
    r = ci / (ce + ci)
    den = r * (r * c["I_t"] - c["I_p"])
    return float(np.sqrt(c["k_eff"] / den)) if den > 0 else np.inf


def unbalance_response(p: dict, spins) -> np.ndarray:
    """Steady synchronous tilt θ = a e^{iΩt} (θ = θx + iθy as in `whirl_damped`, heavy spot at
    e^{i(Ωt + π/2)}: the centre of mass starts on body y) of the unbalanced rotor at constant
    spin Ω: the complex amplitudes a, one per spin.

    The eccentricity e puts the centre of mass at R(0, e, l); to first order in e it adds the
    rotating moment −m e (l Ω² − g_z) e^{iΩt} to `whirl_damped`'s equation: the centrifugal
    force m e Ω² at height l (equivalently the product of inertia I_yz = −m e l spun at Ω)
    and gravity on the offset centre of mass (m e g_z). With θ = a e^{iΩt} the internal damper
    sees no motion (θ̇ − iΩθ = 0: synchronous whirl is rigid rotation) and
        a = −m e (l Ω² − g_z) / (k_eff − (I_t − I_p) Ω² + i c_e Ω),
    whose undamped peak is the forward critical speed √(k_eff/(I_t − I_p))."""
    c = constants(p)
    W = np.asarray(spins, float)
    force = -p["m"] * p["eccentricity"] * (p["l"] * W**2 - c["gravity"][2])
    return force / (c["k_eff"] - (c["I_t"] - c["I_p"]) * W**2
                    + 1j * p.get("c_ext", 0.0) * W)
