"""Linear-acceleration (Wilson-θ) integration of M(q, t) q'' = Q(q, q', t), compiled with numba.

The method (Wilson 1962; Bathe & Wilson; the press paper's eqs. 41–45) assumes the acceleration
varies linearly over t_i … t_i + τ, τ = θ·h:

    q''(t_i + s) = q''_i + (a − q''_i) s/τ          a = q''(t_i + τ)
    q'(t_i + τ)  = q'_i + τ (q''_i + a)/2                                  (eq. 42 / 44)
    q(t_i + τ)   = q_i + τ q'_i + τ² (q''_i/3 + a/6)                       (eq. 43 / 45)

and demands that the equations of motion hold at t_i + τ. θ = 1 is the plain linear-acceleration
method (Newmark β = 1/6, γ = 1/2): stable only for h ≤ (√3/π)·T = 0.551·T of the fastest mode;
θ ≥ 1.37 makes it unconditionally stable for linear systems. The end-of-step acceleration is
q''_{i+1} = q''_i + (a − q''_i)/θ, and q', q follow from the same linear law over h.

Three ways to find a (setting `mode`):
- MODE_NEWTON: Newton on R(a) = a − f(t+τ, q(a), q'(a)) with the Jacobian
  I − (τ²/6) ∂f/∂q − (τ/2) ∂f/∂q' by forward differences, once per step. The implicit
  method proper: its stability is the theory's (0.551·T at θ = 1).
- MODE_FIXED_POINT: a ← f(t+τ, q(a), q'(a)) until converged. Cheaper per iteration, but it
  contracts only while (ωτ)²/6 < 1, i.e. it fails *below* the method's own limit (h < 0.39·T).
- MODE_PC: exactly one such correction from a = q''_i: the paper's algorithm as printed
  (predict with constant acceleration, eqs. 38–39; evaluate, eq. 40; correct with the linear
  law, eqs. 44–45), the next step restarting from accelerations evaluated at the corrected state.
  An explicit predictor–corrector with its own, smaller stability limit: h ≤ 0.318·T (spectral
  radius of its amplification matrix for q'' = −ω²q; measured, not from the paper).

The model supplies one jitted function `acc(t, q, qd, p) -> array(n + nz)`: the accelerations
q'' (first n entries), optionally followed by the rates of nz auxiliary integrals z' = g(t, q, q')
(work of non-conservative forces, for an energy balance). z is integrated with the trapezoid
rule, which is what the linear-acceleration assumption gives for a rate sampled at the step
ends (second order, like the method). `accel_from_mass_force` builds `acc` from M and Q callables.

A step whose Newton iteration does not converge is retried as 2, 4, … 2^MAX_CUTS equal steps
from the same start (`la_step`; the time-step cutback of implicit finite-element codes). Its
cause is rarely the step's size: the tolerance sits below the model's own rounding (the
partial systems' second differences amplify the closures' rounding by 1/Δθ², 5e-7 of θ'' on 40
chained loops), so the iteration alternates between two accelerations for ever, and the
shorter step's convergence test on the state (τ²/6 of the correction) is met. The fixed-point
and predictor–corrector variants keep their one step (their limits are the variants' own).
`steps` counts the steps taken, cut ones included.

Output layout matches the explicit drivers: rows [q, q', z] on the output grid, NaN after a
failure, plus (steps, rhs_evals, t_fail, code).
"""
import math

import numba as nb
import numpy as np
from numba import types as nt

from .explicit import _MAT, _VEC, FAIL_NONFINITE, FAIL_OK, GUARD

# acc(t, q, q', p) -> [q'', z'] as a first-class function type: the drivers are compiled (and
# cached on disk) once for every model, as the explicit ones (q, q' may be slices: layout 'A')
ACC = nt.FunctionType(_VEC(nt.float64, nt.float64[:], nt.float64[:], _VEC))

