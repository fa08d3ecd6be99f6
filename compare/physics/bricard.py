"""Bricard's mechanism (scene `bricard`; IFToMM Library of Computational Benchmark Problems,
problem A04, González, Dopico, Lugrís & Cuadrado 2006): five identical uniform rods (mass m,
length L, square cross-section of side a; a = 0: thin rods) joined end to end by six revolute
joints in a closed loop whose two end joints are on the ground, under gravity g along −y,
released at rest. The Grübler count gives zero degrees
of freedom; the joint axes (each rod's two axes perpendicular to it and to each other, the
trihedral Bricard linkage) leave one. Everything every solver of the scene computes alike lives
here: the geometry, the kinematics in joint angles (screw theory: product of exponentials), the
energy, and the reference integration. Numpy and numba only (leaves import it).

Geometry at the start (all joint angles 0), the library's: joint k at P_k with axis s_k,
P0 = (0, 0, 0) s0 = y, P1 = (L, 0, 0) s1 = z, P2 = (L, −L, 0) s2 = x, P3 = (L, −L, L) s3 = y,
P4 = (0, −L, L) s4 = z, P5 = (0, 0, L) s5 = x; rod k (1…5) runs from P_{k−1} to P_k, joints 0
and 5 are to the ground. Rod k's pose is g_k = exp(ξ̂0 q0)…exp(ξ̂_{k−1} q_{k−1}); the loop
closes where g_6 = I (six equations, rank five on the mechanism's curve).
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np

from ..contract import Channel
from .rotation import axis_rotation

# the library's values: rod mass (kg), rod length (m), gravity (m/s², along −y), side of the
# rods' square cross-section (m)
PARAMS = (("m", 1.0), ("L", 1.0), ("g", 9.81), ("a", 0.1))
NAMES = tuple(n for n, _ in PARAMS)
M, LEN, G, SIDE = range(4)
T_END = 10.0
CHANNELS = (Channel("p3_x", "m"), Channel("p3_y", "m"), Channel("p3_z", "m"),
            Channel("theta1", "rad"), Channel("energy_balance", "J"),
            Channel("kinetic_energy", "J"))
# the joints at the start in units of L, and their axes
POINTS = np.array([[0, 0, 0], [1, 0, 0], [1, -1, 0], [1, -1, 1], [0, -1, 1], [0, 0, 1]], float)
AXES = np.array([[0, 1, 0], [0, 0, 1], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 0, 0]], float)


def pack(params: dict) -> np.ndarray:
    return np.array([float(params[n]) for n in NAMES])


@nb.njit(cache=True)
def forward(q, p):
    """(X, Rs, ts): X[j] = the joint j's twist (ω, v) in space at angles q (v = p × ω for the
    axis through p), and the poses g_k = (Rs[k], ts[k]) of ground (k = 0), the rods (1…5) and
    the loop's end (6, the identity where the loop closes)."""
    L = p[LEN]
    X = np.zeros((6, 6))
    Rs = np.zeros((7, 3, 3))
    ts = np.zeros((7, 3))
    R = np.eye(3)
    t = np.zeros(3)
    Rs[0] = R
    for j in range(6):
        s = AXES[j]
        pj = POINTS[j] * L
        w = R @ s
        x = R @ pj + t
        X[j, :3] = w
        X[j, 3:] = np.cross(x, w)
        Rj = axis_rotation(s, q[j])
        t = R @ (pj - Rj @ pj) + t
        R = R @ Rj
        Rs[j + 1] = R
        ts[j + 1] = t
    return X, Rs, ts


@nb.njit(cache=True)
def closure(q, p):
    """The loop's end pose as a 6-vector (skew part of R, translation): zero where it closes;
    its derivative along joint j is the twist X[j] (the end moves by exp(Σ ξ'_j dq_j))."""
    _, Rs, ts = forward(q, p)
    return _end_residual(Rs[6], ts[6])


@nb.njit(cache=True)
def _end_residual(R, t):
    r = np.empty(6)
    r[0] = 0.5 * (R[2, 1] - R[1, 2])
    r[1] = 0.5 * (R[0, 2] - R[2, 0])
    r[2] = 0.5 * (R[1, 0] - R[0, 1])
    r[3:] = t
    return r


@nb.njit(cache=True)
def _lstsq5(B, r):
    """x minimising |B x − r| for B (6×5) of full rank (normal equations; the systems here are
    consistent, so the residual is the closure's own)."""
    return np.linalg.solve(B.T @ B, B.T @ r)


