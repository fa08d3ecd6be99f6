"""Whirl frequencies from the Euler-vector model's own linearisation (`euler-vector`, modes).

The right-hand side of `rotor_euler` is differentiated numerically (central differences) about
steady spin Ω e_z at zero tilt, in the reduced state x = (K, γ_x, γ_y): the axial angle φ and the
work A do not feed back (axisymmetric disk), and γ_z ≡ 0. The eigenvalues ±i·w of the Jacobian
are the whirl frequencies; the rotation sense of the tilt in the eigenvector tells forward
(with the spin) from backward whirl. The dampers add their moments to K' in this model's own
variables: external −c_ext γ' (the fixed-frame tilt rate) and internal −c_int (γ' − ω × γ), the
rate of the tilt seen in the spinning rotor's frame (d/dt of Rᵀγ, turned back by R); their
real parts σ of λ = σ ± iw give ζ = −σ/|λ| and the growth rate.
"""
import numpy as np

from compare.contract import LeafModes, merge_settings
from compare.physics import eigen

from . import model as rotor
from .euler_vector import kinematics, rhs

MODES_SETTINGS = {"fd_step": 1e-6}


def _reduced_rhs(p, x, c_ext=0.0, c_int=0.0, phi=0.0):
    """The reduced right-hand side (K', γ_x', γ_y') at x = (K, γ_x, γ_y) and axial turn φ, the
    dampers' moments added to K'."""
    kin = np.empty((1, 13))
    y = np.zeros(8)
    y[0:3], y[3:5], y[6] = x[0:3], x[3:5], phi
    d = rhs(0.0, y, p)
    kinematics(y[None, :], p, kin)
    kin = kin[0]                                           # kin[9:12]: ω in the fixed frame
    d[0:3] -= c_ext * d[3:6] + c_int * (d[3:6] - np.cross(kin[9:12], y[3:6]))
    return np.concatenate([d[0:3], d[3:5]])


def _reduced_jacobian(p, K0, h, c_ext=0.0, c_int=0.0):
    def f(x):
        return _reduced_rhs(p, x, c_ext, c_int)
    x0 = np.concatenate([K0, [0.0, 0.0]])
    J = np.empty((5, 5))
    for j in range(5):
        dx = np.zeros(5)
        dx[j] = h * max(1.0, abs(x0[j]))
        J[:, j] = (f(x0 + dx) - f(x0 - dx)) / (2 * dx[j])
    return J


def whirl_roots(params, spin, h=1e-6, with_floor=False):
    """The (backward, forward) whirl eigenvalues λ = σ + iw (w > 0, rad/s) at spin Ω; with
    `with_floor` also their round-off bounds |δλ| (compare.physics.eigen). For an eccentric
    rotor at Ω ≠ 0 steady spin is no equilibrium: the linearisation is approximate."""
    p = rotor.pack(dict(params, torque=0.0))
    I0 = p[rotor.I0].reshape(3, 3)
    J = _reduced_jacobian(p, I0 @ np.array([0.0, 0.0, spin]), h,
                          params.get("c_ext", 0.0), params.get("c_int", 0.0))
    lam, V = np.linalg.eig(J)
    pos = [i for i in range(5) if lam[i].imag > 1e-8 * max(1.0, abs(lam).max())]
    if len(pos) != 2:
        raise RuntimeError(f"expected two whirl pairs, got eigenvalues {lam}")
    # rotation sense of the tilt vector Re(v e^{λt}): positive = counter-clockwise about +z
    sense = np.array([-np.imag(np.conj(V[3, i]) * V[4, i]) for i in pos])
    if spin == 0:
        pos = [pos[i] for i in np.argsort(lam[pos].imag)]
    else:
        fwd = np.sign(sense) == np.sign(spin)
        if fwd.sum() != 1:
            raise RuntimeError("could not tell forward from backward whirl")
        pos = [pos[int(np.argmin(fwd))], pos[int(np.argmax(fwd))]]
    roots = tuple(complex(lam[i]) for i in pos)
    if not with_floor:
        return roots
    return roots, eigen.round_off(J, lam, V, eigen.left_rows(V), pos)


def whirl(params, spin, h=1e-6):
    """(backward, forward) whirl frequencies in rad/s at spin Ω."""
    b, f = whirl_roots(params, spin, h)
    return float(b.imag), float(f.imag)


