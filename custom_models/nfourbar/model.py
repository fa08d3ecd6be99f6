"""The N four-bar mechanism in one minimal coordinate, θ = φ_0 (crank 0's angle): the press
paper's Lagrange method as generalised for Andrews' squeezer and Bricard's loop. The dependent
coordinates q = (φ_0 … φ_N, ψ_0 … ψ_{N−1}) (cranks from +x, coupler k from B_k to B_{k+1})
come from the loops' closure, loop by loop (given φ_k, Newton on φ_{k+1}, ψ_k of

    cos φ_k + cos ψ_k − 1 − cos φ_{k+1} = 0,   sin φ_k + sin ψ_k − sin φ_{k+1} = 0

in units of L; its Jacobian's determinant is sin(φ_{k+1} − ψ_k), zero on the mechanism where
φ = 0 or π: the singular positions; solved in half-angle form, see `close`), each closure
started from the first-order predictor along the last solution (kept in `p`, see
`analogues`); the velocity analogue J = dq/dθ and J2 = d²q/dθ² come from the partial systems
at θ ± Δθ by central differences (custom_models/loops.py). Then, as for Bricard's loop,

    A θ'' = −(½ A' θ'² + V'),   A = Σ m|v_c|² + I ω²,   ½ A' = Σ m v_c·a_c + I ω α,

over the 2N + 1 rods for q' = J, q'' = J2 (planar: I = m L²/12 about each centre). One
compiled `acc(t, q, q', p)` serves the shared linear-acceleration driver.
"""
import math

import numba as nb
import numpy as np

from .. import loops

NAMES = ("m", "L", "g", "N")
NP = len(NAMES)
M, LEN, G, NN = range(NP)
DTHETA, CLOSURE_TOL, FLAG, THETA_PREV, WARM = NP, NP + 1, NP + 2, NP + 3, NP + 4
# p[WARM:WARM + 2N]: the last dependent coordinates; p[WARM + 2N:]: their rates J there
FAIL_CLOSURE = 10
MAX_NEWTON = 30


def pack(params: dict, dtheta: float, closure_tol: float) -> np.ndarray:
    n = int(params["N"])
    p = np.zeros(WARM + 4 * n)
    p[:NP] = [float(params["m"]), float(params["L"]), float(params["g"]), n]
    p[DTHETA], p[CLOSURE_TOL] = dtheta, closure_tol
    reset(p, float(params["phi0"]), initial_warm(params))
    return p


def reset(p: np.ndarray, theta: float, warm: np.ndarray):
    """The warm start at θ: the dependent coordinates `warm`, no predictor (J unknown)."""
    n = int(p[NN])
    p[THETA_PREV] = theta
    p[WARM:WARM + 2 * n] = warm
    p[WARM + 2 * n:] = 0.0


def initial_warm(params: dict) -> np.ndarray:
    """The dependent coordinates at the start: the parallelogram (every crank at φ0, couplers
    level)."""
    n = int(params["N"])
    return np.concatenate([np.full(n, float(params["phi0"])), np.zeros(n)])


@nb.njit(cache=True)
def close(theta, guess, p, tol, max_iter):
    """q = (φ_0 … φ_N, ψ_0 … ψ_{N−1}) with every loop closed, from φ_0 = θ and the dependent
    coordinates' guess (φ_1 … φ_N, ψ_0 … ψ_{N−1}); (q, ok)."""
    n = int(p[NN])
    q = np.empty(2 * n + 1)
    q[0] = theta
    q[1:] = guess
    for k in range(n):
        a = q[k]
        d, y = q[k + 1] - a, q[n + 1 + k]
        done = False
        for _ in range(max_iter):
            # the closure in half-angle form, in d = φ_{k+1} − φ_k: each term vanishes with
            # its own factor, so the residual carries no rounding of order 1 (no cos a − cos x
            # cancellation) and the parallelogram (d = ψ = 0) is resolved exactly even where
            # the Jacobian's determinant sin(φ_{k+1} − ψ_k) → 0
            sh, sm, cm = math.sin(0.5 * d), math.sin(a + 0.5 * d), math.cos(a + 0.5 * d)
            r1 = 2.0 * sm * sh - 2.0 * math.sin(0.5 * y) ** 2
            r2 = -2.0 * cm * sh + math.sin(y)
            if r1 == 0.0 and r2 == 0.0:
                done = True
                break
            x = a + d
            cx, sx, cy, sy = math.cos(x), math.sin(x), math.cos(y), math.sin(y)
            det = sx * cy - cx * sy
            if not (det != 0.0 and math.isfinite(det)):
                return q, False
            # [sx, −sy; −cx, cy] [dd, dy] = −[r1, r2]
            dd = (-r1 * cy - sy * r2) / det
            dy = (-sx * r2 - cx * r1) / det
            d += dd
            y += dy
            if not (math.isfinite(d) and math.isfinite(y)):
                return q, False
            if max(abs(dd), abs(dy)) <= tol:
                done = True
                break
        if not done:
            return q, False
        q[k + 1], q[n + 1 + k] = a + d, y
    return q, True


