"""Runge–Kutta drivers with dense output: the step is set by the tolerance (or `dt`) alone.

Drivers that land a step on every output time can never take an adaptive step longer than the
output interval (the rotor's DOP853 took 1004 steps at rtol 1e-5, 1e-7 and 1e-9 alike, before
every model moved here). Here the step runs free and the output grid is filled by each method's
continuous extension, evaluated only for the outputs inside an accepted step:

- DOP853: the 7th-order extension of Hairer, Nørsett & Wanner (three extra stages, computed only
  for a step that contains an output; scipy's public `DOP853.A_EXTRA`, `C_EXTRA`, `D`);
- Dopri5 / RK23: the 4th- / 3rd-order interpolants of scipy's public `RK45.P`, `RK23.P`;
- fixed-step methods: cubic Hermite through (y, f) at both ends of the step (f at the step's end
  is the next step's first stage, so it costs no extra evaluation). Where the step divides the
  output interval, the outputs are the step ends themselves, bit for bit.

The guard is checked on every accepted step (at its end), before the outputs inside the step
are written: after a failure every later row stays NaN and the failure time is the step's end.

The right-hand side writes into a given array: `f(t, y, p, dy)` (type `RHS_INTO`), so one
evaluation allocates nothing. The drivers are compiled once for first-class function types
(fixed signatures, called through a pointer), which numba caches on disk: one compiled driver
serves every model, where a specialisation per model would compile again in every process.
`solve` runs a method by name with the settings every leaf shares (dt or rtol/atol/h_max).
"""
import functools
import time

import numba as nb
import numpy as np
from numba import types as nt
from numba.experimental.function_type import _get_wrapper_address

from .explicit import (
    _MAT,
    _VEC,
    ADAPTIVE_TABLEAUS,
    FAIL_MAX_STEPS,
    FAIL_NONFINITE,
    FAIL_OK,
    FAIL_STEP_UNDERFLOW,
    FIXED_TABLEAUS,
    GUARD,
    _error_norm,
    _weighted_rows,
    initial_step,
)
from .tableaus import DOP853 as _DOP853
from .tableaus import RK23 as _RK23
from .tableaus import RK45 as _RK45

RHS_INTO = nt.FunctionType(nt.void(nt.float64, _VEC, _VEC, _VEC))    # f(t, y, p, dy)

DENSE_POLY, DENSE_DOP853 = 1, 2


class FirstClass:
    """A jitted function as a first-class function value of type `ftype` (numba's wrapper
    address protocol: `_numba_type_`, `signature`, `__wrapper_address__`), its machine address
    looked up once. Passed as a plain dispatcher, numba types it and looks the address up again
    on every call of a driver: 80–150 µs per function argument, more than a short run's whole
    integration. The address is numba's own for that argument (`_get_wrapper_address`), taken
    on first use, so building one costs nothing at import."""

    def __init__(self, fn, ftype):
        self._fn, self._numba_type_, self._addr = fn, ftype, None

    def signature(self):
        return self._numba_type_.signature

    def __wrapper_address__(self):
        if self._addr is None:
            self._addr = _get_wrapper_address(self._fn, self.signature())
        return self._addr


@functools.cache
def first_class(fn, ftype) -> FirstClass:
    """The one `FirstClass` value of a jitted function for type `ftype`."""
    return FirstClass(fn, ftype)
_NONE, _NONE_1D = np.zeros((0, 0)), np.zeros(0)


def _dense(kind, P=_NONE, AX=_NONE, CX=_NONE_1D, D=_NONE):
    c = np.ascontiguousarray
    return {"dense": kind, "P": c(P, float), "AX": c(AX, float), "CX": c(CX, float),
            "D": c(D, float)}


# The adaptive tableaus of `explicit` with their continuous extensions.
DENSE_TABLEAUS = {
    "rk23": {**ADAPTIVE_TABLEAUS["rk23"], **_dense(DENSE_POLY, P=_RK23.P)},
    "dopri5": {**ADAPTIVE_TABLEAUS["dopri5"], **_dense(DENSE_POLY, P=_RK45.P)},
    "dop853": {**ADAPTIVE_TABLEAUS["dop853"],
               **_dense(DENSE_DOP853, AX=_DOP853.A_EXTRA, CX=_DOP853.C_EXTRA, D=_DOP853.D)},
}
FIXED = FIXED_TABLEAUS


