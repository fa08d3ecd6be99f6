"""Drivers of the thread-spool model: explicit RK4 in the rotating frame through the shared
fixed-step dense-output driver (custom_models/integrators/dense.py, allocation-free right-hand
side), and the implicit midpoint rule with energy–momentum spring forces in the inertial frame
(its own step: the discrete gradient is the method). Both land a step on every release and at
the end of payout and release nodes there; the implicit midpoint also steps onto every output,
RK4 interpolates them (cubic Hermite). Both integrate only the released nodes: the stored ones
sit on the spool until their release.

- "rk4": the paper's fixed-step explicit RK4 in the rotating frame. A step above the stability
  limit is caught (spring stretch beyond `stretch_limit`·l0, or a non-finite state).
- "imr": implicit midpoint rule in the inertial frame with energy–momentum (discrete-gradient,
  Simo & Tarnow 1992) spring forces: each spring's force is c(1 − l0/ℓ̄) times the midpoint
  chord, ℓ̄ the mean of its start and end lengths. The total angular momentum is then conserved
  exactly (forces along the midpoint chords; the hub–node pair at Q balanced), for any step; the
  springs' work is exactly −ΔU, so the unresolved longitudinal modes (1e5 rad/s) cannot pump
  energy (the plain midpoint rule did: at dt = 1e-3 it went unstable within 20 s). Newton on the
  midpoint velocities and hub rate; the Newton matrix (spring stiffness + damping, bordered by
  the hub) is block-tridiagonal and solved in O(n) (`integrators.implicit`). Where Newton fails
  (just after a release the new boundary segment is nearly zero-length and its transverse
  stiffness T/ℓ is huge) the step is retried as 2, 4, … 4096 sub-steps (stats "retries").
"""
import numba as nb
import numpy as np

from compare.physics.sail import release_state

from ..integrators import FIXED_TABLEAUS
from ..integrators.dense import integrate_fixed_dense
from ..integrators.implicit import block3_tridiag_factor, bordered_block3_solve
from .equations import _forces_dg, _lengths, _max_stretch, _rhs_rot, _spring_jac
from .model import (
    CC,
    DD,
    EPS,
    JH,
    LC,
    NN,
    NP,
    OFF,
    RR,
    SLIM,
    STORED,
    TURN,
    WSP,
    imr_work,
    j_eff,
    payout,
)

FAIL_NONFINITE, FAIL_STRETCH, FAIL_NEWTON = 1, 10, 11
REASONS = {FAIL_NONFINITE: "non-finite state",
           FAIL_STRETCH: "spring stretch beyond stretch_limit*l0",
           FAIL_NEWTON: "Newton iteration of the implicit midpoint step did not converge"}


@nb.njit(cache=True)
def release_rot(y, P, j):
    """Release node j at Q (body frame): the release law of compare.physics.sail written in the
    rotating frame — at Q = (0, 0, r) with body velocity (r ω, 0, 0) — or, in the paper variant,
    turned along the released thread [12] (|v| kept)."""
    n = int(P[NN])
    ox, ov = OFF, OFF + 3 * n
    rw = P[RR] * P[WSP]
    y[ox + 3 * j] = 0.0
    y[ox + 3 * j + 1] = 0.0
    y[ox + 3 * j + 2] = P[RR]
    vx, vy, vz = rw, 0.0, 0.0
    if P[TURN] > 0.5 and j > 0:                     # [12]: turn along the released thread
        dx = y[ox + 3 * j - 3] - y[ox + 3 * j]
        dy = y[ox + 3 * j - 2] - y[ox + 3 * j + 1]
        dz = y[ox + 3 * j - 1] - y[ox + 3 * j + 2]
        ell = np.sqrt(dx * dx + dy * dy + dz * dz)
        if ell > 0.0:
            vx, vy, vz = rw * dx / ell, rw * dy / ell, rw * dz / ell
    y[ov + 3 * j] = vx
    y[ov + 3 * j + 1] = vy
    y[ov + 3 * j + 2] = vz


@nb.njit(cache=True)
def split(T, dt):
    """Equal steps no longer than dt over a breakpoint interval T: (count ≥ 1, step)."""
    ns = max(1, int(np.ceil(T / dt - 1e-9)))
    return ns, T / ns


