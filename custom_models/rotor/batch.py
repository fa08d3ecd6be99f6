"""Many rotor runs in one compiled call, each reduced to its regime where it ran: the map's
batch path (`regimes`, offered by both formulations).

Every point runs the shared integrator core of `integrators.dense` on the formulation's own
right-hand side and guard — the same compiled calls `simulate` makes — on the same output grid;
nothing per point returns to Python. With DOP853 (the map's cheap and accurate levels) the
points run 8 at a time on the SIMD lanes (`integrators.lanes`, the formulation's `rhs_lanes` and
`row_lanes`), each lane bit for bit the scalar driver: about twice the points a second (a
batch of `LANES_FROM` points or more).

Each formulation writes its own four short wrappers over its inline cores (`rhs_into`,
`rhs_lanes`, `kinematics`, `row_lanes`), alike in both files: numba takes no function as a
compile-time argument, and wrappers made by a factory are closures, which missed numba's disk
cache in every new process (measured: a second process compiled and saved a second entry).

From each run's rows it keeps what the map's decision needs: the integrator's code, the regime
(the scene's speed levels on |ω|) and the energy numbers of the adapter's divergence rule
(largest drift of the energy balance from its first value, largest |value| of each energy
channel), so that the caller applies that rule as `simulate` does. The per-row channels are
`physics.rotor.channels` in scalar form.
"""
import numba as nb
import numpy as np
from numba import types as nt

from compare.physics.rotation import mat_tvec_t, mat_vec_t
from compare.physics.trig import atan2

from ..integrators import FIXED_TABLEAUS
from ..integrators.dense import (
    DENSE_TABLEAUS,
    RHS_INTO,
    first_class,
    integrate_adaptive_dense,
    integrate_fixed_dense,
)
from ..integrators.explicit import _MAT, _VEC, GUARD
from ..integrators.lanes import LANES, RHS_LANES, ROW_LANES, integrate_dop853_lanes, nine
from .model import I0, I0INV, K_, M_, RC0, G, check_settings, pack_many

# kinematics(Y, p, O): each row of O = rotation body → fixed (9, row-major), fixed-frame ω (3),
# work of that row of Y — one call per run, not one call through a pointer per row
KINEMATICS = nt.FunctionType(nt.void(_MAT, _VEC, _MAT))
ENERGY_CHANNELS = ("energy_balance", "kinetic", "potential", "work")
# a run's accumulators: the first row with |ω| ≥ reach (−1: none), the least |ω| from the window
# on, the energy balance at row 0, finite (1/0), max |E − E(0)|, then max |value| of each of
# ENERGY_CHANNELS
_FIRST, _WMIN, _E0, _FINITE = 0, 1, 2, 3
ACC0 = np.array([-1.0, np.inf, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0])
N_PACK = I0INV.stop                 # the packed parameters' length: lane rows go on with levels
# the lanes' workspace (integrators.lanes): state and derivative (8 rows each), the point's
# packed parameters with reach, stay and the window's start, ACC0, an output row's time,
# index and mask, then the row's motion (13) and channels (3) as scratch
NY, L = 8, LANES
Z_DY, Z_P = NY * L, 2 * NY * L
Z_ACC = Z_P + (N_PACK + 3) * L
Z_T = Z_ACC + len(ACC0) * L        # the row's time, index, mask
Z_J, Z_M = Z_T + L, Z_T + 2 * L
Z_O = Z_T + 3 * L
Z_CH = Z_O + 13 * L                 # the row's |ω|, kinetic and potential energy
N_SCRATCH = 16
_I0, _RC0, _G = I0.start, RC0.start, G.start
_I64 = nt.int64[::1]


