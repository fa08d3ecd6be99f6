"""`unbalance_response`: the steady synchronous tilt of the unbalanced rotor from the tree's
linearisation and Exudyn's own acceleration."""
import exudyn as exu
import numpy as np

from .linear import linearised
from .model import build, rotor, sim_settings, solve, upright
from .settings import SOLVERS


def _acceleration(params, phi, spin, h=1e-3):
    """q̈ of the tree at tilt 0, spin angle φ, spin rate Ω: one explicit Euler step of size h
    from q̇0 = (0, 0, Ω) gives q̇1 = q̇0 + h q̈(q0, q̇0), so (q̇1 − q̇0)/h is Exudyn's own
    acceleration (no cancellation in the transverse rows, where q̇0 is 0)."""
    rotor_at = rotor(params, q0=np.array([0.0, 0.0, phi]), qd0=np.array([0.0, 0.0, spin]))
    model = build([rotor_at], with_work=False, stop_checks=False)
    ex = solve(model["mbs"], sim_settings(0.0, h, 1, 0.0, "explicit_euler", 1e-10),
               SOLVERS["explicit_euler"])
    if ex is not None:
        raise RuntimeError(f"exudyn: {ex}")
    v1 = np.asarray(model["mbs"].systemData.GetODE2Coordinates_t(exu.ConfigurationType.Current))
    return (v1 - np.array([0.0, 0.0, spin])) / h


def _unbalance_amplitudes(params, spins, he):
    """Forward tilt amplitudes a (θ ≈ q0 + i q1 = a e^{iΩt}: the first two Cardan angles are
    the fixed-frame tilt to first order) from M, K, D of `ComputeLinearizedSystem` and the
    unbalance input: d q̈/de by central differences (±he) of Exudyn's acceleration at spin
    angle φ. The input turns with the rotor, B(φ) = Re(b e^{iφ}), b = B(0) − i B(π/2); the
    steady q = Re(X e^{iΩt}) solves (K − Ω² M + iΩ D) X = M b e."""
    base = dict(params, eccentricity=0.0)
    model = upright(base)
    out = []
    for spin in spins:
        M, K, D = linearised(model, spin)
        B = [(_acceleration({**base, "eccentricity": he}, phi, spin)
              - _acceleration({**base, "eccentricity": -he}, phi, spin)) / (2 * he)
             for phi in (0.0, np.pi / 2)]
        X = np.linalg.solve(K - spin**2 * M + 1j * spin * D,
                            M @ (B[0] - 1j * B[1]) * params["eccentricity"])
        out.append((X[0] + 1j * X[1]) / 2)
    return np.array(out)


HE = 1e-7            # the eccentricity step of the input derivative, per unit l


def unbalance_response(params, spins):
    """(a, error) per spin (`_unbalance_amplitudes`); the error is the central differences'
    change from step 2he to he (4/3 of it; he = 1e-7 l: 1e-4 l left the O(he²) truncation,
    9.4e-9 relative, the closed form 9e-15 away at 1e-7 l), plus a few roundings."""
    he = HE * params["l"]
    a, a2 = _unbalance_amplitudes(params, spins, he), _unbalance_amplitudes(params, spins, 2 * he)
    return a, 4 / 3 * np.abs(a - a2) + 8 * np.finfo(float).eps * np.abs(a)