@nb.njit(cache=True)
def close(q0, guess, p, tol, max_iter):
    """q = (q0, s) with the loop closed by Gauss–Newton on the five dependent angles from s =
    guess; (q, ok)."""
    q = np.empty(6)
    q[0] = q0
    q[1:] = guess
    for _ in range(max_iter):
        X, Rs, ts = forward(q, p)
        dx = _lstsq5(np.ascontiguousarray(X[1:].T), -_end_residual(Rs[6], ts[6]))
        big = 0.0
        for k in range(5):
            if not math.isfinite(dx[k]):
                return q, False
            q[k + 1] += dx[k]
            big = max(big, abs(dx[k]))
        if big <= tol:
            return q, True
    return q, False


@nb.njit(cache=True)
def _ad(a, b):
    """The Lie bracket of twists (ω, v): (ωa × ωb, ωa × vb + va × ωb)."""
    out = np.empty(6)
    out[:3] = np.cross(a[:3], b[:3])
    out[3:] = np.cross(a[:3], b[3:]) + np.cross(a[3:], b[:3])
    return out


@nb.njit(cache=True)
def rod_motion(q, qd, qdd, p):
    """Each rod's centre c, its velocity and angular velocity, their accelerations, and the
    loop end's twist and its rate (both zero for rates on the mechanism): arrays (5, 3) ×5,
    (6,), (6,). Spatial twists: V_k = Σ_{j<k} ξ'_j q'_j,
    V'_k = Σ_{j<k} (ξ'_j q''_j + [V_j, ξ'_j] q'_j)."""
    X, Rs, ts = forward(q, p)
    return _rod_motion(X, Rs, ts, qd, qdd, p)


@nb.njit(cache=True)
def _rod_motion(X, Rs, ts, qd, qdd, p):
    L = p[LEN]
    c = np.zeros((5, 3))
    v = np.zeros((5, 3))
    w = np.zeros((5, 3))
    a = np.zeros((5, 3))
    al = np.zeros((5, 3))
    V = np.zeros(6)
    A = np.zeros(6)
    for j in range(6):
        A = A + X[j] * qdd[j] + _ad(V, X[j]) * qd[j]
        V = V + X[j] * qd[j]
        if j < 5:
            mid = 0.5 * (POINTS[j] + POINTS[j + 1]) * L
            cj = Rs[j + 1] @ mid + ts[j + 1]
            c[j] = cj
            w[j] = V[:3]
            v[j] = V[3:] + np.cross(V[:3], cj)
            al[j] = A[:3]
            a[j] = A[3:] + np.cross(A[:3], cj) + np.cross(V[:3], v[j])
    return c, v, w, a, al, V, A


@nb.njit(cache=True)
def inertia(q, p):
    """Each rod's inertia tensor about its centre in space (d its axis): a uniform square prism
    of side a, m (L² + a²)/12 (I − d dᵀ) + m a²/6 d dᵀ (the square's transverse moments are
    equal, so the section's turn about d does not matter); a = 0: the thin rod."""
    _, Rs, _ = forward(q, p)
    return _inertia(Rs, p)


@nb.njit(cache=True)
def _inertia(Rs, p):
    out = np.zeros((5, 3, 3))
    it, ia = principal_inertia(p)
    for j in range(5):
        d = Rs[j + 1] @ (POINTS[j + 1] - POINTS[j])
        out[j] = it * (np.eye(3) - np.outer(d, d)) + ia * np.outer(d, d)
    return out


@nb.njit(cache=True)
def principal_inertia(p):
    """(transverse, axial) moments of a rod about its centre: m (L² + a²)/12, m (a² + a²)/12."""
    a2 = p[SIDE] * p[SIDE]
    return p[M] * (p[LEN] ** 2 + a2) / 12.0, p[M] * a2 / 6.0


@nb.njit(cache=True)
def energy(q, qd, p):
    """(kinetic, potential m g Σ y_c) in J at angles q and rates qd (the rods need q0…q4)."""
    c, v, w, _, _, _, _ = rod_motion(q, qd, np.zeros(6), p)
    Iw = inertia(q, p)
    T, V = 0.0, 0.0
    for j in range(5):
        T += 0.5 * (p[M] * (v[j] @ v[j]) + w[j] @ (Iw[j] @ w[j]))
        V += p[M] * p[G] * c[j, 1]
    return T, V


