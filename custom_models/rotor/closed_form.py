"""Closed-form whirl frequencies of the rotor at constant spin Ω (the `closed-form` solver).

Small tilt about steady spin, axisymmetric disk (eccentricity 0), gravity along the shaft:
    I_t w² ∓ I_p Ω w − k_eff = 0,  I_t = mR²/4 + m l²,  I_p = mR²/2,  k_eff = k + m l g_z
(the sign pair gives forward and backward whirl); the formula lives in compare.physics.rotor,
shared with the scene's findings.
"""
import numpy as np

from compare.contract import LeafModes
from compare.physics.rotor import whirl_closed_form

MODES_SETTINGS: dict = {}


def whirl_sweep(params: dict, spins) -> tuple[np.ndarray, np.ndarray]:
    """(backward, forward) inertial whirl frequencies in rad/s for each spin in `spins`."""
    return whirl_closed_form(params, spins)


def modes(params: dict, settings: dict) -> LeafModes:
    b, f = whirl_closed_form(params, [params["spin"]])
    notes = []
    if params["eccentricity"] != 0:
        notes.append("approximate: the closed form ignores the eccentricity")
    if np.any(np.asarray(params["gravity"])[:2]):
        notes.append("approximate: the closed form takes only the axial gravity component")
    return LeafModes(frequencies_hz=np.array([b[0], f[0]]) / (2 * np.pi),
                       labels=["backward whirl", "forward whirl"],
                       settings={"exact": not notes}, notes=notes,
                       # a quadratic's roots: a few roundings (exact only where `exact`)
                       extra={"frequency_error_hz": 8 * np.finfo(float).eps
                              * np.abs([b[0], f[0]]) / (2 * np.pi)} if not notes else {})
