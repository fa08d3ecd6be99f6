"""Rotor on a spherical joint with a transverse angular spring (seed 000, scene rotor-spinup).

Shared by the two custom formulations (`rotor_euler`, `rotor_quaternion`): parameter packing,
the spring moment −kγ, the output channels and the driver around the shared integrators. Each
formulation supplies only its right-hand side, its initial state and the map from its state to
(rotation, angular velocity, work).
"""
import time
import numpy as np
import numba as nb

from .integrators import (ADAPTIVE_TABLEAUS, FIXED_TABLEAUS, FAIL_REASONS, integrate_adaptive,
                          integrate_fixed)
from .rotation import rotation_tensor, transverse_vector

CHANNELS = ("omega_norm", "spin_rate", "tilt", "work", "kinetic", "potential", "energy_balance")
INTEGRATORS = tuple(ADAPTIVE_TABLEAUS) + tuple(FIXED_TABLEAUS)
ADAPTIVE = tuple(ADAPTIVE_TABLEAUS)          # integrators that take rtol
DEFAULT_SETTINGS = {"integrator": "dop853", "rtol": 1e-11, "dt": None}

# Both the spring law −kγ and the Euler-vector split lose their meaning at tilt π (the transverse
# axis is undefined there): stop this close to it and say so.
TILT_LIMIT = np.pi - 1e-3
FAIL_TILT = 10
REASONS = {**FAIL_REASONS, FAIL_TILT: "tilt reached pi: the transverse Euler vector (and the "
                                     "spring -k*gamma) is undefined there"}

# layout of the packed parameter array p
L_, K_, M_, TORQUE, G = 0, 1, 2, 3, slice(4, 7)
RC0, I0, I0INV = slice(7, 10), slice(10, 19), slice(19, 28)


def pack(params):
    """Physical parameters as one float64 array (numba kernels take no globals)."""
    l, m, R, e = params["l"], params["m"], params["R"], params["eccentricity"]
    rc0 = np.array([0.0, e, l])
    I_c = np.diag([m * R**2 / 4, m * R**2 / 4, m * R**2 / 2])
    I_o = I_c + m * ((rc0 @ rc0) * np.eye(3) - np.outer(rc0, rc0))      # Steiner, about O
    return np.concatenate([[l, params["k"], m, params["torque"]],
                           np.asarray(params["gravity"], float), rc0, I_o.ravel(),
                           np.linalg.inv(I_o).ravel()])


def initial_motion(params, p):
    """Initial rotation Rx(tilt0) and fixed-frame angular velocity spin0 · (body axis)."""
    R0 = rotation_tensor(np.array([params.get("tilt0", 0.0), 0.0, 0.0]))
    return R0, params.get("spin0", 0.0) * R0[:, 2]


@nb.njit(cache=True)
def spring_moment(R, p):
    """−kγ, γ the transverse Euler vector carrying e_z to the body axis R·e_z."""
    return -p[K_] * transverse_vector(R[:, 2])


@nb.njit(cache=True)
def tilt_guard(R):
    n_z = min(1.0, max(-1.0, R[2, 2]))
    return FAIL_TILT if np.arccos(n_z) > TILT_LIMIT else 0


def channels(Rs, omegas, work, p):
    """Scene channels from rotations (n,3,3), fixed-frame ω (n,3) and drive work (n,)."""
    I0m, rc0, g = p[I0].reshape(3, 3), p[RC0], p[G]
    I = np.einsum("nij,jk,nlk->nil", Rs, I0m, Rs)
    kinetic = 0.5 * np.einsum("ni,nij,nj->n", omegas, I, omegas)
    n = Rs[:, :, 2]
    tilt = np.arctan2(np.hypot(n[:, 0], n[:, 1]), n[:, 2])
    rc = Rs @ rc0
    potential = 0.5 * p[K_] * tilt**2 - p[M_] * rc @ g
    return {"omega_norm": np.linalg.norm(omegas, axis=1), "spin_rate": omegas[:, 2],
            "tilt": tilt, "work": work, "kinetic": kinetic, "potential": potential,
            "energy_balance": kinetic + potential - work}


def integrate(rhs, guard, y0, p, t_out, settings):
    """Run one of the shared integrators; returns (Y, stats, t_fail, reason, used settings)."""
    s = dict(DEFAULT_SETTINGS, **{k: v for k, v in settings.items() if v is not None})
    name = s["integrator"]
    if name in FIXED_TABLEAUS:
        dt_out = t_out[1] - t_out[0]
        dt = s.get("dt") or 1e-3
        substeps = int(round(dt_out / dt))
        if substeps < 1 or abs(substeps * dt - dt_out) > 1e-9 * dt_out:
            raise ValueError(f"dt={dt} must divide output_dt={dt_out} into whole steps")
        tb = FIXED_TABLEAUS[name]
        t0 = time.perf_counter()
        Y, steps, evals, t_fail, code = integrate_fixed(rhs, guard, y0, p, t_out, substeps,
                                                        tb["A"], tb["B"], tb["C"])
        used = {"integrator": name, "dt": dt_out / substeps}
        stats = {"steps": int(steps), "rhs_evals": int(evals)}
    elif name in ADAPTIVE_TABLEAUS:
        tb = ADAPTIVE_TABLEAUS[name]
        rtol = float(s["rtol"])
        atol = float(s.get("atol") or rtol * 1e-2)
        h_max = float(s.get("h_max") or (t_out[1] - t_out[0]))
        t0 = time.perf_counter()
        Y, steps, evals, rej, t_fail, code = integrate_adaptive(
            rhs, guard, y0, p, t_out, rtol, atol, h_max, int(s.get("max_steps", 10**8)),
            tb["A"], tb["B"], tb["C"], tb["E"], tb["E3"], tb["err_order"])
        used = {"integrator": name, "rtol": rtol, "atol": atol}
        stats = {"steps": int(steps), "rhs_evals": int(evals), "rejected": int(rej)}
    else:
        raise ValueError(f"unknown integrator {name!r}; choose one of {', '.join(INTEGRATORS)}")
    stats["integrate_s"] = time.perf_counter() - t0
    return Y, stats, (None if code == 0 else float(t_fail)), REASONS.get(int(code)), used


def result(t_out, Y, stats, t_fail, reason, used, motion, p, extra_invariants=None):
    """Assemble the leaf-contract dict; rows after a failure stay NaN."""
    Rs, omegas, work = motion(Y, p)
    from .rotation import matrix_to_quat
    ok = np.isfinite(Y).all(axis=1)
    quats = np.full((len(t_out), 4), np.nan)
    quats[ok] = [matrix_to_quat(R) for R in Rs[ok]]
    out = {"channels": channels(Rs, omegas, work, p), "stats": stats, "settings": used,
           "status": "ok" if t_fail is None else "diverged", "t_fail": t_fail,
           "reason": reason, "extra": {"orientation": quats}}
    if extra_invariants:
        out["invariants"] = extra_invariants
    return out
