"""Fixed-step integration with a state event, for every custom model that needs one.

`integrate_segment` steps from (t0, y0) to t_stop with the explicit Runge–Kutta tableaus of
`explicit` (on an allocation-free right-hand side `f(t, y, p, dy)`, the stage loop of `dense`)
or the linear-acceleration step of `linear_acceleration` (no second copy of either),
fills the output rows it passes, and — when asked — stops at the first sign change of a jitted
event function g(t, y, p), located by bisection on the step length (re-stepping from the start
of the step, so the state at the event carries the integrator's own accuracy).

Working data are grouped: the method's coefficients in one tuple `tab` = (A, B, C) and its
scalar options in one float array `cfg` (indices below), instead of a long positional list.
"""
import numba as nb
import numpy as np
from numba import types as nt

from .dense import RHS_INTO, _combine, _finite, _stage_state
from .explicit import _MAT, _VEC, FAIL_NONFINITE, GUARD
from .linear_acceleration import ACC, la_step

# g(t, y, p) -> float: the event is a sign change of g over a step
EVENT_FN = nt.FunctionType(nt.float64(nt.float64, _VEC, _VEC))
TABLEAU = nt.Tuple((_MAT, _VEC, _VEC))

# cfg entries
(C_METHOD, C_THETA, C_LA_MODE, C_TOL, C_MAX_ITER, C_EVENT_ON, C_EVENT_TOL, C_NQ) = range(8)
CFG_LEN = 8
M_RK, M_LA = 0, 1           # method: explicit Runge–Kutta tableau, linear acceleration (Wilson)
EVENT = 50                  # return code: stopped at an event


def config(method: int, theta: float = 1.0, la_mode: int = 0, tol: float = 1e-10,
           max_iter: int = 30, event_on: bool = False, event_tol: float = 1e-10,
           n_q: int = 0) -> np.ndarray:
    """The cfg array of `integrate_segment` (n_q: number of coordinates q, for the
    linear-acceleration method's y = [q, q', z])."""
    cfg = np.zeros(CFG_LEN)
    cfg[C_METHOD], cfg[C_THETA], cfg[C_LA_MODE], cfg[C_TOL] = method, theta, la_mode, tol
    cfg[C_MAX_ITER], cfg[C_EVENT_ON], cfg[C_EVENT_TOL], cfg[C_NQ] = (max_iter, float(event_on),
                                                                       event_tol, n_q)
    return cfg


@nb.njit(cache=True)
def rk_step(f, t, y, p, h, A, B, C, K, ys, y1):
    """One explicit Runge–Kutta step of tableau (A, B, C) into y1 (K, ys: stage work arrays;
    the stage loop of `dense`, so one copy of it)."""
    f(t, y, p, K[0])
    for s in range(1, B.shape[0]):
        _stage_state(y, h, A, K, s, ys)
        f(t + C[s] * h, ys, p, K[s])
    _combine(y, h, B, K, y1)


@nb.njit(cache=True)
def _one_step(f, acc, t, y, qdd, zd, p, h, tab, cfg, K, ys, y1):
    """One step of the configured method from y = [q, q', z] (and, for linear acceleration,
    the carried q'', z') into y1. Returns (qdd1, zd1, evals, steps, code): steps > 1 where
    the linear-acceleration step was cut."""
    if cfg[C_METHOD] == M_RK:
        rk_step(f, t, y, p, h, tab[0], tab[1], tab[2], K, ys, y1)
        return qdd, zd, tab[1].shape[0], 1, 0
    n = int(cfg[C_NQ])
    q1, qd1, qdd1, z1, zd1, ev, taken, code = la_step(
        acc, t, y[:n], y[n:2 * n], qdd, y[2 * n:], zd, p, h, cfg[C_THETA], int(cfg[C_LA_MODE]),
        cfg[C_TOL], int(cfg[C_MAX_ITER]))
    y1[:n] = q1
    y1[n:2 * n] = qd1
    y1[2 * n:] = z1
    return qdd1, zd1, ev, taken, code