@nb.njit(cache=True, inline="always")
def _channels(o, oo, ost, p, po, pst):
    """(|ω|, kinetic, potential) of one row (R, ω, work) as physics.rotor.channels; its entry k
    at o[oo + k·ost], the parameters' at p[po + k·pst] (strides 1, or LANES in a lane block)."""
    R = nine(o, oo, ost)
    w0, w1, w2 = o[oo + 9 * ost], o[oo + 10 * ost], o[oo + 11 * ost]
    b = mat_tvec_t(R, w0, w1, w2)                                   # body-frame ω
    I = nine(p, po + _I0 * pst, pst)
    kin = 0.5 * (b[0] * (I[0] * b[0] + I[1] * b[1] + I[2] * b[2])
                 + b[1] * (I[3] * b[0] + I[4] * b[1] + I[5] * b[2])
                 + b[2] * (I[6] * b[0] + I[7] * b[1] + I[8] * b[2]))
    # √ rather than hypot: hypot is a libm call with its own branches, which kept the loop over
    # lanes from vectorising (≤ 1 ulp apart; physics.rotor.tilt keeps hypot)
    tilt = atan2(np.sqrt(R[2] * R[2] + R[5] * R[5]), R[8])
    rc = mat_vec_t(R, p[po + _RC0 * pst], p[po + (_RC0 + 1) * pst], p[po + (_RC0 + 2) * pst])
    pot = 0.5 * p[po + K_ * pst] * tilt * tilt - p[po + M_ * pst] * (
        rc[0] * p[po + _G * pst] + rc[1] * p[po + (_G + 1) * pst]
        + rc[2] * p[po + (_G + 2) * pst])
    return np.sqrt(w0 * w0 + w1 * w1 + w2 * w2), kin, pot


@nb.njit(cache=True, inline="always")
def _keep_max(on, acc, i, v):
    acc[i] = max(acc[i], v) if on else acc[i]


@nb.njit(cache=True, inline="always")
def _accumulate(on, wn, ke, pe, work, j, t, reach, t_window, acc, a, st):
    """One row into a run's accumulators acc[a + k·st] (ACC0's layout) where `on`; written
    with selects, not branches, so that the loop over lanes vectorises."""
    e = ke + pe - work
    i = a + _E0 * st
    acc[i] = e if on & (j == 0) else acc[i]
    e0 = acc[i]
    i = a + _FINITE * st
    fin = np.isfinite(wn) & np.isfinite(e)
    acc[i] = acc[i] if fin or not on else 0.0
    _keep_max(on, acc, a + 4 * st, abs(e - e0))
    _keep_max(on, acc, a + 5 * st, abs(e))
    _keep_max(on, acc, a + 6 * st, abs(ke))
    _keep_max(on, acc, a + 7 * st, abs(pe))
    _keep_max(on, acc, a + 8 * st, abs(work))
    i = a + _FIRST * st
    acc[i] = j if on & (acc[i] < 0) & (wn >= reach) else acc[i]
    i = a + _WMIN * st
    acc[i] = min(acc[i], wn) if on & (t >= t_window) else acc[i]


@nb.njit(cache=True, error_model="numpy")
def _reduce(Y, p, t_out, kin, reach, t_window, acc):
    """A run's rows into its accumulators `acc` (from ACC0)."""
    O = np.empty((Y.shape[0], 13))
    kin(Y, p, O)
    for j in range(Y.shape[0]):
        wn, ke, pe = _channels(O[j], 0, 1, p, 0, 1)
        _accumulate(True, wn, ke, pe, O[j, 12], j, t_out[j], reach, t_window, acc, 0, 1)


@nb.njit(cache=True, error_model="numpy")
def reduce_lanes(Z):
    """`_reduce` for the row of each lane whose mask is 1, the row's motion already in the
    workspace's Z_O rows (the formulation's `row_lanes` forms it). Three loops over the lanes,
    each vectorised or not on its own: the motion's and the channels' (these two vectorise),
    then the accumulators' selects (unrolled, scalar; fused with either, neither vectorised)."""
    for lane in range(L):
        Z[Z_CH + lane], Z[Z_CH + L + lane], Z[Z_CH + 2 * L + lane] = _channels(
            Z, Z_O + lane, L, Z, Z_P + lane, L)
    for lane in range(L):
        _accumulate(Z[Z_M + lane] != 0.0, Z[Z_CH + lane], Z[Z_CH + L + lane],
                    Z[Z_CH + 2 * L + lane], Z[Z_O + 12 * L + lane], Z[Z_J + lane],
                    Z[Z_T + lane], Z[Z_P + N_PACK * L + lane], Z[Z_P + (N_PACK + 2) * L + lane],
                    Z, Z_ACC + lane, L)


@nb.njit(nt.void(RHS_INTO, GUARD, KINEMATICS, _MAT, _MAT, _VEC, _MAT, nt.float64,
                 nt.float64, nt.float64, nt.float64, nt.float64, nt.int64, _MAT, _VEC, _VEC,
                 _VEC, _VEC, nt.int64, nt.int64, _MAT, _MAT, _VEC, _MAT, _I64, _VEC, _MAT),
         cache=True)