@nb.njit(cache=True)
def _stage_state(y, h, A, K, s, ys):
    """ys = y + h Σ_r<s A[s, r] K[r]."""
    _weighted_rows(A[s, :s], K, ys)
    for j in range(y.shape[0]):
        ys[j] = y[j] + h * ys[j]


@nb.njit(cache=True)
def _combine(y, h, B, K, out):
    """out = y + h Σ_s B[s] K[s]."""
    _weighted_rows(B, K, out)
    for j in range(y.shape[0]):
        out[j] = y[j] + h * out[j]


@nb.njit(cache=True)
def _finite(y):
    """All entries finite (a scalar loop: np.isfinite would allocate every step)."""
    acc = 0.0
    for j in range(y.shape[0]):
        acc += y[j] * 0.0          # NaN for a NaN or ±inf entry, else 0
    return acc == 0.0


@nb.njit(cache=True)
def _hermite(y0, f0, y1, f1, h, x, out):
    x2 = x * x
    x3 = x2 * x
    a0, a1 = 2 * x3 - 3 * x2 + 1.0, -2 * x3 + 3 * x2
    b0, b1 = (x3 - 2 * x2 + x) * h, (x3 - x2) * h
    for j in range(y0.shape[0]):
        out[j] = a0 * y0[j] + b0 * f0[j] + a1 * y1[j] + b1 * f1[j]


@nb.njit(nt.Tuple((_MAT, nt.int64, nt.int64, nt.float64, nt.int64))(
    RHS_INTO, GUARD, _VEC, _VEC, _VEC, nt.float64, _MAT, _VEC, _VEC), cache=True)
def integrate_fixed_dense(f, guard, y0, p, t_out, dt, A, B, C):
    """Fixed step h = (t_end − t0)/N, N = ⌈(t_end − t0)/dt⌉ (h = dt when dt divides the span);
    outputs by cubic Hermite inside a step. Returns (Y, steps, rhs_evals, t_fail, code)."""
    n_out, ny, n_st = t_out.shape[0], y0.shape[0], B.shape[0]
    Y = np.full((n_out, ny), np.nan)
    K = np.empty((n_st, ny))
    ys = np.empty(ny)
    y = y0.copy()
    y_new = np.empty(ny)
    f_new = np.empty(ny)
    t0, t_end = t_out[0], t_out[n_out - 1]
    n_steps = max(1, int(np.ceil((t_end - t0) / dt - 1e-9)))
    h = (t_end - t0) / n_steps
    Y[0] = y
    f(t0, y, p, K[0])
    evals = 1
    i_out = 1
    for k in range(n_steps):
        t = t0 + k * h
        t_new = t_end if k == n_steps - 1 else t0 + (k + 1) * h
        for s in range(1, n_st):
            _stage_state(y, h, A, K, s, ys)
            f(t + C[s] * h, ys, p, K[s])
        _combine(y, h, B, K, y_new)
        if not _finite(y_new):
            return Y, k + 1, evals + n_st - 1, t_new, FAIL_NONFINITE
        code = guard(t_new, y_new, p)
        if code != 0:
            return Y, k + 1, evals + n_st - 1, t_new, code
        f(t_new, y_new, p, f_new)
        evals += n_st
        while i_out < n_out and t_out[i_out] <= t_new + 1e-12 * abs(t_new):
            if t_out[i_out] >= t_new - 1e-12 * abs(t_new):
                Y[i_out] = y_new
            else:
                _hermite(y, K[0], y_new, f_new, h, (t_out[i_out] - t) / h, Y[i_out])
            i_out += 1
        y[:] = y_new
        K[0] = f_new
    return Y, n_steps, evals, np.nan, FAIL_OK