FAIL_NO_CONVERGENCE = 4
MAX_CUTS = 4                # a step that does not converge is retried down to h/16
MODE_NEWTON, MODE_FIXED_POINT, MODE_PC = 0, 1, 2
# the variants a leaf offers by name: (θ, or None = the leaf's `theta` setting; iteration mode)
LA_INTEGRATORS = {"linacc": (1.0, MODE_NEWTON), "wilson": (None, MODE_NEWTON),
                  "linacc-pc": (1.0, MODE_PC), "linacc-fp": (1.0, MODE_FIXED_POINT)}
LA_REASONS = {FAIL_NO_CONVERGENCE: "implicit linear-acceleration step did not converge "
                                   "(iteration diverged: step too large for the iteration)"}


@nb.njit(cache=True)
def solve_small(A, b):
    """x = A⁻¹b by Gaussian elimination with partial pivoting, for the few-DOF systems here
    (compiles in a fraction of the time of np.linalg.solve's LAPACK binding; NaN if singular)."""
    n = b.shape[0]
    M = A.copy()
    x = b.copy()
    for k in range(n):
        piv = k
        for i in range(k + 1, n):
            if abs(M[i, k]) > abs(M[piv, k]):
                piv = i
        if M[piv, k] == 0.0:
            return np.full(n, np.nan)
        if piv != k:
            for j in range(n):
                M[k, j], M[piv, j] = M[piv, j], M[k, j]
            x[k], x[piv] = x[piv], x[k]
        for i in range(k + 1, n):
            f = M[i, k] / M[k, k]
            for j in range(k, n):
                M[i, j] -= f * M[k, j]
            x[i] -= f * x[k]
    for k in range(n - 1, -1, -1):
        acc = x[k]
        for j in range(k + 1, n):
            acc -= M[k, j] * x[j]
        x[k] = acc / M[k, k]
    return x


def accel_from_mass_force(mass, force):
    """acc(t, q, qd, p) = M(t, q, p)^-1 Q(t, q, qd, p) from two jitted callables."""
    @nb.njit
    def acc(t, q, qd, p):
        return solve_small(mass(t, q, p), force(t, q, qd, p))
    return acc


def as_first_order(acc, n):
    """y' = [q', q'', z'] for y = [q, q', z], so the explicit RK drivers can integrate the same
    model (`acc` as above, n the number of coordinates)."""
    @nb.njit
    def f(t, y, p):
        r = acc(t, y[:n], y[n:2 * n], p)
        dy = np.empty(y.shape[0])
        dy[:n] = y[n:2 * n]
        dy[n:] = r
        return dy
    return f


@nb.njit(cache=True)
def _all_finite(x):
    for v in x:
        if not np.isfinite(v):
            return False
    return True


@nb.njit(cache=True)
def _state_at(q, qd, qdd, a, tau, qt, qdt):
    """q, q' at t + τ from the linear acceleration law, given a = q''(t + τ)."""
    for j in range(q.shape[0]):
        qt[j] = q[j] + tau * qd[j] + tau * tau * (qdd[j] / 3.0 + a[j] / 6.0)
        qdt[j] = qd[j] + 0.5 * tau * (qdd[j] + a[j])


@nb.njit(cache=True)
def _jacobian(acc, t, qt, qdt, p, tau, n, f0):
    """I − (τ²/6) ∂f/∂q − (τ/2) ∂f/∂q' by forward differences (2n evaluations)."""
    Jm = np.eye(n)
    for k in range(n):
        for which in range(2):
            x = qt if which == 0 else qdt
            xk = x[k]
            dx = 1e-7 * max(abs(xk), 1e-3) if which == 0 else 1e-7 * max(abs(xk), 1.0)
            x[k] = xk + dx
            fk = acc(t, qt, qdt, p)
            x[k] = xk
            w = tau * tau / 6.0 if which == 0 else 0.5 * tau
            for j in range(n):
                Jm[j, k] -= w * (fk[j] - f0[j]) / dx
    return Jm