@nb.njit(cache=True)
def release_in(y, P, j):
    """Release node j at Q (inertial frame) by the shared release law (at Q, the hub point's
    velocity + r ω along the rotated X1 axis), turned along the thread in the paper variant."""
    n = int(P[NN])
    ox, ov = OFF, OFF + 3 * n
    rw = P[RR] * P[WSP]
    Q0, Q1, Q2, v0, v1, v2 = release_state(y[1], y[0], P[LC], P[RR], rw)
    y[ox + 3 * j] = Q0
    y[ox + 3 * j + 1] = Q1
    y[ox + 3 * j + 2] = Q2
    if P[TURN] > 0.5 and j > 0:
        dx = y[ox + 3 * j - 3] - Q0
        dy = y[ox + 3 * j - 2] - Q1
        dz = y[ox + 3 * j - 1] - Q2
        ell = np.sqrt(dx * dx + dy * dy + dz * dz)
        if ell > 0.0:
            Om = y[0]
            v0, v1, v2 = -Om * Q1 + rw * dx / ell, Om * Q0 + rw * dy / ell, rw * dz / ell
    y[ov + 3 * j] = v0
    y[ov + 3 * j + 1] = v1
    y[ov + 3 * j + 2] = v2


@nb.njit(cache=True)
def copy_active(src, dst, n, Nb):
    """dst = src on the entries a step changes: hub, D, W and nodes 0..Nb−1 (the stored nodes
    are neither read nor written until their release)."""
    for q in range(OFF + 3 * Nb):
        dst[q] = src[q]
    for q in range(OFF + 3 * n, OFF + 3 * n + 3 * Nb):
        dst[q] = src[q]


@nb.njit(cache=True)
def step_imr(t, h, y, P, m, b, tol, w):
    """One step of the implicit midpoint rule with energy–momentum spring forces, inertial
    frame. Unknowns: midpoint velocities of nodes 0..b and the midpoint hub rate (Newton,
    block-tridiagonal matrix bordered by the hub; working arrays in w, an ImrWork). Returns
    (code, newton_iterations)."""
    F, Ym, Y1, Dm, Bm, Dinv, U, R, X, G = w.F, w.Ym, w.Y1, w.Dm, w.Bm, w.Dinv, w.U, w.R, w.X, w.G
    l_a, l_e, TR = w.l_a, w.l_e, w.TR
    n = int(P[NN])
    ox, ov = OFF, OFF + 3 * n
    hh = 0.5 * h
    c, d = P[CC], P[DD]
    J1 = 0.5 * j_eff(P, m, b)            # one blade's share of the hub
    Nb = b + 1
    tm = t + hh
    _lengths(y, P, b, np.sin(y[1]), np.cos(y[1]), l_a)
    copy_active(y, Ym, n, Nb)
    copy_active(y, Y1, n, Nb)
    it = 0
    dprev = np.inf
    fqx = fqy = diss = wsp = 0.0
    dmax, vmax, dOm = 0.0, 1.0, 0.0
    q_on = payout(tm, P)[2]
    for it in range(1, 40):
        Om = Ym[0]
        Ym[1] = y[1] + hh * Om
        Y1[1] = y[1] + h * Om
        for k in range(3 * Nb):
            Ym[ox + k] = y[ox + k] + hh * Ym[ov + k]
            Y1[ox + k] = y[ox + k] + h * Ym[ov + k]
        _lengths(Y1, P, b, np.sin(Y1[1]), np.cos(Y1[1]), l_e)
        ps, pc = np.sin(Ym[1]), np.cos(Ym[1])
        Q0, Q1, Q2 = P[LC] * pc, P[LC] * ps, P[RR]
        fqx, fqy, diss, wsp = _forces_dg(tm, Ym, P, m, b, (Q0, Q1, Q2), (-Om * Q1, Om * Q0),
                                         (pc, ps, 0.0), w)
        w0, w1 = -Q1, Q0                        # e_z × ρ_Q
        for j in range(Nb):
            for a in range(3):
                R[j, a] = -(m[j] * (Ym[ov + 3 * j + a] - y[ov + 3 * j + a]) - hh * F[3 * j + a])
        Mz = -(w0 * fqx + w1 * fqy)             # one blade's torque on the hub
        rho = -(J1 * (Om - y[0]) - hh * Mz)
        if it > 1:
            rel = max(dmax / vmax, abs(dOm) / (abs(Ym[0]) + 1e-3))
            if rel <= tol:
                break
            if rel <= 1e-9 and rel >= 0.5 * dprev:   # stagnated at round-off: converged
                break
            dprev = rel
        for j in range(Nb):
            for a in range(3):
                for q in range(3):
                    Dm[j, a, q] = m[j] if a == q else 0.0
        for j in range(b):
            dx = Ym[ox + 3 * j + 3] - Ym[ox + 3 * j]
            dy = Ym[ox + 3 * j + 4] - Ym[ox + 3 * j + 1]
            dz = Ym[ox + 3 * j + 5] - Ym[ox + 3 * j + 2]
            _spring_jac(dx, dy, dz, max(TR[j], 0.0), c, d, hh, G)
            for a in range(3):
                for q in range(3):
                    Dm[j, a, q] += G[a, q]
                    Dm[j + 1, a, q] += G[a, q]
                    Bm[j, a, q] = -G[a, q]
        dx = Q0 - Ym[ox + 3 * b]
        dy = Q1 - Ym[ox + 3 * b + 1]
        dz = Q2 - Ym[ox + 3 * b + 2]
        if dx * dx + dy * dy + dz * dz < P[EPS] ** 2:
            dx, dy, dz = -pc, -ps, 0.0
        if q_on:
            _spring_jac(dx, dy, dz, max(TR[b], 0.0), c, d, hh, G)
        else:                                   # last node released: no Q-spring
            G[:, :] = 0.0
        for a in range(3):
            for q in range(3):
                Dm[b, a, q] += G[a, q]
        for j in range(Nb):
            for a in range(3):
                U[j, a] = 0.0
        gw0 = G[0, 0] * w0 + G[0, 1] * w1
        gw1 = G[1, 0] * w0 + G[1, 1] * w1
        gw2 = G[2, 0] * w0 + G[2, 1] * w1
        U[b, 0], U[b, 1], U[b, 2] = -gw0, -gw1, -gw2
        delta = J1 + w0 * gw0 + w1 * gw1
        if not block3_tridiag_factor(Dm, Bm, Nb, Dinv, w.Wf):
            return FAIL_NEWTON, it
        dOm = bordered_block3_solve(Bm, Dinv, Nb, U, delta, R, rho, X, w.Xu)
        Ym[0] += dOm
        vmax = 1e-3
        dmax = 0.0
        for j in range(Nb):
            for a in range(3):
                Ym[ov + 3 * j + a] += X[j, a]
                vmax = max(vmax, abs(Ym[ov + 3 * j + a]))
                dmax = max(dmax, abs(X[j, a]))
        if not np.isfinite(dOm) or not np.isfinite(dmax):
            return FAIL_NONFINITE, it
    else:
        return FAIL_NEWTON, it
    # the last residual evaluation used the converged midpoint: take the step
    Om = Ym[0]
    y[0] = 2.0 * Om - y[0]
    y[1] = y[1] + h * Om
    y[2] += h * diss
    y[3] += h * wsp
    for k in range(3 * Nb):
        y[ox + k] = y[ox + k] + h * Ym[ov + k]
        y[ov + k] = 2.0 * Ym[ov + k] - y[ov + k]
    return 0, it - 1