@nb.njit(cache=True)
def accel(q, J, J2, rate, p):
    """θ'' of the minimal form in θ = q0 from q(θ), J = dq/dθ, J2 = d²q/dθ²: Lagrange's
    A θ'' + ½ A'(θ) θ'² + V'(θ) = 0 with A = Σ m|v_c|² + ωᵀIω per unit θ' and ½ A' =
    Σ (m v_c·a_c + ω·Iα) for q' = J, q'' = J2 (ωᵀ İ ω = 0), V' = m g Σ v_c,y."""
    X, Rs, ts = forward(q, p)
    _, v, w, a, al, _, _ = _rod_motion(X, Rs, ts, J, J2, p)
    Iw = _inertia(Rs, p)
    A, h, dV = 0.0, 0.0, 0.0
    for j in range(5):
        A += p[M] * (v[j] @ v[j]) + w[j] @ (Iw[j] @ w[j])
        h += p[M] * (v[j] @ a[j]) + w[j] @ (Iw[j] @ al[j])
        dV += p[M] * p[G] * v[j, 1]
    return -(h * rate * rate + dV) / A


@nb.njit(cache=True)
def analogues_exact(q, p):
    """J = dq/dθ and J2 = d²q/dθ² on the mechanism exactly: Σ ξ'_j J_j = 0 with J_0 = 1, and
    Σ ξ'_j J2_j + (the bracket terms of the acceleration at q' = J) = 0 with J2_0 = 0."""
    X, _, _ = forward(q, p)
    B = np.ascontiguousarray(X[1:].T)
    J = np.zeros(6)
    J[0] = 1.0
    J[1:] = _lstsq5(B, -X[0])
    _, _, _, _, _, _, A = rod_motion(q, J, np.zeros(6), p)
    J2 = np.zeros(6)
    J2[1:] = _lstsq5(B, -A)
    return J, J2


@nb.njit(cache=True)
def point3(q, p):
    """P3 (the joint between rods 3 and 4) in space."""
    _, Rs, ts = forward(q, p)
    return Rs[3] @ (POINTS[3] * p[LEN]) + ts[3]


def channels(Q, QD, p) -> dict:
    """The scene's channels from joint angles Q (n, ≥5) and rates QD (n, ≥5): P3, θ1 = q0, the
    energy balance T + V − E₀ (zero for an exact solution: no work is done on the loop) and T."""
    Q, QD = np.asarray(Q, float), np.asarray(QD, float)
    n = len(Q)
    P3 = np.full((n, 3), np.nan)
    T, V = np.full(n, np.nan), np.full(n, np.nan)
    for i in range(n):
        if np.all(np.isfinite(Q[i, :5])) and np.all(np.isfinite(QD[i, :5])):
            q = np.zeros(6)
            qd = np.zeros(6)
            q[:5], qd[:5] = Q[i, :5], QD[i, :5]
            P3[i] = point3(q, p)
            T[i], V[i] = energy(q, qd, p)
    return {"p3_x": P3[:, 0], "p3_y": P3[:, 1], "p3_z": P3[:, 2], "theta1": Q[:, 0].copy(),
            "energy_balance": T + V - (T[0] + V[0]), "kinetic_energy": T}


def reference(params: dict, t_out, rtol: float = 1e-12, atol: float = 1e-12,
              method: str = "DOP853", events=None):
    """The reference integration in the one minimal coordinate θ = q0 (at rest at θ = 0): the
    loop closed by Gauss–Newton at each evaluation, J and J2 exact (analogues_exact), scipy's
    `method` at rtol; `events` (functions of (t, [θ, θ'])) passed to scipy. Returns (Q (n, 6),
    QD (n, 6), scipy's result)."""
    from scipy.integrate import solve_ivp
    p = pack(params)
    warm = [np.zeros(5)]

    def state(theta):
        q, ok = close(float(theta), warm[0], p, 1e-15, 50)
        if not ok:
            raise ValueError(f"the loop does not close at theta1 = {theta:.6g} rad")
        warm[0] = q[1:].copy()
        return q

    def rhs(t, y):
        q = state(y[0])
        J, J2 = analogues_exact(q, p)
        return np.array([y[1], accel(q, J, J2, y[1], p)])

    t_out = np.asarray(t_out, float)
    sol = solve_ivp(rhs, (0.0, float(t_out[-1])), np.zeros(2), method=method, rtol=rtol,
                    atol=atol, t_eval=t_out, events=events)
    n = len(sol.t)
    Q, QD = np.zeros((n, 6)), np.zeros((n, 6))
    warm[0] = np.zeros(5)
    for i in range(n):
        Q[i] = state(sol.y[0, i])
        QD[i] = analogues_exact(Q[i], p)[0] * sol.y[1, i]
    return Q, QD, sol
