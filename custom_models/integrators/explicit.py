"""Explicit Runge–Kutta integrators as coefficient tables, compiled with numba.

Both drivers take a jitted right-hand side `f(t, y, p) -> dy` (p: float64 parameter array) and a
jitted `guard(t, y, p) -> int` that returns 0 while the state is valid and a model-specific code
(>= 10) when the model's description breaks down. They return the solution on the output grid;
after a failure the remaining rows are NaN and the failure time and code are returned, so a
diverged run can never look like a finite result.

Steps always land on the output times (the adaptive driver shortens a step to hit the next output
instead of interpolating), so outputs carry the integrator's own accuracy.

Why function arguments: one compiled driver serves every model. The drivers are compiled for
first-class function types (`RHS`, `GUARD`: fixed signatures, called through a pointer), which
numba caches on disk like any other type — a specialisation on a particular jitted function
would not be cached, and every process paid ~8 s to compile it again.
"""
import numba as nb
import numpy as np
from numba import types as nt
from scipy.integrate import DOP853 as _DOP853
from scipy.integrate import RK23 as _RK23
from scipy.integrate import RK45 as _RK45

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
RHS = nt.FunctionType(_VEC(nt.float64, _VEC, _VEC))          # f(t, y, p) -> dy
GUARD = nt.FunctionType(nt.int64(nt.float64, _VEC, _VEC))    # guard(t, y, p) -> code


@nb.njit(cache=True)
def no_guard(t, y, p):
    return 0


@nb.njit(cache=True)
def _stages(f, t, y, p, h, A, C, K):
    """Fill K[0..s-1] with the stage derivatives (K[0] must hold f(t, y) already)."""
    n_st = A.shape[0]
    ny = y.shape[0]
    ys = np.empty(ny)
    for s in range(1, n_st):
        for j in range(ny):
            acc = 0.0
            for r in range(s):
                acc += A[s, r] * K[r, j]
            ys[j] = y[j] + h * acc
        K[s] = f(t + C[s] * h, ys, p)


@nb.njit(nt.Tuple((_MAT, nt.int64, nt.int64, nt.float64, nt.int64))(
    RHS, GUARD, _VEC, _VEC, _VEC, nt.int64, _MAT, _VEC, _VEC), cache=True)
def integrate_fixed(f, guard, y0, p, t_out, substeps, A, B, C):
    """Fixed step h = (t_out[i+1] - t_out[i]) / substeps.

    Returns (Y, steps, rhs_evals, t_fail, code)."""
    n_out, ny, n_st = t_out.shape[0], y0.shape[0], B.shape[0]
    Y = np.full((n_out, ny), np.nan)
    K = np.empty((n_st, ny))
    y = y0.copy()
    Y[0] = y
    steps = 0
    evals = 0
    for i in range(n_out - 1):
        h = (t_out[i + 1] - t_out[i]) / substeps
        for k in range(substeps):
            t = t_out[i] + k * h
            K[0] = f(t, y, p)
            _stages(f, t, y, p, h, A, C, K)
            evals += n_st
            for j in range(ny):
                acc = 0.0
                for s in range(n_st):
                    acc += B[s] * K[s, j]
                y[j] += h * acc
            steps += 1
            if not np.all(np.isfinite(y)):
                return Y, steps, evals, t + h, FAIL_NONFINITE
            code = guard(t + h, y, p)
            if code != 0:
                return Y, steps, evals, t + h, code
        Y[i + 1] = y
    return Y, steps, evals, np.nan, FAIL_OK


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
def _error_norm(K, h, scale, E, E3):
    ny = scale.shape[0]
    e5 = 0.0
    e3 = 0.0
    for j in range(ny):
        a = 0.0
        for s in range(E.shape[0]):
            a += E[s] * K[s, j]
        e5 += (a / scale[j]) ** 2
        if E3.shape[0] > 0:
            b = 0.0
            for s in range(E3.shape[0]):
                b += E3[s] * K[s, j]
            e3 += (b / scale[j]) ** 2
    if E3.shape[0] == 0:           # ordinary embedded pair: RMS norm
        return abs(h) * np.sqrt(e5 / ny)
    if e5 == 0.0 and e3 == 0.0:    # DOP853's 5th/3rd-order blend (Hairer & Wanner)
        return 0.0
    return abs(h) * e5 / np.sqrt((e5 + 0.01 * e3) * ny)


@nb.njit(nt.Tuple((_MAT, nt.int64, nt.int64, nt.int64, nt.float64, nt.int64))(
    RHS, GUARD, _VEC, _VEC, _VEC, nt.float64, nt.float64, nt.float64, nt.int64,
    _MAT, _VEC, _VEC, _VEC, _VEC, nt.int64), cache=True)
def integrate_adaptive(f, guard, y0, p, t_out, rtol, atol, h_max, max_steps,
                       A, B, C, E, E3, err_order):
    """Error-controlled embedded RK (FSAL), steps clipped to land on every output time.

    Returns (Y, steps, rhs_evals, rejected, t_fail, code)."""
    n_out, ny, n_st = t_out.shape[0], y0.shape[0], B.shape[0]
    Y = np.full((n_out, ny), np.nan)
    K = np.empty((n_st + 1, ny))
    y = y0.copy()
    Y[0] = y
    t = t_out[0]
    fy = f(t, y, p)
    evals = 1
    steps = 0
    rejected = 0
    expo = -1.0 / (err_order + 1)
    h = min(initial_step(y, fy, rtol, atol), h_max)
    y_new = np.empty(ny)
    scale = np.empty(ny)
    for i in range(n_out - 1):
        t_next = t_out[i + 1]
        while t < t_next:
            if steps + rejected >= max_steps:
                return Y, steps, evals, rejected, t, FAIL_MAX_STEPS
            last = False
            if t + h >= t_next - 1e-12 * abs(t_next):
                h_try = t_next - t
                last = True
            else:
                h_try = h
            if h_try < 10.0 * np.abs(np.nextafter(t, np.inf) - t):
                return Y, steps, evals, rejected, t, FAIL_STEP_UNDERFLOW
            K[0] = fy
            _stages(f, t, y, p, h_try, A, C, K)
            for j in range(ny):
                acc = 0.0
                for s in range(n_st):
                    acc += B[s] * K[s, j]
                y_new[j] = y[j] + h_try * acc
            f_new = f(t + h_try, y_new, p)
            K[n_st] = f_new
            evals += n_st
            for j in range(ny):
                scale[j] = atol + max(abs(y[j]), abs(y_new[j])) * rtol
            err = _error_norm(K, h_try, scale, E, E3)
            if not np.isfinite(err):
                err = 1e10           # a NaN trial step: retry smaller, fail by underflow
            if err < 1.0:
                fac = 10.0 if err == 0.0 else min(10.0, 0.9 * err ** expo)
                t = t_next if last else t + h_try
                y[:] = y_new
                fy = f_new
                steps += 1
                code = guard(t, y, p)
                if code != 0:
                    return Y, steps, evals, rejected, t, code
                # a clipped last step says little about the next one: keep h unless it grew
                h = min(h_max, max(h, h_try * fac) if last else h_try * fac)
            else:
                rejected += 1
                h = h_try * max(0.2, 0.9 * err ** expo)
        Y[i + 1] = y
    return Y, steps, evals, rejected, np.nan, FAIL_OK
