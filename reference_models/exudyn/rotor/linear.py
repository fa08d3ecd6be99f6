"""The linearised whirl: `modes` and `whirl_sweep`.

The upright tree (`model.upright`, drive torque 0) is linearised about steady spin Ω at tilt 0
with Exudyn's `ComputeLinearizedSystem` (M, K and the gyroscopic D = −∂f/∂q̇; gravity enters K
through the tree) and the quadratic eigenproblem solved.
"""
import math

import exudyn as exu
import numpy as np

from compare.contract import LeafModes
from compare.physics import eigen

from .model import upright

FD_VARY = 10.0      # Exudyn's finite-difference step × this: the linearisation's own error
# Exudyn forms M, K and D inside the engine, rounding more than the eigensolver's floor: over
# 140 random rotor-whirl sets its frequencies' distance to the closed form (exact to an ulp)
# reached 1.25 × that floor (its own round-off plus the closed form's 8 eps); 2.5 × it holds
# them with a margin of 2 (on the tilt block, `whirl_coordinates`: the distance to the exact
# quadratic ≤ 0.44 of the bar at 100 sweep speeds of six damper pairs)
FORMATION = 2.5


TILT, SPIN = [0, 1], [2]      # the two Cardan tilt angles, the spin angle


def whirl_coordinates(M, K, D) -> list:
    """The coordinates the whirl roots are solved on: the tilt angles alone where the tilt
    rows do not depend on the spin coordinate (an axisymmetric rotor: nothing depends on the
    spin angle or its rate to first order), else all three (an eccentric rotor couples them).
    Block-triangular, the whirl roots are then the tilt block's; the spin row holds only the
    finite differences' noise (~1e-8 × c_int Ω), and with it the state matrix's defective zero
    pair cost the whirl roots 40–47 ulp where the block's are 5–9 against the exact quadratic
    (`xval modes rotor-whirl --set spin=140 --set c_int=0.5 --set c_ext=0.05`: the sweep's
    forward whirl at 15.15 rad/s 8.8e-15 off the closed form against a bar of 8.5e-15)."""
    coupled = any(np.any(X[np.ix_(TILT, SPIN)]) for X in (M, K, D))
    return TILT + SPIN if coupled else TILT


def block(mats, idx):
    return tuple(X[np.ix_(idx, idx)] for X in mats)


def linearised(model, spin, fd_scale=1.0):
    """M, K, D of the tree at tilt 0 spinning at `spin` (rad/s) about e_z; `fd_scale` ×
    Exudyn's finite-difference step."""
    mbs = model["mbs"]
    mbs.systemData.SetODE2Coordinates([0.0, 0.0, 0.0], exu.ConfigurationType.Initial)
    mbs.systemData.SetODE2Coordinates_t([0.0, 0.0, float(spin)], exu.ConfigurationType.Initial)
    ss = exu.SimulationSettings()
    ss.staticSolver.newton.numericalDifferentiation.relativeEpsilon *= fd_scale
    out = mbs.ComputeLinearizedSystem(ss)
    return [np.asarray(x, float) for x in out[:3]]


def state_matrix(M, K, D):
    n = M.shape[0]
    Minv = np.linalg.inv(M)
    return np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ K, -Minv @ D]])


def _whirl_pair(M, K, D, spin):
    """Two whirl frequencies (rad/s) and their labels from the quadratic eigenproblem."""
    lam, V = np.linalg.eig(state_matrix(M, K, D))
    w = lam.imag
    sel = np.where(w > 1e-6 * max(1.0, np.max(np.abs(lam))))[0]
    pairs = []
    for i in sel:
        X, Y = V[0, i], V[1, i]           # q0 ~ tilt about x, q1 ~ tilt about y
        # n ≈ (q1, −q0): sense of the whirl of n about +z for the motion Re(v e^{iwt})
        nx, ny = Y, -X
        sense = w[i] * np.imag(nx * np.conj(ny))
        pairs.append((w[i], sense, lam[i].real))
    pairs.sort(key=lambda p: p[0])
    if len(pairs) != 2:
        raise ValueError(f"the upright rotor is not a stable whirl at spin {spin:g} rad/s "
                         f"({len(pairs)} oscillatory modes; is k <= m g l?)")
    if abs(spin) < 1e-12:
        labels = ["backward whirl", "forward whirl"]
    else:
        labels = ["forward whirl" if p[1] * spin > 0 else "backward whirl" for p in pairs]
    return [p[0] for p in pairs], labels, [p[2] for p in pairs]


def modes(params, settings=None):
    """Linearised whirl frequencies (Hz) at steady spin params['spin'] about the upright axis."""
    spin = float(params["spin"])
    model = upright(params)
    mats = linearised(model, spin)
    idx = whirl_coordinates(*mats)
    M, K, D = block(mats, idx)
    w, labels, re = _whirl_pair(M, K, D, spin)
    re = np.asarray(re, float)
    # ζ's and the frequencies' errors: eigen round-off plus the change when the FD step is
    # varied, mode by mode
    A = state_matrix(M, K, D)
    A_varied = state_matrix(*block(linearised(model, spin, FD_VARY), idx))
    roots = re + 1j * np.asarray(w)
    z_err = eigen.root_zeta_errors(A, roots, A_varied)
    f_err = eigen.root_errors(A, roots, A_varied, FORMATION) / (2 * math.pi)
    return LeafModes(frequencies_hz=np.array(w) / (2 * math.pi), labels=labels,
                     damping=-re / np.hypot(re, w),           # ζ = −Re λ / |λ|
                     whirl=[lb.split()[0] for lb in labels],
                     extra={"max_re_per_s": float(np.max(re)),
                            "damping_error": z_err, "frequency_error_hz": f_err},
                     settings={"method": "exudyn ComputeLinearizedSystem + dense quadratic "
                                         "eigenproblem", "drive_torque": 0.0},
                     notes=_approximate_note(params))


def whirl_sweep(params, spins):
    """Backward and forward whirl frequencies (rad/s) over an array of spins, one model reused."""
    model = upright(params)
    spins = np.asarray(spins, dtype=float)
    bw = np.empty(len(spins))
    fw = np.empty(len(spins))
    for i, sp in enumerate(spins):
        mats = linearised(model, sp)
        w, labels, _ = _whirl_pair(*block(mats, whirl_coordinates(*mats)), sp)
        if sp == 0.0:
            bw[i], fw[i] = w
        else:
            fw[i] = w[labels.index("forward whirl")]
            bw[i] = w[labels.index("backward whirl")]
    return bw, fw


def _approximate_note(params):
    if params["spin"] != 0 and params["eccentricity"] != 0:
        return ["approximate: steady spin is no equilibrium of an eccentric rotor"]
    return []