def _kernel(f, guard, kin, Y0, P, t_out, levels, window, dt, rtol, atol, h_max, max_steps,
            A, B, C, E, E3, err_order, dense, Pd, AX, CX, D, code, t_fail, acc):
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
        _reduce(Y, P[i], t_out, kin, levels[i, 0], t_window, acc[i])


# a batch this small runs scalar: the lanes save ≲ 0.3 ms a point, and their first compile on a
# machine costs 15–19 s (numba caches it after) — the campaign's maps, 45-point coarse grids in
# ~11-point chunks, would pay it for nothing; a 10,000-point map's chunks are thousands
LANES_FROM = 64


def regimes(rhs_into, guard, kinematics, initial_state, params_list, t_out, settings,
            channel, levels, window, lanes=None, lanes_from=LANES_FROM):
    """Run every point of `params_list` on the grid `t_out` in one compiled call; the regime
    is read off `channel` (only |ω|, "omega_norm": else None). `levels`: (n, 2) per point
    (reach, stay above), `window`: the fraction of the run after which |ω| must stay above.
    `lanes`: the formulation's (rhs_lanes, row_lanes), with which DOP853 runs LANES points at
    once (`integrators.lanes`: bit for bit the scalar driver's numbers, ~2× the points a second)
    for a batch of at least `lanes_from` points.
    Returns {"code", "t_fail", "regime", "finite", "drift", "max_abs": {channel: (n,)}}
    (code ≠ 0: the run failed)."""
    if channel != "omega_norm":
        return None
    s = check_settings(settings, t_out)
    t_out = np.ascontiguousarray(t_out, float)
    P = pack_many(params_list)
    Y0 = np.stack([initial_state(p, pk) for p, pk in zip(params_list, P)])
    levels = np.ascontiguousarray(levels, float)
    n = len(params_list)
    code, t_fail = np.zeros(n, np.int64), np.full(n, np.nan)
    acc = np.tile(ACC0, (n, 1))
    fixed = s["integrator"] in FIXED_TABLEAUS
    # one signature for both drivers: a fixed-step method leaves the adaptive slots unused
    tb = {**DENSE_TABLEAUS["dop853"], **(FIXED_TABLEAUS[s["integrator"]] if fixed
                                         else DENSE_TABLEAUS[s["integrator"]])}
    rtol = float(s["rtol"])
    atol, h_max = float(s["atol"] or rtol * 1e-2), float(s["h_max"] or 0.0)
    t_window = float(window) * t_out[-1]
    if lanes and s["integrator"] == "dop853" and n >= lanes_from:
        rhs_lanes, row_lanes = lanes
        P_rows = np.hstack([P, levels, np.full((n, 1), t_window)])     # N_PACK: reach, stay, t₀
        integrate_dop853_lanes(
            first_class(rhs_lanes, RHS_LANES), first_class(guard, GUARD),
            first_class(row_lanes, ROW_LANES), Y0, P_rows, t_out, rtol, atol, h_max,
            int(s["max_steps"]), tb["A"], tb["B"], tb["C"], tb["E"], tb["E3"], tb["err_order"],
            tb["AX"], tb["CX"], tb["D"], ACC0, N_SCRATCH, code, t_fail, acc)
    else:
        _kernel(first_class(rhs_into, RHS_INTO), first_class(guard, GUARD),
                first_class(kinematics, KINEMATICS), Y0, P, t_out, levels, float(window),
                float(s["dt"] or 1e-3) if fixed else 0.0, rtol, atol, h_max,
                int(s["max_steps"]), tb["A"], tb["B"], tb["C"], tb["E"], tb["E3"],
                tb["err_order"], tb["dense"], tb["P"], tb["AX"], tb["CX"], tb["D"], code, t_fail,
                acc)
    # the regime (0: |ω| never reaches `reach` after t = 0, 2: it stays above `stay` from the
    # window on, else 1; reaching it at row 0 is "never", as first_crossing gives None there)
    regime = np.where(acc[:, _FIRST] <= 0, 0, np.where(acc[:, _WMIN] > levels[:, 1], 2, 1))
    return {"code": code, "t_fail": t_fail, "regime": regime, "finite": acc[:, _FINITE] > 0,
            "drift": acc[:, 4],
            "max_abs": {c: acc[:, 5 + k] for k, c in enumerate(ENERGY_CHANNELS)}}