# ---- RK4, rotating frame, through the shared fixed-step dense driver --------------------------
# Between two releases the boundary index b is constant and the stored nodes sit rigidly on the
# spool, so each such stretch integrates the released nodes 0..b only (state `_active`): their
# parameters p = [P with n = b + 1 and the stored thread's inertia folded into J_hub (j_eff, as
# the full model counts it), b, m_0..m_b] — the shared drivers take one float array p.
B_AT, M_AT = NP, NP + 1


@nb.njit(cache=True)
def rhs_rotating_into(t, y, p, dy):
    n = int(p[NN])
    # the forces go straight into the acceleration slots (each is read before it is replaced)
    _rhs_rot(t, y, p, p[M_AT:M_AT + n], int(p[B_AT]), dy[OFF + 3 * n:], dy)


@nb.njit(cache=True)
def guard_rotating(t, y, p):
    return FAIL_STRETCH if _max_stretch(y, p, int(p[B_AT]), t, False) > p[SLIM] else 0


def _active(P, m, b):
    """Parameters of a stretch with boundary node b, and the index of the active states in the
    full state vector (Ω, ψ, D, W, x_0..x_b, v_0..v_b)."""
    n, na = int(P[NN]), b + 1
    Pa = P.copy()
    Pa[NN], Pa[JH], Pa[STORED] = na, j_eff(P, m, b), 0.0
    idx = np.r_[0:OFF + 3 * na, OFF + 3 * n:OFF + 3 * n + 3 * na]
    return np.concatenate((Pa, [float(b)], m[:na])), idx


