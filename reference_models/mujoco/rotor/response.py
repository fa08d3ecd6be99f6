"""`unbalance_response`: the steady synchronous tilt of the unbalanced rotor from the
linearisation (`linear.continuous_A`) and MuJoCo's own acceleration."""
import mujoco
import numpy as np

from .callback import Callback
from .linear import FD_EPS, continuous_A, linearisation_model
from .model import compile_model

HE = 1e-7           # eccentricity step of the input derivative, per unit l
TRANSVERSE = [0, 1, 3, 4]       # δ_x, δ_y, v_x, v_y: the spin rows do not couple at tilt 0


def _models(params, settings):
    """The linearisation's models, compiled once for every spin and both FD steps: (params,
    model) of the balanced rotor and of the rotors with the eccentricity ±he (he = HE·l)."""
    base = dict(params, eccentricity=0.0)
    he = HE * params["l"]
    s, m, _ = linearisation_model(base, settings)
    points = [base] + [{**base, "eccentricity": e} for e in (he, -he)]
    return [(p, m if p is base else compile_model(p, s, "euler")) for p in points]


def _qacc(point, settings, spin):
    """MuJoCo's acceleration (mj_forward) at tilt 0 spinning at Ω about e_z; `point`: (params,
    its compiled model)."""
    params, model = point
    _, m, d = linearisation_model(params, settings, model)
    d.qpos[:] = (1.0, 0.0, 0.0, 0.0)
    d.qvel[:] = (0.0, 0.0, spin)
    mujoco.mj_forward(m, d)
    return np.array(d.qacc, dtype=float)


def _unbalance_amplitudes(params, spins, settings, eps, models):
    """Forward tilt amplitudes a (θ = a e^{iΩt}). In the ball joint's body-frame coordinates
    the unbalance is fixed (it turns with the body): the steady response is the constant δ
    with A δ + b e = 0 on the transverse rows, A = `continuous_A` (mjd_transitionFD), b =
    d q̈/de by central differences (±HE l) of mj_forward. Back in the fixed frame the tilt is
    θ = e^{iΩt}(δ_x + iδ_y) (the axis R e_z ≈ R_z(Ωt)(e_z + δ × e_z)), so a = δ_x + iδ_y."""
    (base, model), up, down = models
    he = up[0]["eccentricity"]
    s, m, d = linearisation_model(base, settings, model)
    out = []
    with Callback(s["callback"]):
        for spin in spins:
            A = continuous_A(m, d, spin, eps)[np.ix_(TRANSVERSE, TRANSVERSE)]
            b = (_qacc(up, settings, spin) - _qacc(down, settings, spin)) / (2 * he)
            rhs = -np.concatenate([[0.0, 0.0], b[:2]]) * params["eccentricity"]
            delta = np.linalg.solve(A, rhs)
            out.append((delta[0] + 1j * delta[1], np.linalg.cond(A)))
    a, cond = np.array(out).T
    return a, cond.real


def unbalance_response(params, spins, settings=None):
    """(a, error) per spin (`_unbalance_amplitudes`); the error is the change of the result
    when mjd_transitionFD's step is doubled (4/3 of it: its truncation) plus the linear
    solve's round-off, cond(A)·ε·|a| (the bar without it, 5.9e-15 relative at 82 rad/s, fell
    short of the 7.6e-15 seen against the closed form; cond(A) ≈ 1e2…1e4)."""
    models = _models(params, settings)
    a, cond = _unbalance_amplitudes(params, spins, settings, FD_EPS, models)
    a2, _ = _unbalance_amplitudes(params, spins, settings, 2 * FD_EPS, models)
    return a, 4 / 3 * np.abs(a - a2) + (cond + 8) * np.finfo(float).eps * np.abs(a)