@nb.njit(cache=True)
def analogues(theta, p):
    """q(θ), J, J2 from the partial systems at θ, θ ± Δθ; ok flag. Each closure starts from
    the first-order predictor along the last solution (q_last + J_last·(θ − θ_last)): at a
    singular position the other branch passes within |θ − θ_sing| of the mechanism's own, and
    the predictor's error (O(Δθ²)) stays below that where a plain warm start (O(Δθ)) would not."""
    n = int(p[NN])
    h, tol = p[DTHETA], p[CLOSURE_TOL]
    last, rate = p[WARM:WARM + 2 * n], p[WARM + 2 * n:WARM + 4 * n]
    q0, ok0 = close(theta, last + rate * (theta - p[THETA_PREV]), p, tol, MAX_NEWTON)
    qp, okp = close(theta + h, q0[1:] + rate * h, p, tol, MAX_NEWTON)
    qm, okm = close(theta - h, q0[1:] - rate * h, p, tol, MAX_NEWTON)
    J, J2 = loops.partial_systems(q0, qp, qm, h)
    return q0, J, J2, ok0 and okp and okm


@nb.njit(cache=True)
def remember(theta, q, J, p):
    n = int(p[NN])
    p[THETA_PREV] = theta
    p[WARM:WARM + 2 * n] = q[1:]
    p[WARM + 2 * n:WARM + 4 * n] = J[1:]


@nb.njit(cache=True)
def accel(q, J, J2, rate, p):
    """θ'' of the minimal form from q(θ), J and J2 (Lagrange's equation, as above)."""
    m, L, g, n = p[M], p[LEN], p[G], int(p[NN])
    inertia = m * L * L / 12.0
    A, h, dV = 0.0, 0.0, 0.0
    for k in range(n + 1):                 # crank k about its pin: centre at L/2 (cos, sin) φ
        c, s = math.cos(q[k]), math.sin(q[k])
        w, al = J[k], J2[k]
        vx, vy = -0.5 * L * s * w, 0.5 * L * c * w
        ax = 0.5 * L * (-s * al - c * w * w)
        ay = 0.5 * L * (c * al - s * w * w)
        A += m * (vx * vx + vy * vy) + inertia * w * w
        h += m * (vx * ax + vy * ay) + inertia * w * al
        dV += m * g * vy
    for k in range(n):                     # coupler k: centre B_k + L/2 (cos, sin) ψ_k
        c, s = math.cos(q[k]), math.sin(q[k])
        w, al = J[k], J2[k]
        cp, sp = math.cos(q[n + 1 + k]), math.sin(q[n + 1 + k])
        wp, alp = J[n + 1 + k], J2[n + 1 + k]
        vx = -L * s * w - 0.5 * L * sp * wp
        vy = L * c * w + 0.5 * L * cp * wp
        ax = L * (-s * al - c * w * w) + 0.5 * L * (-sp * alp - cp * wp * wp)
        ay = L * (c * al - s * w * w) + 0.5 * L * (cp * alp - sp * wp * wp)
        A += m * (vx * vx + vy * vy) + inertia * wp * wp
        h += m * (vx * ax + vy * ay) + inertia * wp * alp
        dV += m * g * vy
    return -(h * rate * rate + dV) / A


@nb.njit(cache=True)
def acc(t, q, qd, p):
    """[θ''] of the minimal form (NaN and FLAG set where a loop does not close)."""
    out = np.empty(1)
    qf, J, J2, ok = analogues(q[0], p)
    if not ok:
        p[FLAG] = FAIL_CLOSURE
        out[0] = np.nan
        return out
    remember(q[0], qf, J, p)
    out[0] = accel(qf, J, J2, qd[0], p)
    return out


@nb.njit(cache=True)
def guard(t, y, p):
    return int(p[FLAG])


def full_state(Y: np.ndarray, p: np.ndarray, theta0: float, warm: np.ndarray):
    """The 2N + 1 coordinates and rates (q(θ), J θ') of each row of [θ, θ'] (NaN rows kept),
    followed from the start (θ0, warm) along the run's branch with the same predictor."""
    reset(p, theta0, warm)
    n_q = 2 * int(p[NN]) + 1
    Q, QD = np.full((len(Y), n_q), np.nan), np.full((len(Y), n_q), np.nan)
    for i in range(len(Y)):
        if np.isfinite(Y[i, 0]) and np.isfinite(Y[i, 1]):
            qf, J, _, ok = analogues(Y[i, 0], p)
            if ok:
                remember(Y[i, 0], qf, J, p)
                Q[i], QD[i] = qf, J * Y[i, 1]
    return Q, QD
