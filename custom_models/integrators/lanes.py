"""DOP853 with dense output over LANES points at once: the map's batch on the CPU's SIMD lanes.

`dense.integrate_adaptive_dense` runs one point; its right-hand side is scalar code, ~60–100 ns
an evaluation for the rotor, and a cheap map point is ~4800 of them. Here LANES points step side
by side, each with its own time, step size, error and acceptance, exactly as the scalar driver
steps it: every stage sum, error norm, step-size rule and dense evaluation is the scalar
driver's expression evaluated per lane, in its order, so each lane's numbers are bit for bit
the scalar driver's (tests/studies/test_map_batch.py). What the lanes share is the loop over them:
the stage sums, the right-hand side `f(T, Z)` and the per-row reduce `row(Z)` loop over the lanes
innermost, which LLVM vectorises (the rotor's quaternion right-hand side: 23–37 ns a lane
against 57–71 ns scalar, measured in the same process, twice; 19 ns once its atan2 was
`compare.physics.trig`'s rather than libm's).

A lane whose point is done (or failed) takes the next point at once, so no lane waits for the
slowest. Outputs: per point the failure code and time (as the scalar driver's) and the row
reduce's accumulators (kept in the workspace's accumulator rows; a point starts from `acc0`).
For a failed point the accumulators cover the rows before the failure only.

What it took to vectorise (each measured on the compiled code's instructions): one workspace
array, not one array per quantity (below); the model's helpers inlined at numba's level
(`inline="always"`: left to LLVM's inliner, they were inlined too late for the loop
vectoriser); the lane loops compiled in numpy's error model, which inlined code takes from its
caller (numba's division check raises, and a loop with a raise does not vectorise); rows
indexed in place (a row view per term costs a
reference-count call pair). Loops whose body is short are unrolled instead and stay scalar
(the row reduce's selects).
"""
import numba as nb
import numpy as np
from numba import types as nt

from .explicit import (
    _VEC,
    FAIL_MAX_STEPS,
    FAIL_OK,
    FAIL_STEP_UNDERFLOW,
    initial_step,
)

LANES = 8
N_F = 7                 # rows of DOP853's interpolant (dense._prepare_dense: 3 + D's 4)
# The lanes' workspace Z, flat [row · LANES + lane], rows in this order: the state y (ny rows),
# its derivative dy (ny), the point's parameters p (n_p), the row reduce's accumulators (n_a),
# an output row's time, index and mask (3: `row` reduces the lanes whose mask is 1), scratch
# (n_s). One array, not five: each access is then Z[constant + lane], which LLVM can
# prove free of overlap; between separate arrays it needs runtime alias checks and, for an
# 8-iteration loop, does not vectorise at all (measured: no vector instruction).
# f(T, Z): dy = f(y) on every lane, T the lanes' times
RHS_LANES = nt.FunctionType(nt.void(_VEC, _VEC))
# row(Z): one output row (in y) into the accumulators of each lane whose mask is 1
ROW_LANES = nt.FunctionType(nt.void(_VEC))


@nb.njit(cache=True, inline="always")
def nine(a, i, st):
    """a[i], a[i + st], …, a[i + 8·st]: a 3×3 block of one point's parameters, for st = 1 or
    LANES."""
    return (a[i], a[i + st], a[i + 2 * st], a[i + 3 * st], a[i + 4 * st], a[i + 5 * st],
            a[i + 6 * st], a[i + 7 * st], a[i + 8 * st])


@nb.njit(cache=True, error_model="numpy")
def _stage(y, h, A, K, s, ny, ys):
    """ys = y + h Σ_r<s A[s, r] K[r] per lane, as `dense._stage_state` sums it. K is indexed
    in place: a row view K[r] per term costs a reference count in and out (two calls)."""
    L = LANES
    for k in range(ny * L):
        ys[k] = 0.0
    for r in range(s):
        a = A[r]
        if a != 0.0:
            for k in range(ny * L):
                ys[k] += a * K[r, k]
    for j in range(ny):
        for lane in range(L):
            k = j * L + lane
            ys[k] = y[k] + h[lane] * ys[k]