@nb.njit(cache=True)
def wilson_step(acc, t, q, qd, qdd, z, zd, p, h, theta, mode, tol, max_iter):
    """One step from (q, q', q'', z, z') at t. Returns (q1, qd1, qdd1, z1, zd1, evals, code);
    qdd1 is the method's own end acceleration (for θ = 1 it satisfies the equations)."""
    n = q.shape[0]
    nz = z.shape[0]
    tau = theta * h
    a = qdd.copy()                                   # start from constant acceleration (eq. 38)
    qt = np.empty(n)
    qdt = np.empty(n)
    evals = 0
    _state_at(q, qd, qdd, a, tau, qt, qdt)
    r = acc(t + tau, qt, qdt, p)
    evals += 1
    if mode == MODE_NEWTON:
        Jm = _jacobian(acc, t + tau, qt, qdt, p, tau, n, r)
        evals += 2 * n
    code = FAIL_NO_CONVERGENCE
    err_prev = np.inf
    q_scale = 0.0
    for j in range(n):
        q_scale = max(q_scale, abs(q[j]))
    for it in range(max_iter if mode != MODE_PC else 1):
        if not _all_finite(r):
            return q, qd, qdd, z, zd, evals, FAIL_NONFINITE
        res = a - r[:n]
        if mode == MODE_NEWTON:
            da = solve_small(Jm, res)
        else:
            da = res
        scale = 0.0
        err = 0.0
        for j in range(n):
            a[j] -= da[j]
            scale = max(scale, abs(a[j]))
            err = max(err, abs(da[j]))
        _state_at(q, qd, qdd, a, tau, qt, qdt)
        # converged: relative to the accelerations, or the correction moves q by < 1e-3·tol
        # (coordinates O(1)): the latter ends iterations on a tiny decayed motion whose
        # accelerations sit at the model's round-off level
        if (mode == MODE_PC or err <= tol * scale or err == 0.0
                or tau * tau / 6.0 * err <= 1e-3 * tol * (1.0 + q_scale)):
            code = FAIL_OK
            break
        # round-off floor of the model's accelerations (finite differences inside acc): the
        # correction stopped shrinking but is already tiny
        if it > 0 and err >= 0.5 * err_prev and err <= 1e3 * tol * scale:
            code = FAIL_OK
            break
        r = acc(t + tau, qt, qdt, p)
        evals += 1
        if mode == MODE_NEWTON and it > 0 and err > 0.25 * err_prev:
            # slow contraction: the step-start Jacobian is stale (strong nonlinearity), refresh
            Jm = _jacobian(acc, t + tau, qt, qdt, p, tau, n, r)
            evals += 2 * n
        err_prev = err
    if code != FAIL_OK:
        return q, qd, qdd, z, zd, evals, code
    # back from t + τ to t + h along the same linear law
    qdd1 = np.empty(n)
    qd1 = np.empty(n)
    q1 = np.empty(n)
    for j in range(n):
        qdd1[j] = qdd[j] + (a[j] - qdd[j]) / theta
        qd1[j] = qd[j] + 0.5 * h * (qdd[j] + qdd1[j])
        q1[j] = q[j] + h * qd[j] + h * h * (qdd[j] / 3.0 + qdd1[j] / 6.0)
    # auxiliary integrals: rate at the new end point, trapezoid over the step
    r1 = acc(t + h, q1, qd1, p)
    evals += 1
    if mode == MODE_PC:
        # the paper restarts every step from accelerations evaluated at the corrected state
        # (its step 1); the implicit variants carry the method's own q''_{i+1} (Newmark/Wilson)
        for j in range(n):
            qdd1[j] = r1[j]
    zd1 = np.empty(nz)
    z1 = np.empty(nz)
    for j in range(nz):
        zd1[j] = r1[n + j]
        z1[j] = z[j] + 0.5 * h * (zd[j] + zd1[j])
    if not (_all_finite(q1) and _all_finite(qd1) and _all_finite(r1)):
        return q, qd, qdd, z, zd, evals, FAIL_NONFINITE
    return q1, qd1, qdd1, z1, zd1, evals, FAIL_OK


