"""Whirl frequencies from the Euler-vector model's own linearisation (`euler-vector`, modes).

The right-hand side of `rotor_euler` is differentiated numerically (central differences) about
steady spin Ω e_z at zero tilt, in the reduced state x = (K, γ_x, γ_y): the axial angle φ and the
work A do not feed back (axisymmetric disk), and γ_z ≡ 0. The eigenvalues ±i·w of the Jacobian
are the whirl frequencies; the rotation sense of the tilt in the eigenvector tells forward
(with the spin) from backward whirl.
"""
import numpy as np

from compare.contract import LeafModes, merge_settings

from . import model as rotor
from .euler_vector import rhs

MODES_SETTINGS = {"fd_step": 1e-6}


def _reduced_jacobian(p, K0, h):
    def f(x):
        y = np.zeros(8)
        y[0:3], y[3:5] = x[0:3], x[3:5]
        d = rhs(0.0, y, p)
        return np.concatenate([d[0:3], d[3:5]])
    x0 = np.concatenate([K0, [0.0, 0.0]])
    J = np.empty((5, 5))
    for j in range(5):
        dx = np.zeros(5)
        dx[j] = h * max(1.0, abs(x0[j]))
        J[:, j] = (f(x0 + dx) - f(x0 - dx)) / (2 * dx[j])
    return J


def whirl(params, spin, h=1e-6):
    """(backward, forward) whirl frequencies in rad/s at spin Ω. For an eccentric rotor at
    Ω ≠ 0 steady spin is no equilibrium: the linearisation about it is only approximate."""
    p = rotor.pack(dict(params, torque=0.0))
    I0 = p[rotor.I0].reshape(3, 3)
    lam, V = np.linalg.eig(_reduced_jacobian(p, I0 @ np.array([0.0, 0.0, spin]), h))
    pos = [i for i in range(5) if lam[i].imag > 1e-8 * max(1.0, abs(lam).max())]
    if len(pos) != 2:
        raise RuntimeError(f"expected two whirl pairs, got eigenvalues {lam}")
    w = np.array([lam[i].imag for i in pos])
    # rotation sense of the tilt vector Re(v e^{iwt}): positive = counter-clockwise about +z
    sense = np.array([-np.imag(np.conj(V[3, i]) * V[4, i]) for i in pos])
    if spin == 0:
        return tuple(np.sort(w))
    fwd = np.sign(sense) == np.sign(spin)
    if fwd.sum() != 1:
        raise RuntimeError("could not tell forward from backward whirl")
    return float(w[~fwd][0]), float(w[fwd][0])


def whirl_sweep(params, spins):
    pairs = np.array([whirl(params, s) for s in spins])
    return pairs[:, 0], pairs[:, 1]


def modes(params, settings):
    s = merge_settings(settings, MODES_SETTINGS, ())
    b, f = whirl(params, params["spin"], s["fd_step"])
    b2, f2 = whirl(params, params["spin"], 2 * s["fd_step"])
    # the central differences' change from step 2h to h (4/3 of it: their O(h²) truncation;
    # their round-off differs between the two steps and shows in it too) plus the eigen
    # solver's round-off (eps/h per derivative was 1e5× the 1e-14 deviation seen at 50 rad/s)
    err = (4 / 3 * np.abs([b - b2, f - f2]) + 8 * np.finfo(float).eps * np.abs([b, f])) \
        / (2 * np.pi)
    notes = (["approximate: steady spin is no equilibrium of an eccentric rotor"]
             if params["spin"] != 0 and params["eccentricity"] != 0 else [])
    return LeafModes(frequencies_hz=np.array([b, f]) / (2 * np.pi),
                       labels=["backward whirl", "forward whirl"], settings=s, notes=notes,
                       extra={"frequency_error_hz": err})