@nb.njit(cache=True, error_model="numpy")
def _sum(c, K, n, out):
    """out = Σ_s<n c[s] K[s] (zero weights skipped), as `explicit._weighted_rows`."""
    m = K.shape[1]
    for k in range(m):
        out[k] = 0.0
    for s in range(n):
        a = c[s]
        if a != 0.0:
            for k in range(m):
                out[k] += a * K[s, k]


@nb.njit(cache=True, error_model="numpy")
def _call(f, T, y, Z, dy):
    """dy = f(y) on every lane, through the workspace."""
    n = y.shape[0]
    for k in range(n):              # loops: a slice assignment checks for overlap and copies
        Z[k] = y[k]
    f(T, Z)
    for k in range(n):
        dy[k] = Z[n + k]


@nb.njit(cache=True)
def _finish(lane, pt, c, tf, Z, z_acc, code, t_fail, acc):
    i = pt[lane]
    code[i], t_fail[i] = c, tf
    for k in range(acc.shape[1]):
        acc[i, k] = Z[z_acc + k * LANES + lane]
    pt[lane] = -1


@nb.njit(cache=True, error_model="numpy")
def _error_norms(K, h, scale, E, E3, ny, w5, w3, e53, err):
    """`explicit._error_norm` per lane (e53: scratch, 2 × LANES)."""
    L = LANES
    _sum(E, K, E.shape[0], w5)
    if E3.shape[0] > 0:
        _sum(E3, K, E3.shape[0], w3)
    for lane in range(L):
        e53[0, lane] = 0.0
        e53[1, lane] = 0.0
    for j in range(ny):             # lanes innermost; each lane sums in j order, as the scalar
        for lane in range(L):
            e53[0, lane] += (w5[j * L + lane] / scale[j * L + lane]) ** 2
    if E3.shape[0] > 0:
        for j in range(ny):
            for lane in range(L):
                e53[1, lane] += (w3[j * L + lane] / scale[j * L + lane]) ** 2
    for lane in range(L):
        e5, e3 = e53[0, lane], e53[1, lane]
        if E3.shape[0] == 0:
            err[lane] = abs(h[lane]) * np.sqrt(e5 / ny)
        elif e5 == 0.0 and e3 == 0.0:
            err[lane] = 0.0
        else:
            err[lane] = abs(h[lane]) * e5 / np.sqrt((e5 + 0.01 * e3) * ny)


@nb.njit(cache=True, error_model="numpy")
def _prepare_dense(f, t, y, y_new, h, K, n_st, AX, CX, D, F, ys, T, Z, ny):
    """DOP853's three extra stages and its interpolant's rows F, as `dense._prepare_dense`."""
    L = LANES
    n_k = n_st + 1
    for e in range(AX.shape[0]):
        s = n_k + e
        _stage(y, h, AX[e], K, s, ny, ys)
        for lane in range(L):
            T[lane] = t[lane] + CX[e] * h[lane]
        _call(f, T, ys, Z, K[s])
    for j in range(ny):
        for lane in range(L):
            k = j * L + lane
            dy = y_new[k] - y[k]
            F[0, k] = dy
            F[1, k] = h[lane] * K[0, k] - dy
            F[2, k] = 2.0 * dy - h[lane] * (K[n_st, k] + K[0, k])
    for r in range(D.shape[0]):
        _sum(D[r], K, D.shape[1], F[3 + r])
        for j in range(ny):
            for lane in range(L):
                F[3 + r, j * L + lane] *= h[lane]


@nb.njit(cache=True, error_model="numpy")
def _eval_dense(y, y_new, x, exact, F, ny, out):
    """One output row per lane into out[:ny · LANES]: y_new where the row is the step's end,
    else DOP853's interpolant at x, its N_F rows in `dense._eval_dense`'s order (Horner from the
    last row, x and 1 − x alternating). Written out with the sum in a register: as a loop over
    the rows, storing into `out` each time, it took 58 ns a lane against 24 (rotor, same
    process)."""
    L = LANES
    for j in range(ny):
        for lane in range(L):
            k = j * L + lane
            xl = x[lane]
            xm = 1.0 - xl
            a = (0.0 + F[6, k]) * xl
            a = (a + F[5, k]) * xm
            a = (a + F[4, k]) * xl
            a = (a + F[3, k]) * xm
            a = (a + F[2, k]) * xl
            a = (a + F[1, k]) * xm
            a = (a + F[0, k]) * xl
            out[k] = y_new[k] if exact[lane] else y[k] + a


