"""Many rotor runs in one compiled call, each reduced to its regime where it ran: the map's
batch path (`regimes`, offered by both formulations).

Every point runs the shared integrator core of `integrators.dense` on the formulation's own
right-hand side and guard — the same compiled calls `simulate` makes — on the same output grid;
nothing per point returns to Python. From each run's rows it keeps what the map's decision
needs: the integrator's code, the regime (the scene's speed levels on |ω|) and the energy
numbers of the adapter's divergence rule (largest drift of the energy balance from its first
value, largest |value| of each energy channel), so that the caller applies that rule as
`simulate` does. The per-row channels are `physics.rotor.channels` in scalar form.
"""
import numba as nb
import numpy as np
from numba import types as nt

from ..integrators import FIXED_TABLEAUS
from ..integrators.dense import (
    DENSE_TABLEAUS,
    RHS_INTO,
    first_class,
    integrate_adaptive_dense,
    integrate_fixed_dense,
)
from ..integrators.explicit import _MAT, _VEC, GUARD
from ..rotation import mat_tvec_t, mat_vec_t
from .model import I0, K_, M_, RC0, G, check_settings, pack

# kinematics(Y, p, O): each row of O = rotation body → fixed (9, row-major), fixed-frame ω (3),
# work of that row of Y — one call per run, not one call through a pointer per row
KINEMATICS = nt.FunctionType(nt.void(_MAT, _VEC, _MAT))
# per point: finite, max |E − E(0)|, then max |value| of each of ENERGY_CHANNELS
ENERGY_CHANNELS = ("energy_balance", "kinetic", "potential", "work")
_I0, _RC0, _G = I0.start, RC0.start, G.start
_I64 = nt.int64[::1]


@nb.njit(cache=True)
def _row(o, p):
    """(|ω|, kinetic, potential) of one row o = (R, ω, work), as physics.rotor.channels."""
    w0, w1, w2 = o[9], o[10], o[11]
    b = mat_tvec_t(o, w0, w1, w2)                                   # body-frame ω
    I = p[_I0:_I0 + 9]
    kin = 0.5 * (b[0] * (I[0] * b[0] + I[1] * b[1] + I[2] * b[2])
                 + b[1] * (I[3] * b[0] + I[4] * b[1] + I[5] * b[2])
                 + b[2] * (I[6] * b[0] + I[7] * b[1] + I[8] * b[2]))
    tilt = np.arctan2(np.hypot(o[2], o[5]), o[8])
    rc = mat_vec_t(o, p[_RC0], p[_RC0 + 1], p[_RC0 + 2])
    pot = 0.5 * p[K_] * tilt * tilt - p[M_] * (rc[0] * p[_G] + rc[1] * p[_G + 1]
                                               + rc[2] * p[_G + 2])
    return np.sqrt(w0 * w0 + w1 * w1 + w2 * w2), kin, pot


@nb.njit(cache=True)
def _reduce(Y, p, t_out, kin, reach, stay, t_window, stats):
    """The regime of one run's rows (0: |ω| never reaches `reach` after t = 0, 2: it stays
    above `stay` from `t_window` on, else 1); fills `stats` (finite, drift, max |channel|)."""
    O = np.empty((Y.shape[0], 13))
    kin(Y, p, O)
    first, w_min, e0, finite = -1, np.inf, 0.0, True
    for k in range(1, 6):
        stats[k] = 0.0
    for j in range(Y.shape[0]):
        wn, ke, pe = _row(O[j], p)
        e = ke + pe - O[j, 12]
        if j == 0:
            e0 = e
        finite = finite and np.isfinite(wn) and np.isfinite(e)
        stats[1] = max(stats[1], abs(e - e0))
        stats[2] = max(stats[2], abs(e))
        stats[3] = max(stats[3], abs(ke))
        stats[4] = max(stats[4], abs(pe))
        stats[5] = max(stats[5], abs(O[j, 12]))
        if first < 0 and wn >= reach:
            first = j
        if t_out[j] >= t_window:
            w_min = min(w_min, wn)
    stats[0] = 1.0 if finite else 0.0
    if first <= 0:                  # never, or already at t = 0: first_crossing gives None
        return 0
    return 2 if w_min > stay else 1


