"""Closed-form whirl of the rotor at constant spin Ω (the `closed-form` solver).

Small tilt about steady spin, axisymmetric disk (eccentricity 0), gravity along the shaft:
    I_t w² ∓ I_p Ω w − k_eff = 0,  I_t = mR²/4 + m l²,  I_p = mR²/2,  k_eff = k + m l g_z
(the sign pair gives forward and backward whirl); with the external and internal dampers the
complex quadratic of `compare.physics.rotor.whirl_damped` gives damped frequencies, ζ and the
growth rate. The formulas live in compare.physics.rotor, shared with the scene's findings.
"""
import numpy as np

from compare.contract import LeafModes
from compare.physics import eigen
from compare.physics import rotor as physics
from compare.physics.rotor import whirl_closed_form, whirl_damped

MODES_SETTINGS: dict = {}


def _roots(params: dict, spin: float) -> np.ndarray:
    """The two whirl roots λ = σ + iω, ascending |ω|; undamped, the real formula's ±w."""
    if params.get("c_ext", 0.0) == 0 and params.get("c_int", 0.0) == 0:
        b, f = whirl_closed_form(params, [spin])
        sense = np.sign(spin) or 1.0                    # forward whirls with the spin
        return 1j * sense * np.array([-b[0], f[0]])
    lam = whirl_damped(params, spin)
    return lam[np.argsort(np.abs(lam.imag))]


def whirl_sweep(params: dict, spins) -> tuple[np.ndarray, np.ndarray]:
    """(backward, forward) inertial whirl frequencies in rad/s for each spin in `spins`."""
    w = np.abs([_roots(params, s).imag for s in spins])
    return w[:, 0], w[:, 1]


def modes(params: dict, settings: dict) -> LeafModes:
    spin = params["spin"]
    lam = _roots(params, spin)
    w = np.abs(lam.imag)
    whirl = (["backward", "forward"] if spin == 0 else
             ["forward" if np.sign(x) == np.sign(spin) else "backward" for x in lam.imag])
    notes = []
    if params["eccentricity"] != 0:
        notes.append("approximate: the closed form ignores the eccentricity")
    if np.any(np.asarray(params["gravity"])[:2]):
        notes.append("approximate: the closed form takes only the axial gravity component")
    # a quadratic's roots: a few roundings (exact only where `exact`)
    err = {"frequency_error_hz": 8 * np.finfo(float).eps * w / (2 * np.pi)} if not notes else {}
    # ζ's round-off: the roots as eigenvalues of their monic quadratic's companion matrix
    companion = np.array([[lam[0] + lam[1], -lam[0] * lam[1]], [1.0, 0.0]])
    z_err = eigen.root_zeta_errors(companion, lam)
    return LeafModes(frequencies_hz=w / (2 * np.pi), labels=[f"{d} whirl" for d in whirl],
                     damping=-lam.real / np.abs(lam), whirl=whirl,
                     settings={"exact": not notes}, notes=notes,
                     extra={**err, "damping_error": z_err,
                            "max_re_per_s": float(np.max(lam.real))})


def unbalance_response(params: dict, spins) -> tuple[np.ndarray, np.ndarray]:
    """Steady unbalance tilt amplitudes a (θ = a e^{iΩt}, `compare.physics.rotor.
    unbalance_response`) at each spin and their error: a few roundings of one complex ratio."""
    a = physics.unbalance_response(params, spins)
    return a, 8 * np.finfo(float).eps * np.abs(a)