@nb.njit(cache=True)       # typed on first use, not at import: most processes never call it
def integrate_dop853_lanes(f, guard, row, Y0, P, t_out, rtol, atol, h_max, max_steps,
                           A, B, C, E, E3, err_order, AX, CX, D, acc0, n_s, code, t_fail, acc):
    """Every point i (state Y0[i], parameters P[i]) on the output grid `t_out`; fills code[i],
    t_fail[i] and acc[i] (the row reduce's accumulators, from acc0). h_max ≤ 0: no cap; n_s:
    the scratch rows `f` and `row` use."""
    L = LANES
    n, ny, n_p, n_a = Y0.shape[0], Y0.shape[1], P.shape[1], acc0.shape[0]
    n_out, n_st = t_out.shape[0], B.shape[0]
    n_k = n_st + 1
    if D.shape[0] != N_F - 3:
        raise ValueError("integrate_dop853_lanes: DOP853's interpolant (7 rows: D has 4)")
    t0, t_end = t_out[0], t_out[n_out - 1]
    if h_max <= 0.0:
        h_max = np.inf
    expo = -1.0 / (err_order + 1)
    K = np.empty((n_k + AX.shape[0], ny * L))
    F = np.empty((N_F, ny * L))
    y, y_new, ys, fy = np.zeros(ny * L), np.zeros(ny * L), np.zeros(ny * L), np.zeros(ny * L)
    w5, w3, out, scale = np.empty(ny * L), np.empty(ny * L), np.empty(ny * L), np.empty(ny * L)
    Z = np.zeros((2 * ny + n_p + n_a + 3 + n_s) * L)
    z_p, z_acc = 2 * ny * L, (2 * ny + n_p) * L
    Tr, Jr, M = Z[z_acc + n_a * L:], Z[z_acc + (n_a + 1) * L:], Z[z_acc + (n_a + 2) * L:]
    e53 = np.zeros((2, L))
    lane_f = np.zeros((7, L))           # per lane: stage time, row's x, t, step, trial, error
    T, x = lane_f[0], lane_f[1]
    t, h, h_try, t_new, err = lane_f[2], lane_f[3], lane_f[4], lane_f[5], lane_f[6]
    lane_i = np.zeros((3, L), np.int64)
    steps, rejected, i_out = lane_i[0], lane_i[1], lane_i[2]
    pt = np.full(L, -1, np.int64)
    lane_b = np.zeros((5, L), np.bool_)
    last, just_rejected, accepted, exact, fresh = (lane_b[0], lane_b[1], lane_b[2], lane_b[3],
                                                   lane_b[4])
    ysc, fsc = np.empty(ny), np.empty(ny)
    nxt = 0
    while True:
        # idle lanes take the next points: state, parameters, f(y0), first step, row 0
        any_fresh = False
        for lane in range(L):
            fresh[lane] = False
            if pt[lane] < 0 and nxt < n:
                pt[lane], nxt, fresh[lane], any_fresh = nxt, nxt + 1, True, True
                for j in range(ny):
                    y[j * L + lane] = Y0[pt[lane], j]
                for j in range(n_p):
                    Z[z_p + j * L + lane] = P[pt[lane], j]
                for j in range(n_a):
                    Z[z_acc + j * L + lane] = acc0[j]
                t[lane] = t0
                steps[lane], rejected[lane], i_out[lane] = 0, 0, 1
                just_rejected[lane] = False
        if any_fresh:
            for lane in range(L):
                T[lane] = t0
            _call(f, T, y, Z, out)
            for lane in range(L):
                M[lane] = 1.0 if fresh[lane] else 0.0
                Jr[lane], Tr[lane] = 0.0, t0
                if fresh[lane]:
                    for j in range(ny):
                        fy[j * L + lane] = out[j * L + lane]
                        ysc[j], fsc[j] = y[j * L + lane], out[j * L + lane]
                    h[lane] = min(initial_step(ysc, fsc, rtol, atol), h_max)
            for k in range(ny * L):
                Z[k] = y[k]
            row(Z)
        busy = False
        for lane in range(L):
            accepted[lane] = False
            if pt[lane] < 0:
                continue
            if i_out[lane] >= n_out:        # a one-row grid: nothing to step (as the scalar)
                _finish(lane, pt, FAIL_OK, np.nan, Z, z_acc, code, t_fail, acc)
                continue
            if steps[lane] + rejected[lane] >= max_steps:
                _finish(lane, pt, FAIL_MAX_STEPS, t[lane], Z, z_acc, code, t_fail, acc)
                continue
            last[lane] = t[lane] + h[lane] >= t_end - 1e-12 * abs(t_end)
            h_try[lane] = t_end - t[lane] if last[lane] else h[lane]
            if h_try[lane] < 10.0 * np.abs(np.nextafter(t[lane], np.inf) - t[lane]):
                _finish(lane, pt, FAIL_STEP_UNDERFLOW, t[lane], Z, z_acc, code, t_fail, acc)
                continue
            busy = True
        if not busy:
            if nxt >= n:
                return
            continue
        # one trial step on every lane (idle lanes compute on stale numbers, ignored)
        K[0, :] = fy
        for s in range(1, n_st):
            _stage(y, h_try, A[s], K, s, ny, ys)
            for lane in range(L):
                T[lane] = t[lane] + C[s] * h_try[lane]
            _call(f, T, ys, Z, K[s])
        _sum(B, K, n_st, y_new)
        for j in range(ny):
            for lane in range(L):
                k = j * L + lane
                y_new[k] = y[k] + h_try[lane] * y_new[k]
        for lane in range(L):
            T[lane] = t[lane] + h_try[lane]
        _call(f, T, y_new, Z, K[n_st])
        for k in range(ny * L):
            scale[k] = atol + max(abs(y[k]), abs(y_new[k])) * rtol
        _error_norms(K, h_try, scale, E, E3, ny, w5, w3, e53, err)
        any_dense = False
        for lane in range(L):
            if pt[lane] < 0:
                continue
            e = err[lane]
            if not np.isfinite(e):
                e = 1e10
            err[lane] = e
            if e >= 1.0:
                rejected[lane] += 1
                just_rejected[lane] = True
                h[lane] = h_try[lane] * max(0.2, 0.9 * e ** expo)
                continue
            t_new[lane] = t_end if last[lane] else t[lane] + h_try[lane]
            steps[lane] += 1
            for j in range(ny):
                ysc[j] = y_new[j * L + lane]
            c = guard(t_new[lane], ysc, P[pt[lane]])
            if c != 0:
                _finish(lane, pt, c, t_new[lane], Z, z_acc, code, t_fail, acc)
                continue
            accepted[lane] = True
            tn = t_new[lane]
            any_dense = any_dense or t_out[i_out[lane]] < tn - 1e-12 * abs(tn)
        if any_dense:
            _prepare_dense(f, t, y, y_new, h_try, K, n_st, AX, CX, D, F, ys, T, Z, ny)
        # the outputs inside each lane's accepted step, one row per lane per pass
        while True:
            pending = False
            for lane in range(L):
                M[lane] = 0.0
                if accepted[lane] and i_out[lane] < n_out:
                    tn, to = t_new[lane], t_out[i_out[lane]]
                    if to <= tn + 1e-12 * abs(tn):
                        pending = True
                        M[lane], Jr[lane], Tr[lane] = 1.0, i_out[lane], to
                        exact[lane] = to >= tn - 1e-12 * abs(tn)
                        x[lane] = (to - t[lane]) / h_try[lane]
            if not pending:
                break
            _eval_dense(y, y_new, x, exact, F, ny, Z)
            row(Z)
            for lane in range(L):
                if M[lane] != 0.0:
                    i_out[lane] += 1
        for lane in range(L):
            if not accepted[lane]:
                continue
            t[lane] = t_new[lane]
            for j in range(ny):
                k = j * L + lane
                y[k] = y_new[k]
                fy[k] = K[n_st, k]
            e = err[lane]
            fac = 10.0 if e == 0.0 else min(10.0, 0.9 * e ** expo)
            if just_rejected[lane]:
                fac = min(1.0, fac)
                just_rejected[lane] = False
            h[lane] = min(h_max, max(h[lane], h_try[lane] * fac) if last[lane]
                          else h_try[lane] * fac)
            if i_out[lane] >= n_out:
                _finish(lane, pt, FAIL_OK, np.nan, Z, z_acc, code, t_fail, acc)