@nb.njit(cache=True)
def la_step(acc, t, q, qd, qdd, z, zd, p, h, theta, mode, tol, max_iter):
    """`wilson_step` over h; where Newton's iteration does not converge, the same interval as
    2, 4, … 2^MAX_CUTS equal steps from the same start. Returns (q1, qd1, qdd1, z1, zd1, evals,
    steps, code)."""
    evals = 0
    cuts = MAX_CUTS if mode == MODE_NEWTON else 0
    for cut in range(cuts + 1):
        m = 2 ** cut
        hs = h / m
        q1, qd1, qdd1, z1, zd1 = q, qd, qdd, z, zd
        code = FAIL_OK
        for k in range(m):
            q1, qd1, qdd1, z1, zd1, ev, code = wilson_step(acc, t + k * hs, q1, qd1, qdd1, z1,
                                                           zd1, p, hs, theta, mode, tol,
                                                           max_iter)
            evals += ev
            if code != FAIL_OK:
                break
        if code != FAIL_NO_CONVERGENCE:
            return q1, qd1, qdd1, z1, zd1, evals, m, code
    return q, qd, qdd, z, zd, evals, 2 ** cuts, FAIL_NO_CONVERGENCE


@nb.njit(nt.Tuple((_MAT, nt.int64, nt.int64, nt.float64, nt.int64))(
    ACC, GUARD, _VEC, nt.int64, _VEC, _VEC, nt.int64, nt.float64, nt.int64, nt.float64,
    nt.int64), cache=True)
def integrate_wilson(acc, guard, y0, n, p, t_out, substeps, theta, mode, tol, max_iter):
    """Fixed step h = (t_out[i+1] − t_out[i]) / substeps; y = [q (n), q' (n), z].

    guard(t, y, p) as in the explicit drivers. Returns (Y, steps, rhs_evals, t_fail, code)."""
    n_out, ny = t_out.shape[0], y0.shape[0]
    Y = np.full((n_out, ny), np.nan)
    Y[0] = y0
    q = y0[:n].copy()
    qd = y0[n:2 * n].copy()
    z = y0[2 * n:].copy()
    r0 = acc(t_out[0], q, qd, p)
    qdd = r0[:n].copy()
    zd = r0[n:].copy()
    evals = 1
    steps = 0
    y = np.empty(ny)
    if not _all_finite(r0):
        return Y, steps, evals, t_out[0], FAIL_NONFINITE
    for i in range(n_out - 1):
        h = (t_out[i + 1] - t_out[i]) / substeps
        for k in range(substeps):
            t = t_out[i] + k * h
            q, qd, qdd, z, zd, ev, taken, code = la_step(acc, t, q, qd, qdd, z, zd, p, h,
                                                         theta, mode, tol, max_iter)
            evals += ev
            steps += taken
            if code != FAIL_OK:
                return Y, steps, evals, t + h, code
            y[:n] = q
            y[n:2 * n] = qd
            y[2 * n:] = z
            code = guard(t + h, y, p)
            if code != 0:
                return Y, steps, evals, t + h, code
        Y[i + 1, :n] = q
        Y[i + 1, n:2 * n] = qd
        Y[i + 1, 2 * n:] = z
    return Y, steps, evals, np.nan, FAIL_OK


def steps_per_output(t_out: np.ndarray, dt: float) -> int:
    """Whole steps per output interval: dt rounded down onto a divisor of the output step."""
    dt_out = t_out[1] - t_out[0]
    if not dt or not dt > 0.0:
        raise ValueError(f"dt must be > 0, got {dt!r}")
    n = dt_out / dt
    return max(1, int(round(n)) if abs(n - round(n)) < 1e-6 * n else int(math.ceil(n)))


def la_args(s: dict) -> tuple:
    """(θ, iteration mode) of the settings' linear-acceleration variant."""
    theta, mode = LA_INTEGRATORS[s["integrator"]]
    return (float(s["theta"]) if theta is None else theta), mode
