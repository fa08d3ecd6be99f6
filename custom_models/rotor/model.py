"""Rotor on a spherical joint with a transverse angular spring (seed 000, scene rotor-spinup).

Shared by the two custom formulations (`rotor_euler`, `rotor_quaternion`): parameter packing,
the spring moment −kγ and the driver around the shared integrators. Each
formulation supplies only its right-hand side, its initial state and the map from its state to
(rotation, angular velocity, work).

The integrators are the dense-output drivers (`integrators.dense`): the adaptive step is set by
the tolerance alone (no cap at the output interval unless `h_max` is given) and a fixed step
need not divide the output interval. The right-hand sides write into a given array and are
fused scalar code (`rotation.*_t` helpers): no allocation per evaluation.
"""

import numba as nb
import numpy as np

from compare.contract import LeafResult, check_once, merge_settings
from compare.physics import rotor as physics
from compare.physics.rotation import matrices_to_quats, rotation_tensor

from ..integrators import FAIL_REASONS, FIXED_TABLEAUS
from ..integrators.dense import DENSE_TABLEAUS, solve

INTEGRATORS = tuple(DENSE_TABLEAUS) + tuple(FIXED_TABLEAUS)
ADAPTIVE = tuple(DENSE_TABLEAUS)          # integrators that take rtol
# atol defaults to rtol/100; h_max (no cap by default) bounds the adaptive step; max_steps
# bounds a runaway adaptive run
DEFAULT_SETTINGS = {"integrator": "dop853", "rtol": 1e-11, "dt": None, "atol": None,
                    "h_max": None, "max_steps": 10**8}
# a map point's first look (compare/leafinfo.py `cheaper`): DOP853 at rtol 1e-4. Measured on 60
# random points of the default map (10 s, torque 1–5, e 0–0.02) against rtol 1e-11: max ||ω||
# error over the run 0.099 rad/s (quaternion), 0.126 (euler-vector); 1e-3 errs up to 1.7 rad/s.
# The margins it is read against are not all wide: on 200 random points the deciding level lies
# within 1 rad/s of |ω| for 12 % of them (least 0.04 rad/s: a late escape from capture), so a cheap
# label can be wrong (1000 random points: quaternion 0, euler-vector 2 differ from rtol 1e-11; at
# 1e-3, 0 and 8 of 300). It stands only where every neighbour reads the same; a point next to a
# regime change is rerun accurate (compare/workflows/maps.py); tests/studies/test_map_trace.py
# checks that the boundary is the all-accurate one and that sampled cheap labels hold. Looser buys
# little: DOP853's steps follow the whirl, 264 per run at 1e-4, 209 at 1e-3 (quaternion).
CHEAP_RTOL = {"dop853": 1e-4}

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
    return pack_many([params])[0]


def pack_many(params_list):
    """`pack` of many points as rows, the inertias inverted in one call (numpy's per-call
    overhead was a third of a map point's packing)."""
    cs = [physics.constants(p) for p in params_list]
    I_o = np.stack([c["I_o"] for c in cs])
    return np.hstack([np.array([[p["l"], p["k"], p["m"], p["torque"]] for p in params_list],
                               float),
                      np.stack([c["gravity"] for c in cs]), np.stack([c["rc0"] for c in cs]),
                      I_o.reshape(-1, 9), np.linalg.inv(I_o).reshape(-1, 9)])


def initial_motion(params, p):
    """Initial rotation Rx(tilt0) and fixed-frame angular velocity spin0 · (body axis)."""
    R0 = rotation_tensor(np.array([params["tilt0"], 0.0, 0.0]))
    return R0, params["spin0"] * R0[:, 2]


@nb.njit(cache=True)
def tilt_guard_z(n_z):
    """FAIL_TILT once the body axis' z component n_z = cos(tilt) is within TILT_LIMIT of π."""
    return FAIL_TILT if np.arccos(min(1.0, max(-1.0, n_z))) > TILT_LIMIT else 0


@check_once
def check_settings(settings, t_out=None):
    """The settings merged and checked before anything runs."""
    s = merge_settings(settings, DEFAULT_SETTINGS, INTEGRATORS)
    for key in ("dt", "rtol", "atol", "h_max"):
        v = s[key]
        if v is not None and not (isinstance(v, (int, float)) and np.isfinite(v) and v > 0):
            raise ValueError(f"{key} must be a positive number, got {v!r}")
    if not s["rtol"] < 1:
        raise ValueError(f"rtol must be in (0, 1), got {s['rtol']!r}")
    return s


def integrate(rhs, guard, y0, p, t_out, settings):
    """Run one of the shared integrators; returns (Y, stats, t_fail, reason, used settings)."""
    s = check_settings(settings, t_out)
    Y, stats, t_fail, code, used = solve(rhs, guard, y0, p, t_out, s["integrator"],
                                         dt=s["dt"] or 1e-3, rtol=s["rtol"], atol=s["atol"],
                                         h_max=s["h_max"], max_steps=s["max_steps"])
    return Y, stats, (None if code == 0 else float(t_fail)), REASONS.get(code), used


def result(params, t_out, Y, stats, t_fail, reason, used, motion, p, invariants=None,
           quats=None):
    """Assemble the LeafResult; rows after a failure stay NaN. `quats`: the orientation as
    unit quaternions (w ≥ 0) where the formulation has them, else taken from the rotations."""
    Rs, omegas, work = motion(Y, p)
    quats = matrices_to_quats(Rs) if quats is None else quats
    return LeafResult(channels=physics.channels(params, Rs, omegas, work), stats=stats,
                      settings=used, status="ok" if t_fail is None else "diverged",
                      t_fail=t_fail, reason=reason, extra={"orientation": quats},
                      invariants=invariants or {})