def run_rk4(y0, P, m, bk_t, bk_out, bk_rel, bk_end, dt, n_out):
    """Fixed-step RK4 in the rotating frame, one driver call per stretch between releases (and
    the end of payout, a kink in the Q-spring's rest length); the outputs inside a stretch come
    from the driver's dense output. Returns (Y, b_out, stats, t_fail, code)."""
    tb = FIXED_TABLEAUS["rk4"]
    Y = np.full((n_out, y0.shape[0]), np.nan)
    b_out = np.zeros(n_out, np.int64)
    y = y0.copy()
    b = 0
    release_rot(y, P, 0)
    if bk_out[0] >= 0:
        Y[bk_out[0]] = y
    steps = evals = 0
    ends = {i for i in range(1, len(bk_t)) if bk_rel[i] > 0 or bk_end[i]} | {len(bk_t) - 1}
    i0 = 0
    for i1 in sorted(ends - {0}):
        p, idx = _active(P, m, b)
        Ya, st, ev, t_fail, code = integrate_fixed_dense(
            rhs_rotating_into, guard_rotating, y[idx], p, bk_t[i0:i1 + 1], dt, tb["A"], tb["B"],
            tb["C"])
        steps, evals = steps + st, evals + ev
        rows = bk_out[i0 + 1:i1 + 1]
        out = rows >= 0
        Ys = np.repeat(y[None, :], len(Ya) - 1, axis=0)      # stored nodes: unchanged
        Ys[:, idx] = Ya[1:]
        Y[rows[out]], b_out[rows[out]] = Ys[out], b
        if code != 0:
            return Y, b_out, {"steps": steps, "rhs_evals": evals}, t_fail, code
        y = Ys[-1].copy()
        if bk_rel[i1] > 0:
            b = bk_rel[i1]
            release_rot(y, P, b)
            if bk_out[i1] >= 0:
                Y[bk_out[i1]], b_out[bk_out[i1]] = y, b
        i0 = i1
    return Y, b_out, {"steps": steps, "rhs_evals": evals}, np.nan, 0


# ---- implicit midpoint rule, inertial frame ----------------------------------------------------
@nb.njit(cache=True)
def _imr_loop(y0, P, m, bk_t, bk_out, bk_rel, dt, n_out, tol):
    ny = y0.shape[0]
    n = int(P[NN])
    Y = np.full((n_out, ny), np.nan)
    b_out = np.zeros(n_out, np.int64)
    w = imr_work(n, ny)
    ysave = w.ysave
    y = y0.copy()
    # the boundary node as a typed int64, not the constant 0: numba would otherwise compile
    # step_imr and the kernels below it twice, once for Literal[int](0) (this loop's cold
    # compile 16.6 -> 15.0 s)
    b = np.int64(0)
    release_in(y, P, b)
    steps = 0
    iters = 0
    evals = 0
    retries = 0
    slim = P[SLIM]
    for ib in range(bk_t.shape[0]):
        if ib > 0:
            t0 = bk_t[ib - 1]
            ns, h = split(bk_t[ib] - t0, dt)
            for k in range(ns):
                t = t0 + k * h
                # Newton may fail where the boundary segment is nearly zero-length (just after
                # a release, stiff springs): retry the step as 2, 4, ... 4096 sub-steps
                copy_active(y, ysave, n, b + 1)
                for lev in range(13):
                    nsub = 1 << lev
                    hs = h / nsub
                    code = 0
                    for ks in range(nsub):
                        code, it = step_imr(t + ks * hs, hs, y, P, m, b, tol, w)
                        steps += 1
                        iters += it
                        evals += it + (code == 0)   # force evaluations
                        if code != 0:
                            break
                    if code == 0:
                        break
                    retries += 1
                    copy_active(ysave, y, n, b + 1)
                if code != 0:
                    return Y, b_out, steps, iters, evals, retries, t + h, code
                if _max_stretch(y, P, b, t + h, True) > slim:
                    return Y, b_out, steps, iters, evals, retries, t + h, FAIL_STRETCH
        j = bk_rel[ib]
        if j > 0:
            b = j
            release_in(y, P, j)
        if bk_out[ib] >= 0:
            Y[bk_out[ib]] = y
            b_out[bk_out[ib]] = b
    return Y, b_out, steps, iters, evals, retries, np.nan, 0


def run_imr(y0, P, m, bk_t, bk_out, bk_rel, dt, n_out, tol):
    """Implicit midpoint rule in the inertial frame. Returns (Y, b_out, stats, t_fail, code);
    stats: steps, newton_iters, retries (the failed steps retried with sub-steps), rhs_evals
    (evaluations of the midpoint forces: one per Newton pass, each followed by an O(n) solve)."""
    Y, b_out, steps, iters, evals, retries, t_fail, code = _imr_loop(
        y0, P, m, bk_t, bk_out, bk_rel, dt, n_out, tol)
    return Y, b_out, {"steps": int(steps), "rhs_evals": int(evals), "newton_iters": int(iters),
                      "retries": int(retries)}, t_fail, code
