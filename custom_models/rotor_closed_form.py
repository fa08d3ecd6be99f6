"""Closed-form whirl frequencies of the rotor at constant spin Ω (the `closed-form` solver).

Small tilt about steady spin, axisymmetric disk (eccentricity 0), gravity along the shaft:
    I_t w² ∓ I_p Ω w − k_eff = 0,  I_t = mR²/4 + m l²,  I_p = mR²/2,  k_eff = k + m l g_z
(the sign pair gives forward and backward whirl). Exact for eccentricity 0 and axial gravity.
"""
import numpy as np

MODES_SETTINGS = {}


def inertias(params):
    m, R, l = params["m"], params["R"], params["l"]
    g = np.asarray(params["gravity"], float)
    return m * R**2 / 4 + m * l**2, m * R**2 / 2, params["k"] + m * l * g[2]


def whirl_sweep(params, spins):
    """(backward, forward) inertial whirl frequencies in rad/s for each spin in `spins`."""
    I_t, I_p, k_eff = inertias(params)
    W = np.abs(np.asarray(spins, float))
    root = np.sqrt((I_p * W) ** 2 + 4 * I_t * k_eff)
    return (root - I_p * W) / (2 * I_t), (root + I_p * W) / (2 * I_t)


def modes(params, settings):
    b, f = whirl_sweep(params, [params["spin"]])
    exact = params.get("eccentricity", 0.0) == 0 and not np.any(np.asarray(params["gravity"])[:2])
    return {"frequencies_hz": [b[0] / (2 * np.pi), f[0] / (2 * np.pi)],
            "labels": ["backward whirl", "forward whirl"],
            "settings": {"exact": bool(exact)}}