@nb.njit(nt.Tuple((nt.int64, nt.float64, _VEC, nt.int64, nt.int64, nt.int64))(
    RHS_INTO, ACC, GUARD, EVENT_FN, _VEC, _VEC, nt.float64, nt.float64, _VEC, nt.int64, _MAT,
    nt.float64, TABLEAU, _VEC), cache=True)
def integrate_segment(f, acc, guard, g, y0, p, t0, t_stop, t_out, i_next, Y, h_nom, tab, cfg):
    """Fixed-step integration from (t0, y0) to t_stop, filling Y at the output times in
    (t0, t_stop]; each interval between stops is split into equal steps ≤ h_nom, so a segment
    may start off the output grid (after an event). With cfg[C_EVENT_ON], stops at the first
    sign change of g(t, y, p), located by bisection on the step length to cfg[C_EVENT_TOL].
    `f(t, y, p, dy)` serves the Runge–Kutta method, `acc` the linear-acceleration one (the
    other is unused). Returns (code, t, y, i_next, steps, evals); code EVENT at an event, 0 at
    t_stop, else the failure code (non-finite state, the method's, or the guard's)."""
    n_out, ny = t_out.shape[0], y0.shape[0]
    t = t0
    y = y0.copy()
    y1 = np.empty(ny)
    ym = np.empty(ny)
    ys = np.empty(ny)
    K = np.empty((tab[1].shape[0], ny))
    steps = 0
    evals = 0
    n = int(cfg[C_NQ])
    qdd = np.zeros(n)
    zd = np.zeros(ny - 2 * n)
    if cfg[C_METHOD] != M_RK:
        r = acc(t, y[:n], y[n:2 * n], p)
        qdd = r[:n].copy()
        zd = r[n:].copy()
        evals += 1
    ev_on = cfg[C_EVENT_ON] != 0.0
    i = i_next
    while True:
        on_grid = i < n_out and t_out[i] <= t_stop + 1e-12 * max(1.0, abs(t_stop))
        tb = t_out[i] if on_grid else t_stop
        span = tb - t
        if span > 0.0:
            nsub = max(1, int(np.ceil(span / h_nom - 1e-9)))
            h = span / nsub
            ta = t
            for k in range(nsub):
                tk = ta + k * h
                qdd1, zd1, ev, taken, code = _one_step(f, acc, tk, y, qdd, zd, p, h, tab, cfg,
                                                       K, ys, y1)
                evals += ev
                steps += taken
                if code == 0 and not _finite(y1):
                    code = FAIL_NONFINITE
                if code == 0:
                    code = guard(tk + h, y1, p)
                if code != 0:
                    return code, tk + h, y, i, steps, evals
                if ev_on:
                    g0 = g(tk, y, p)
                    g1 = g(tk + h, y1, p)
                    if g0 != 0.0 and g0 * g1 <= 0.0:
                        lo, hi = 0.0, h
                        while hi - lo > cfg[C_EVENT_TOL]:
                            mid = 0.5 * (lo + hi)
                            _, _, ev, _, _ = _one_step(f, acc, tk, y, qdd, zd, p, mid, tab,
                                                       cfg, K, ys, ym)
                            evals += ev
                            if g(tk + mid, ym, p) * g0 > 0.0:
                                lo = mid
                            else:
                                hi = mid
                                y1[:] = ym
                        return EVENT, tk + hi, y1, i, steps, evals
                y[:] = y1
                qdd = qdd1
                zd = zd1
            t = tb
        if on_grid:
            Y[i] = y
            i += 1
            if abs(tb - t_stop) <= 1e-12 * max(1.0, abs(t_stop)):
                return 0, t_stop, y, i, steps, evals
        else:
            return 0, t_stop, y, i, steps, evals
