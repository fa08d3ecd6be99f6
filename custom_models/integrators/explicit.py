"""Explicit Runge–Kutta methods as coefficient tables, and the pieces every driver shares.

The tables (`FIXED_TABLEAUS`, `ADAPTIVE_TABLEAUS`: A, B, C, the embedded error weights E/E3)
feed the dense-output drivers of `dense` and the event stepping of `events`; so do the failure
codes, the guard type `GUARD` (`guard(t, y, p) -> int`: 0 while the state is valid, a
model-specific code ≥ 10 when the model's description breaks down), Hairer's initial-step
estimate and the error norm. (The drivers that landed a step on every output time lived here
until every model had moved to `dense`.)
"""
import numba as nb
import numpy as np
from numba import types as nt

from .tableaus import DOP853 as _DOP853
from .tableaus import RK23 as _RK23
from .tableaus import RK45 as _RK45

FAIL_OK, FAIL_NONFINITE, FAIL_STEP_UNDERFLOW, FAIL_MAX_STEPS = 0, 1, 2, 3
FAIL_REASONS = {FAIL_NONFINITE: "non-finite state",
                FAIL_STEP_UNDERFLOW: "step size underflow (stiff or singular)",
                FAIL_MAX_STEPS: "maximum number of steps exceeded"}


def _square(a, n):
    out = np.zeros((n, n))
    out[:a.shape[0], :a.shape[1]] = a
    return out


def _tableau(A, B, C, E=None, E3=None, order=0, err_order=0):
    n = len(B)
    vec = np.ascontiguousarray
    return {"A": _square(np.asarray(A, float), n), "B": vec(B, float), "C": vec(C[:n], float),
            "E": np.zeros(0) if E is None else vec(E, float),
            "E3": np.zeros(0) if E3 is None else vec(E3, float),
            "order": order, "err_order": err_order}


# Fixed-step methods (order p is what the convergence check expects).
FIXED_TABLEAUS = {
    "euler": _tableau([[0.0]], [1.0], [0.0], order=1),
    "midpoint": _tableau([[0, 0], [0.5, 0]], [0, 1.0], [0, 0.5], order=2),
    "rk4": _tableau([[0, 0, 0, 0], [0.5, 0, 0, 0], [0, 0.5, 0, 0], [0, 0, 1, 0]],
                    [1 / 6, 1 / 3, 1 / 3, 1 / 6], [0, 0.5, 0.5, 1.0], order=4),
}

# Embedded pairs, coefficients from scipy's public solver classes (the tables solve_ivp uses).
ADAPTIVE_TABLEAUS = {
    "rk23": _tableau(_RK23.A, _RK23.B, _RK23.C, E=_RK23.E, order=3, err_order=2),
    "dopri5": _tableau(_RK45.A, _RK45.B, _RK45.C, E=_RK45.E, order=5, err_order=4),
    "dop853": _tableau(_DOP853.A, _DOP853.B, _DOP853.C, E=_DOP853.E5, E3=_DOP853.E3, order=8,
                       err_order=7),
}


_VEC, _MAT = nt.float64[::1], nt.float64[:, ::1]       # C-contiguous: models reshape slices
GUARD = nt.FunctionType(nt.int64(nt.float64, _VEC, _VEC))    # guard(t, y, p) -> code


@nb.njit(cache=True)
def no_guard(t, y, p):
    return 0


@nb.njit(cache=True)
def initial_step(y, fy, rtol, atol):
    """First step from the scale of y and f (Hairer's simple estimate)."""
    ny = y.shape[0]
    d0 = 0.0
    d1 = 0.0
    for j in range(ny):
        sc = atol + abs(y[j]) * rtol
        d0 += (y[j] / sc) ** 2
        d1 += (fy[j] / sc) ** 2
    d0 = np.sqrt(d0 / ny)
    d1 = np.sqrt(d1 / ny)
    return 1e-6 if (d0 < 1e-5 or d1 < 1e-5) else 0.01 * d0 / d1


@nb.njit(cache=True)
def _weighted_rows(c, K, out):
    """out = Σ_s c[s] K[s], zero weights skipped, the inner loop along a row (vectorises)."""
    for j in range(out.shape[0]):
        out[j] = 0.0
    for s in range(c.shape[0]):
        a = c[s]
        if a != 0.0:
            for j in range(out.shape[0]):
                out[j] += a * K[s, j]


@nb.njit(cache=True)
def _error_norm(K, h, scale, E, E3, w5, w3):
    """The embedded error of a step; w5, w3: scratch rows of len(scale)."""
    ny = scale.shape[0]
    _weighted_rows(E, K, w5)
    e5 = 0.0
    for j in range(ny):
        e5 += (w5[j] / scale[j]) ** 2
    e3 = 0.0
    if E3.shape[0] > 0:
        _weighted_rows(E3, K, w3)
        for j in range(ny):
            e3 += (w3[j] / scale[j]) ** 2
    if E3.shape[0] == 0:           # ordinary embedded pair: RMS norm
        return abs(h) * np.sqrt(e5 / ny)
    if e5 == 0.0 and e3 == 0.0:    # DOP853's 5th/3rd-order blend (Hairer & Wanner)
        return 0.0
    return abs(h) * e5 / np.sqrt((e5 + 0.01 * e3) * ny)
