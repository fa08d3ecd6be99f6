"""Rotor on a spherical joint with a transverse angular spring (seed 000, scene rotor-spinup).

Shared by the two custom formulations (`rotor_euler`, `rotor_quaternion`): parameter packing,
the spring moment −kγ and the driver around the shared integrators. Each
formulation supplies only its right-hand side, its initial state and the map from its state to
(rotation, angular velocity, work).
"""
import time

import numba as nb
import numpy as np

from compare.contract import LeafResult, merge_settings
from compare.physics import rotor as physics

from .integrators import (
    ADAPTIVE_TABLEAUS,
    FAIL_REASONS,
    FIXED_TABLEAUS,
    integrate_adaptive,
    integrate_fixed,
)
from .rotation import matrix_to_quat, rotation_tensor, transverse_vector

INTEGRATORS = tuple(ADAPTIVE_TABLEAUS) + tuple(FIXED_TABLEAUS)
ADAPTIVE = tuple(ADAPTIVE_TABLEAUS)          # integrators that take rtol
# atol defaults to rtol/100; h_max to the output step; max_steps bounds a runaway adaptive run
DEFAULT_SETTINGS = {"integrator": "dop853", "rtol": 1e-11, "dt": None, "atol": None,
                    "h_max": None, "max_steps": 10**8}

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
    c = physics.constants(params)
    return np.concatenate([[params["l"], params["k"], params["m"], params["torque"]],
                           c["gravity"], c["rc0"], c["I_o"].ravel(),
                           np.linalg.inv(c["I_o"]).ravel()])


def initial_motion(params, p):
    """Initial rotation Rx(tilt0) and fixed-frame angular velocity spin0 · (body axis)."""
    R0 = rotation_tensor(np.array([params["tilt0"], 0.0, 0.0]))
    return R0, params["spin0"] * R0[:, 2]


@nb.njit(cache=True)
def spring_moment(R, p):
    """−kγ, γ the transverse Euler vector carrying e_z to the body axis R·e_z."""
    return -p[K_] * transverse_vector(R[:, 2])


@nb.njit(cache=True)
def tilt_guard(R):
    n_z = min(1.0, max(-1.0, R[2, 2]))
    return FAIL_TILT if np.arccos(n_z) > TILT_LIMIT else 0


def check_settings(settings, t_out):
    """The settings merged and checked before anything runs (a fixed step must divide the
    output step into whole steps: the drivers write the grid without interpolation)."""
    s = merge_settings(settings, DEFAULT_SETTINGS, INTEGRATORS)
    if s["integrator"] in FIXED_TABLEAUS and t_out is not None and len(t_out) > 1:
        dt_out = t_out[1] - t_out[0]
        dt = s["dt"] or 1e-3
        substeps = int(round(dt_out / dt))
        if substeps < 1 or abs(substeps * dt - dt_out) > 1e-9 * dt_out:
            raise ValueError(f"dt={dt:g} must divide output_dt={dt_out:g} into whole steps")
    return s


def integrate(rhs, guard, y0, p, t_out, settings):
    """Run one of the shared integrators; returns (Y, stats, t_fail, reason, used settings)."""
    s = check_settings(settings, t_out)
    name = s["integrator"]
    if name in FIXED_TABLEAUS:
        dt_out = t_out[1] - t_out[0]
        substeps = int(round(dt_out / (s["dt"] or 1e-3)))
        tb = FIXED_TABLEAUS[name]
        t0 = time.perf_counter()
        Y, steps, evals, t_fail, code = integrate_fixed(rhs, guard, y0, p, t_out, substeps,
                                                        tb["A"], tb["B"], tb["C"])
        used = {"integrator": name, "dt": dt_out / substeps}
        stats = {"steps": int(steps), "rhs_evals": int(evals)}
    elif name in ADAPTIVE_TABLEAUS:
        tb = ADAPTIVE_TABLEAUS[name]
        rtol = float(s["rtol"])
        atol = float(s["atol"] or rtol * 1e-2)
        h_max = float(s["h_max"] or (t_out[1] - t_out[0]))
        t0 = time.perf_counter()
        Y, steps, evals, rej, t_fail, code = integrate_adaptive(
            rhs, guard, y0, p, t_out, rtol, atol, h_max, int(s["max_steps"]),
            tb["A"], tb["B"], tb["C"], tb["E"], tb["E3"], tb["err_order"])
        used = {"integrator": name, "rtol": rtol, "atol": atol}
        stats = {"steps": int(steps), "rhs_evals": int(evals), "rejected": int(rej)}
    stats["integrate_s"] = time.perf_counter() - t0
    return Y, stats, (None if code == 0 else float(t_fail)), REASONS.get(int(code)), used


def result(params, t_out, Y, stats, t_fail, reason, used, motion, p, invariants=None):
    """Assemble the LeafResult; rows after a failure stay NaN."""
    Rs, omegas, work = motion(Y, p)
    ok = np.isfinite(Y).all(axis=1)
    quats = np.full((len(t_out), 4), np.nan)
    quats[ok] = [matrix_to_quat(R) for R in Rs[ok]]
    return LeafResult(channels=physics.channels(params, Rs, omegas, work), stats=stats,
                      settings=used, status="ok" if t_fail is None else "diverged",
                      t_fail=t_fail, reason=reason, extra={"orientation": quats},
                      invariants=invariants or {})