@nb.njit(cache=True)
def _prepare_dense(f, p, t, y, y_new, h, K, n_st, A, dense, P, AX, CX, D, F, ys):
    """Coefficients F of the step's interpolant; returns the extra evaluations it took."""
    ny = y.shape[0]
    if dense == DENSE_POLY:          # F[k] = Σ_s P[s, k] K[s]  (y = y0 + h Σ_k F[k] x^(k+1))
        for k in range(P.shape[1]):
            _weighted_rows(P[:, k], K, F[k])
        return 0
    n_k = n_st + 1                   # DOP853: three extra stages, then scipy's F rows
    for e in range(AX.shape[0]):
        s = n_k + e
        _weighted_rows(AX[e, :s], K, ys)
        for j in range(ny):
            ys[j] = y[j] + h * ys[j]
        f(t + CX[e] * h, ys, p, K[s])
    for j in range(ny):
        dy = y_new[j] - y[j]
        F[0, j] = dy
        F[1, j] = h * K[0, j] - dy
        F[2, j] = 2.0 * dy - h * (K[n_st, j] + K[0, j])
    for r in range(D.shape[0]):
        _weighted_rows(D[r], K, F[3 + r])
        for j in range(ny):
            F[3 + r, j] *= h
    return AX.shape[0]


@nb.njit(cache=True)
def _eval_dense(y, h, x, dense, F, n_f, out):
    ny = y.shape[0]
    if dense == DENSE_POLY:
        for j in range(ny):
            acc = 0.0
            for k in range(n_f - 1, -1, -1):     # Horner in x
                acc = (acc + F[k, j]) * x
            out[j] = y[j] + h * acc
        return
    # scipy's Dop853DenseOutput, the states in the inner loop (the same operations per state)
    for j in range(ny):
        out[j] = 0.0
    for i in range(n_f):
        m = x if i % 2 == 0 else 1.0 - x
        for j in range(ny):
            out[j] = (out[j] + F[n_f - 1 - i, j]) * m
    for j in range(ny):
        out[j] = y[j] + out[j]


@nb.njit(nt.Tuple((_MAT, nt.int64, nt.int64, nt.int64, nt.float64, nt.int64))(
    RHS_INTO, GUARD, _VEC, _VEC, _VEC, nt.float64, nt.float64, nt.float64, nt.int64,
    _MAT, _VEC, _VEC, _VEC, _VEC, nt.int64, nt.int64, _MAT, _MAT, _VEC, _MAT), cache=True)
def integrate_adaptive_dense(f, guard, y0, p, t_out, rtol, atol, h_max, max_steps,
                             A, B, C, E, E3, err_order, dense, P, AX, CX, D):
    """Error-controlled embedded RK (FSAL) with dense output; `h_max` ≤ 0 means no cap.

    Returns (Y, steps, rhs_evals, rejected, t_fail, code)."""
    n_out, ny, n_st = t_out.shape[0], y0.shape[0], B.shape[0]
    Y = np.full((n_out, ny), np.nan)
    K = np.empty((n_st + 1 + AX.shape[0], ny))
    n_f = P.shape[1] if dense == DENSE_POLY else 3 + D.shape[0]
    F = np.empty((n_f, ny))
    ys = np.empty(ny)
    y = y0.copy()
    y_new = np.empty(ny)
    scale = np.empty(ny)
    w5, w3 = np.empty(ny), np.empty(ny)
    t0, t_end = t_out[0], t_out[n_out - 1]
    if h_max <= 0.0:
        h_max = np.inf
    Y[0] = y
    t = t0
    f(t, y, p, K[0])
    fy = K[0].copy()
    evals = 1
    steps = 0
    rejected = 0
    expo = -1.0 / (err_order + 1)
    h = min(initial_step(y, fy, rtol, atol), h_max)
    i_out = 1
    just_rejected = False
    while i_out < n_out:
        if steps + rejected >= max_steps:
            return Y, steps, evals, rejected, t, FAIL_MAX_STEPS
        last = t + h >= t_end - 1e-12 * abs(t_end)
        h_try = t_end - t if last else h
        if h_try < 10.0 * np.abs(np.nextafter(t, np.inf) - t):
            return Y, steps, evals, rejected, t, FAIL_STEP_UNDERFLOW
        K[0] = fy
        for s in range(1, n_st):
            _stage_state(y, h_try, A, K, s, ys)
            f(t + C[s] * h_try, ys, p, K[s])
        _combine(y, h_try, B, K, y_new)
        f(t + h_try, y_new, p, K[n_st])
        evals += n_st
        for j in range(ny):
            scale[j] = atol + max(abs(y[j]), abs(y_new[j])) * rtol
        err = _error_norm(K, h_try, scale, E, E3, w5, w3)
        if not np.isfinite(err):
            err = 1e10           # a NaN trial step: retry smaller, fail by underflow
        if err >= 1.0:
            rejected += 1
            just_rejected = True
            h = h_try * max(0.2, 0.9 * err ** expo)
            continue
        t_new = t_end if last else t + h_try
        steps += 1
        code = guard(t_new, y_new, p)
        if code != 0:
            return Y, steps, evals, rejected, t_new, code
        if t_out[i_out] < t_new - 1e-12 * abs(t_new):      # an output inside the step
            evals += _prepare_dense(f, p, t, y, y_new, h_try, K, n_st, A, dense, P, AX, CX, D,
                                    F, ys)
        while i_out < n_out and t_out[i_out] <= t_new + 1e-12 * abs(t_new):
            if t_out[i_out] >= t_new - 1e-12 * abs(t_new):
                Y[i_out] = y_new
            else:
                _eval_dense(y, h_try, (t_out[i_out] - t) / h_try, dense, F, n_f, Y[i_out])
            i_out += 1
        t = t_new
        y[:] = y_new
        fy[:] = K[n_st]
        fac = 10.0 if err == 0.0 else min(10.0, 0.9 * err ** expo)
        if just_rejected:        # no growth right after a rejection (as scipy and Hairer do)
            fac = min(1.0, fac)
            just_rejected = False
        # a clipped last step says little about the next one: keep h unless it grew
        h = min(h_max, max(h, h_try * fac) if last else h_try * fac)
    return Y, steps, evals, rejected, np.nan, FAIL_OK