@nb.njit(nt.void(RHS_INTO, GUARD, KINEMATICS, _MAT, _MAT, _VEC, _MAT, nt.float64,
                 nt.float64, nt.float64, nt.float64, nt.float64, nt.int64, _MAT, _VEC, _VEC,
                 _VEC, _VEC, nt.int64, nt.int64, _MAT, _MAT, _VEC, _MAT, _I64, _VEC, _I64,
                 _MAT), cache=True)
def _kernel(f, guard, kin, Y0, P, t_out, levels, window, dt, rtol, atol, h_max, max_steps,
            A, B, C, E, E3, err_order, dense, Pd, AX, CX, D, code, t_fail, regime, stats):
    """A plain loop over points (dt > 0: the fixed-step driver, else the adaptive one): the
    map's process pool runs one kernel per core; a prange kernel in one worker was slower."""
    t_window = window * t_out[t_out.shape[0] - 1]
    for i in range(Y0.shape[0]):
        if dt > 0.0:
            Y, _, _, tf, c = integrate_fixed_dense(f, guard, Y0[i], P[i], t_out, dt, A, B, C)
        else:
            Y, _, _, _, tf, c = integrate_adaptive_dense(
                f, guard, Y0[i], P[i], t_out, rtol, atol, h_max, max_steps, A, B, C, E, E3,
                err_order, dense, Pd, AX, CX, D)
        code[i], t_fail[i] = c, tf
        regime[i] = _reduce(Y, P[i], t_out, kin, levels[i, 0], levels[i, 1], t_window,
                            stats[i])


def regimes(rhs_into, guard, kinematics, initial_state, params_list, t_out, settings,
            channel, levels, window):
    """Run every point of `params_list` on the grid `t_out` in one compiled call; the regime
    is read off `channel` (only |ω|, "omega_norm": else None). `levels`: (n, 2) per point
    (reach, stay above), `window`: the fraction of the run after which |ω| must stay above.
    Returns {"code", "t_fail", "regime", "finite", "drift", "max_abs": {channel: (n,)}}
    (code ≠ 0: the run failed)."""
    if channel != "omega_norm":
        return None
    s = check_settings(settings, t_out)
    t_out = np.ascontiguousarray(t_out, float)
    P = np.stack([pack(p) for p in params_list])
    Y0 = np.stack([initial_state(p, pk) for p, pk in zip(params_list, P)])
    n = len(params_list)
    code, regime = np.zeros(n, np.int64), np.zeros(n, np.int64)
    t_fail, stats = np.full(n, np.nan), np.zeros((n, 2 + len(ENERGY_CHANNELS)))
    fixed = s["integrator"] in FIXED_TABLEAUS
    # one signature for both drivers: a fixed-step method leaves the adaptive slots unused
    tb = {**DENSE_TABLEAUS["dop853"], **(FIXED_TABLEAUS[s["integrator"]] if fixed
                                         else DENSE_TABLEAUS[s["integrator"]])}
    rtol = float(s["rtol"])
    _kernel(first_class(rhs_into, RHS_INTO), first_class(guard, GUARD),
            first_class(kinematics, KINEMATICS), Y0, P, t_out,
            np.ascontiguousarray(levels, float), float(window),
            float(s["dt"] or 1e-3) if fixed else 0.0, rtol, float(s["atol"] or rtol * 1e-2),
            float(s["h_max"] or 0.0), int(s["max_steps"]), tb["A"], tb["B"], tb["C"],
            tb["E"], tb["E3"], tb["err_order"], tb["dense"], tb["P"], tb["AX"], tb["CX"],
            tb["D"], code, t_fail, regime, stats)
    return {"code": code, "t_fail": t_fail, "regime": regime, "finite": stats[:, 0] > 0,
            "drift": stats[:, 1],
            "max_abs": {c: stats[:, 2 + k] for k, c in enumerate(ENERGY_CHANNELS)}}