def whirl_sweep(params, spins):
    pairs = np.array([whirl(params, s) for s in spins])
    return pairs[:, 0], pairs[:, 1]


def _zeta(lam):
    return -lam.real / np.abs(lam)


def modes(params, settings):
    s = merge_settings(settings, MODES_SETTINGS, ())
    lam, floor = whirl_roots(params, params["spin"], s["fd_step"], with_floor=True)
    lam = np.array(lam)
    lam2 = np.array(whirl_roots(params, params["spin"], 2 * s["fd_step"]))
    # the central differences' change from step 2h to h (4/3 of it: their O(h²) truncation;
    # their round-off differs between the two steps and shows in it too) plus the eigen
    # solver's round-off (eps/h per derivative was 1e5× the 1e-14 deviation seen at 50 rad/s)
    err = (4 / 3 * np.abs(lam.imag - lam2.imag) + 8 * np.finfo(float).eps * lam.imag) \
        / (2 * np.pi)
    order = np.argsort(lam.imag)         # ascending frequency (backward first while spin ≥ 0)
    whirl_dirs = np.array(["backward", "forward"])[order]
    notes = (["approximate: steady spin is no equilibrium of an eccentric rotor"]
             if params["spin"] != 0 and params["eccentricity"] != 0 else [])
    # ζ's error: the same change of step (4/3 of it) plus the eigen round-off floor
    z_err = 4 / 3 * np.abs(_zeta(lam) - _zeta(lam2)) + eigen.zeta_error(floor, lam)
    lam, err, z_err = lam[order], err[order], z_err[order]
    return LeafModes(frequencies_hz=lam.imag / (2 * np.pi),
                     labels=[f"{d} whirl" for d in whirl_dirs], whirl=list(whirl_dirs),
                     damping=-lam.real / np.abs(lam), settings=s, notes=notes,
                     extra={"frequency_error_hz": err, "damping_error": z_err,
                            "max_re_per_s": float(np.max(lam.real))})


def _unbalance_amplitudes(params, spins, h):
    """Forward tilt amplitudes a (θ = γ_x + iγ_y = a e^{iΩt}) from this model's linearisation
    J about steady spin and its unbalance input: the derivative of the reduced right-hand side
    with respect to the eccentricity e (central differences, step h·l) at the axial turn φ.
    The unbalance turns with the rotor, B(φ) = Re(b e^{iφ}), so b = B(0) − i B(π/2) and the
    steady response x = Re(X e^{iΩt}) solves (iΩ − J) X = b e; θ's forward part is
    (X_γx + i X_γy)/2 (its backward part, (X̄_γx + i X̄_γy)/2, is zero for the round rotor)."""
    base = dict(params, torque=0.0, eccentricity=0.0)
    p0 = rotor.pack(base)
    he = h * params["l"]
    pp, pm = rotor.pack({**base, "eccentricity": he}), rotor.pack({**base, "eccentricity": -he})
    ce, ci = params.get("c_ext", 0.0), params.get("c_int", 0.0)
    I0 = p0[rotor.I0].reshape(3, 3)
    out = []
    for spin in spins:
        K0 = I0 @ np.array([0.0, 0.0, spin])
        x0 = np.concatenate([K0, [0.0, 0.0]])
        J = _reduced_jacobian(p0, K0, h, ce, ci)
        B = [(_reduced_rhs(pp, x0, ce, ci, phi) - _reduced_rhs(pm, x0, ce, ci, phi)) / (2 * he)
             for phi in (0.0, np.pi / 2)]
        X = np.linalg.solve(1j * spin * np.eye(5) - J, (B[0] - 1j * B[1]) * params["eccentricity"])
        out.append((X[3] + 1j * X[4]) / 2)
    return np.array(out)


def unbalance_response(params, spins):
    """(a, error) per spin: the steady unbalance tilt amplitudes of `_unbalance_amplitudes`;
    the error is the central differences' change from step 2h to h (4/3 of it, as in `modes`)
    plus a few roundings."""
    h = MODES_SETTINGS["fd_step"]
    a, a2 = _unbalance_amplitudes(params, spins, h), _unbalance_amplitudes(params, spins, 2 * h)
    return a, 4 / 3 * np.abs(a - a2) + 8 * np.finfo(float).eps * np.abs(a)