def solve(f, guard, y0: np.ndarray, p: np.ndarray, t_out: np.ndarray, integrator: str, *,
          dt: float | None = None, rtol: float = 1e-10, atol: float | None = None,
          h_max: float | None = None, max_steps: int = 10**8):
    """One run of a named method (`DENSE_TABLEAUS`: error-controlled, `FIXED`: step `dt`) on
    `f(t, y, p, dy)`: (Y, stats, t_fail, code, settings used). atol defaults to rtol/100; no
    cap on the adaptive step unless h_max > 0. stats: steps, rhs_evals (rejected), and
    integrate_s, the wall time of the compiled driver alone."""
    t_out = np.ascontiguousarray(t_out, float)
    f, guard = first_class(f, RHS_INTO), first_class(guard, GUARD)
    if integrator in FIXED:
        tb = FIXED[integrator]
        t0 = time.perf_counter()
        Y, steps, evals, t_fail, code = integrate_fixed_dense(f, guard, y0, p, t_out, float(dt),
                                                              tb["A"], tb["B"], tb["C"])
        stats = {"steps": int(steps), "rhs_evals": int(evals),
                 "integrate_s": time.perf_counter() - t0}
        span = t_out[-1] - t_out[0]
        used = {"integrator": integrator,
                "dt": float(span / steps if code == 0 and span > 0 else dt)}
        return Y, stats, t_fail, int(code), used
    tb = DENSE_TABLEAUS[integrator]
    rtol = float(rtol)
    atol = float(atol or rtol * 1e-2)
    h_max = float(h_max or 0.0)
    t0 = time.perf_counter()
    Y, steps, evals, rej, t_fail, code = integrate_adaptive_dense(
        f, guard, y0, p, t_out, rtol, atol, h_max, int(max_steps), tb["A"], tb["B"], tb["C"],
        tb["E"], tb["E3"], tb["err_order"], tb["dense"], tb["P"], tb["AX"], tb["CX"], tb["D"])
    stats = {"steps": int(steps), "rhs_evals": int(evals), "rejected": int(rej),
             "integrate_s": time.perf_counter() - t0}
    used = {"integrator": integrator, "rtol": rtol, "atol": atol,
            **({"h_max": h_max} if h_max > 0 else {})}
    return Y, stats, t_fail, int(code), used
