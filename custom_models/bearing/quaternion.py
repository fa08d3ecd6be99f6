"""`quaternion` solver of the two-bearing rotor (scene `bearing-rotor`, seed 001): the paper's
Euler equations as a SECOND-ORDER equation for the Rodrigues–Hamilton parameters Λ, plus
Newton's law for the centre of mass. Force laws and observables: compare.physics.bearing_rotor.

The paper (eqs. 6–11, text partly garbled) writes (0, ω_Y) = 2 Λ̃ Λ̇ (6–7) with Λ̃ the matrix of
the conjugate product, differentiates it with the normalisation (3) — the scalar row becomes the
auxiliary M0 = (−2 Σ λ̇ᵢ², 0, 0, 0) — substitutes Euler's equations (2) (the gyroscopic terms
(J_k − J_j) ω_j ω_k are its G[(TΛΛ̇)•(TᵀΛΛ̇)]) and solves with Λ̃⁻¹ = Λ̃ᵀ for |Λ| = 1:
    Λ̈ = Λᵀ J⁻¹ (K P M_X + M0 − G[…])                                        (11)
with the moment M_X in the fixed frame, P = Rᵀ its projection on the body axes (4–5). The
garbled matrices are not copied; the same equation is derived here. With q ≡ Λ (w, x, y, z,
body → fixed) and Ω the body angular velocity, (0, Ω) = 2 q̄∘q̇ / |q|². Differentiating,
    2 q̄∘q̈ = (0, Ω̇)·|q|² − 2 q̄̇∘q̇,   q̄̇∘q̇ = (|q̇|², 0)   (a conjugate pair has no vector part)
so, with J Ω̇ = Rᵀ M − Ω × J Ω (Euler's equations (2)),
    q̈ = q ∘ (−|q̇|², ½ Ω̇) / |q|².
No trigonometric function appears. Its scalar row gives q·q̈ = −|q̇|², i.e. d²|q|²/dt² = 0:
|q|² = 1 and q·q̇ = 0 are first integrals (the paper's (3)), kept by the exact flow only —
numerically |q| drifts (reported as `invariants["quaternion_norm"]`, the largest | |q| − 1 | over
every accepted step). tests/physics/test_bearing_rotor.py checks this q̈ against the first-order
q̇ = ½ q∘Ω (= ½ ω∘q in the fixed frame).

Setting `project` (default False): after each accepted step q ← q/|q| and the radial part of q̇
is removed (q̇ ← q̇ − (q·q̇) q). The shared drivers call the guard on the accepted state after
every step; the projection runs there (the adaptive driver's first-same-as-last derivative of
the next step is then the one of the unprojected state, an O(h·correction) effect).
"""
from __future__ import annotations

import numba as nb
import numpy as np

from compare.contract import LeafResult, check_once, merge_settings
from compare.physics import bearing_rotor as phys
from compare.physics.rotation import (
    cross_t,
    mat_tvec_t,
    quat_matrix_t,
    quat_times_vector,
    quat_times_vector_t,
)

from ..integrators import FAIL_REASONS, FIXED_TABLEAUS
from ..integrators.dense import DENSE_TABLEAUS, solve

INTEGRATORS = tuple(DENSE_TABLEAUS) + tuple(FIXED_TABLEAUS)
ADAPTIVE = tuple(DENSE_TABLEAUS)
# atol defaults to rtol/100 (journal offsets ~3e-5 m sit well above it). h_max defaults to the
# output step although dense output fills the grid without it: uncapped, DOP853 takes ~45 % fewer
# steps at rtol 1e-10 but the spin rate moves by 1.5e-9 relative (8× the golden's tolerance) and
# the norm drift |q| − 1 grows from 4e-14 to 5e-10 over 0.5 s; h_max=inf lifts the cap.
DEFAULT_SETTINGS = {"integrator": "dop853", "rtol": 1e-10, "atol": None, "dt": None,
                    "h_max": None, "max_steps": 10**8, "project": False}
DEFAULT_FIXED_DT = 1e-5       # rk4: the rocking mode (~1000 rad/s) and the 1.4 ms bump
AUTO_DT = {name: DEFAULT_FIXED_DT for name in FIXED_TABLEAUS}     # dt="auto"

# state layout
R_, V_, Q_, QD_, W_, D_, NORM_ = (slice(0, 3), slice(3, 6), slice(6, 10), slice(10, 14),
                                  14, 15, 16)
NY = 17
# extra entries after the physics parameters in p
P_PROJECT, P_BOUND = phys.N_PACK, phys.N_PACK + 1

FAIL_BOUND, FAIL_NORM = 20, 21
NORM_LIMIT = 1e-3     # |q| drifted this far from 1: the first integral is lost
REASONS = {**FAIL_REASONS,
           FAIL_BOUND: "a journal left its bearing (radial offset > l/10)",
           FAIL_NORM: f"quaternion norm drifted by more than {NORM_LIMIT:g} (first integral "
                      "lost: use project=True or a tighter step)"}
STATUS = {1: "diverged", 2: "unstable", 3: "unstable", FAIL_BOUND: "diverged",
          FAIL_NORM: "unstable"}


@nb.njit(cache=True)
def body_rate_t(w, x, y, z, dw, dx, dy, dz):
    """Ω = 2 vec(q̄∘q̇)/|q|² (body frame), scalars."""
    s = 2.0 / (w * w + x * x + y * y + z * z)
    c = cross_t(x, y, z, dx, dy, dz)
    return s * (w * dx - dw * x - c[0]), s * (w * dy - dw * y - c[1]), s * (w * dz - dw * z - c[2])


@nb.njit(cache=True)
def fixed_rate_t(w, x, y, z, dw, dx, dy, dz):
    """ω = 2 vec(q̇∘q̄)/|q|² (fixed frame), scalars."""
    s = 2.0 / (w * w + x * x + y * y + z * z)
    c = cross_t(x, y, z, dx, dy, dz)
    return s * (w * dx - dw * x + c[0]), s * (w * dy - dw * y + c[1]), s * (w * dz - dw * z + c[2])


@nb.njit(cache=True)
def quaternion_acceleration_t(w, x, y, z, dw, dx, dy, dz, a0, a1, a2):
    """q̈ = q ∘ (−|q̇|², ½ Ω̇) / |q|² for Ω̇ = (a0, a1, a2), scalars."""
    s = 1.0 / (w * w + x * x + y * y + z * z)
    qd2 = dw * dw + dx * dx + dy * dy + dz * dz
    u = quat_times_vector_t(w, x, y, z, 0.5 * a0, 0.5 * a1, 0.5 * a2)
    return (s * (u[0] - qd2 * w), s * (u[1] - qd2 * x), s * (u[2] - qd2 * y),
            s * (u[3] - qd2 * z))


# the same three as arrays (tests, linearisations)
@nb.njit(cache=True)
def body_rate(q, qd):
    return np.array(body_rate_t(q[0], q[1], q[2], q[3], qd[0], qd[1], qd[2], qd[3]))


@nb.njit(cache=True)
def fixed_rate(q, qd):
    return np.array(fixed_rate_t(q[0], q[1], q[2], q[3], qd[0], qd[1], qd[2], qd[3]))


@nb.njit(cache=True)
def quaternion_acceleration(q, qd, omega_body_dot):
    a = omega_body_dot
    return np.array(quaternion_acceleration_t(q[0], q[1], q[2], q[3], qd[0], qd[1], qd[2], qd[3],
                                              a[0], a[1], a[2]))


@nb.njit(cache=True)
def rhs_into(t, y, p, dy):
    """The right-hand side into dy: fused scalar code, no allocation per evaluation."""
    w, x, qy, z = y[6], y[7], y[8], y[9]
    dw, dx, dqy, dz = y[10], y[11], y[12], y[13]
    W = body_rate_t(w, x, qy, z, dw, dx, dqy, dz)
    om = fixed_rate_t(w, x, qy, z, dw, dx, dqy, dz)
    L = phys.loads_t(y[0], y[1], y[2], w, x, qy, z, y[3], y[4], y[5], om[0], om[1], om[2], p)
    mb = mat_tvec_t(quat_matrix_t(w, x, qy, z), L[3], L[4], L[5])
    # Euler's equations in body axes, J = diag(J_t, J_t, J_p): J Ω̇ = Rᵀ M − Ω × J Ω
    jt, jp = p[phys.I_JT], p[phys.I_JP]
    g = cross_t(W[0], W[1], W[2], jt * W[0], jt * W[1], jp * W[2])
    qdd = quaternion_acceleration_t(w, x, qy, z, dw, dx, dqy, dz, (mb[0] - g[0]) / jt,
                                    (mb[1] - g[1]) / jt, (mb[2] - g[2]) / jp)
    m = p[phys.I_M]
    for i in range(3):
        dy[i] = y[3 + i]
        dy[3 + i] = L[i] / m + p[phys.I_GX + i]
    for i in range(4):
        dy[6 + i] = y[10 + i]
        dy[10 + i] = qdd[i]
    dy[W_] = L[6]
    dy[D_] = L[7]
    dy[NORM_] = 0.0


@nb.njit(cache=True)
def rhs(t, y, p):
    """The right-hand side as a new array (tests)."""
    dy = np.empty(NY)
    rhs_into(t, y, p, dy)
    return dy


@nb.njit(cache=True)
def guard(t, y, p):
    """Track the norm drift, project if asked, stop on a lost first integral or a journal out
    of its bearing. Runs on the accepted state after every step (and may change it)."""
    qq = y[6] ** 2 + y[7] ** 2 + y[8] ** 2 + y[9] ** 2
    drift = abs(np.sqrt(qq) - 1.0)
    y[NORM_] = max(y[NORM_], drift)
    if p[P_PROJECT] != 0.0:
        s = 1.0 / np.sqrt(qq)
        radial = 0.0
        for i in range(6, 10):
            y[i] *= s
            radial += y[i] * y[i + 4]
        for i in range(6, 10):
            y[i + 4] -= radial * y[i]
    elif drift > NORM_LIMIT:
        return FAIL_NORM
    # journal offsets: centre ± (l/2) e3, e3 = third column of R(q)
    s = 1.0 / np.sqrt(y[6] ** 2 + y[7] ** 2 + y[8] ** 2 + y[9] ** 2)
    w, x, yy, z = y[6] * s, y[7] * s, y[8] * s, y[9] * s
    half = 0.5 * p[phys.I_L]
    ex, ey = 2 * (x * z + w * yy), 2 * (yy * z - w * x)
    for sgn in (1.0, -1.0):
        dx, dy = y[0] + sgn * half * ex, y[1] + sgn * half * ey
        if dx * dx + dy * dy > p[P_BOUND] ** 2:
            return FAIL_BOUND
    return 0


@check_once
def check_settings(settings: dict | None, t_out: np.ndarray | None = None) -> dict:
    """The settings merged and checked before anything runs (ValueError, one line)."""
    s = merge_settings(settings, DEFAULT_SETTINGS, INTEGRATORS)
    if s["dt"] == "auto":
        s["dt"] = AUTO_DT.get(s["integrator"], DEFAULT_FIXED_DT)
    if isinstance(s["project"], str):
        if s["project"].lower() not in ("true", "false", "1", "0"):
            raise ValueError(f"project={s['project']!r}: use true or false")
        s["project"] = s["project"].lower() in ("true", "1")
    s["project"] = bool(s["project"])
    dt = s["dt"]
    if dt is not None and not (isinstance(dt, (int, float)) and np.isfinite(dt) and dt > 0):
        raise ValueError(f"dt must be a positive number, got {dt!r}")
    return s


def initial_state(params: dict) -> np.ndarray:
    r, q, v, omega = phys.initial_state(params)
    y = np.zeros(NY)
    y[R_], y[V_], y[Q_] = r, v, q
    y[QD_] = 0.5 * quat_times_vector(q, phys.quat_matrix(q).T @ omega)   # ½ q∘(0, Ω_body)
    return y


def simulate(params: dict, t_out: np.ndarray, settings: dict) -> LeafResult:
    s = check_settings(settings, t_out)
    t_out = np.ascontiguousarray(t_out, float)
    p = np.concatenate([phys.pack(params), [float(s["project"]), 0.1 * params["l"]]])
    y0 = initial_state(params)
    Y, stats, t_fail, code, used = solve(
        rhs_into, guard, y0, p, t_out, s["integrator"], dt=s["dt"] or DEFAULT_FIXED_DT,
        rtol=float(s["rtol"]), atol=s["atol"], h_max=s["h_max"] or t_out[1] - t_out[0],
        max_steps=int(s["max_steps"]))
    used["project"] = s["project"]
    return _result(params, t_out, Y, stats, used, code, t_fail)


def _result(params, t_out, Y, stats, used, code, t_fail) -> LeafResult:
    n = len(t_out)
    ok = np.isfinite(Y).all(axis=1)
    Yk = Y[ok]
    q, qd = Yk[:, Q_], Yk[:, QD_]
    qq = np.einsum("ij,ij->i", q, q)[:, None]
    omega = 2.0 * (q[:, :1] * qd[:, 1:] - qd[:, :1] * q[:, 1:]
                   + np.cross(q[:, 1:], qd[:, 1:])) / qq
    ch_ok = phys.channels(params, t_out[ok], Yk[:, R_], Yk[:, V_], q, omega, Yk[:, W_],
                          Yk[:, D_])
    channels = {}
    for k, v in ch_ok.items():
        channels[k] = np.full(n, np.nan)
        channels[k][ok] = v
    orientation = np.full((n, 4), np.nan)
    orientation[ok] = q / np.sqrt(qq)
    journal_a, journal_b = np.full((n, 3), np.nan), np.full((n, 3), np.nan)
    journal_a[ok], journal_b[ok] = phys.journal_positions(params, Yk[:, R_], q)
    status = "ok" if code == 0 else STATUS.get(code, "diverged")
    return LeafResult(
        channels=channels, status=status,
        t_fail=None if code == 0 else float(t_fail),
        reason=None if code == 0 else REASONS.get(code, f"failure code {code}"),
        stats=stats, settings=used,
        extra={"orientation": orientation, "journal_a": journal_a, "journal_b": journal_b},
        invariants={"quaternion_norm": float(np.max(Yk[:, NORM_])) if len(Yk) else np.nan})


# ------------------------------------------------------------------ linearisation (xval modes)
# Finite-difference steps of the linearisation, per coordinate of η (below): 4th-order central
# differences at these steps agree with steps 10× smaller and larger to ~1e-12 of every root
# (conical roots at steps 10× larger moved by 6e-5 with 2nd-order differences: the rotation
# kinematics is not quadratic); positions enter linearly (their step only sets round-off).
FD_STEPS = np.repeat([1e-6, 1e-6, 1e-4, 1e-3], 3)      # m, rad, m/s, rad/s


def _qmul(a, b):
    return np.concatenate([[a[0] * b[0] - a[1:] @ b[1:]],
                           a[0] * b[1:] + b[0] * a[1:] + np.cross(a[1:], b[1:])])


def _eta_rate(eta, p, spin, r0):
    """η̇ of the fixed-frame perturbation η = (δr, θ, δv, δω) about the steady spin, through
    this solver's right-hand side: the state is q = exp(θ/2) (q_ref = 1 at t = 0), q̇ = ½ (0, ω)∘q
    with ω = Ω e_z + δω; back from q̈ by θ̇ = 2 vec(q̇ − ½ q∘(0, Ω e_z)) (q_ref moves at ½ Ω e_z)
    and ω̇ = 2 vec(q̈∘q̄) (|q| = 1, q·q̇ = 0), both to first order in η."""
    th = eta[3:6]
    a = np.linalg.norm(th)
    q = np.concatenate([[np.cos(0.5 * a)], (np.sin(0.5 * a) / a if a > 0 else 0.5) * th])
    y = np.zeros(NY)
    y[R_], y[V_], y[Q_] = r0 + eta[0:3], eta[6:9], q
    y[QD_] = 0.5 * _qmul(np.concatenate([[0.0], [0.0, 0.0, spin] + eta[9:12]]), q)
    dy = rhs(0.0, y, p)
    theta_rate = 2.0 * (y[QD_] - 0.5 * _qmul(q, np.array([0.0, 0.0, 0.0, spin])))[1:]
    omega_rate = 2.0 * _qmul(dy[QD_], q * np.array([1.0, -1.0, -1.0, -1.0]))[1:]
    return np.concatenate([eta[6:9], theta_rate, dy[V_], omega_rate])


def linearise(params: dict, steps: np.ndarray = FD_STEPS) -> np.ndarray:
    """A (12 × 12) of η̇ = A η about the steady spin (defect-free), by 4th-order central
    differences of the right-hand side along each coordinate of η."""
    p = np.concatenate([phys.pack({**params, "defect_height": 0.0}), [0.0, 0.1 * params["l"]]])
    spin, r0 = phys.steady_spin_rate(params), phys.static_sag(params)
    A = np.empty((12, 12))
    for j in range(12):
        d = np.zeros(12)
        d[j] = steps[j]
        f = [_eta_rate(k * d, p, spin, r0) for k in (2, 1, -1, -2)]
        A[:, j] = (-f[0] + 8 * f[1] - 8 * f[2] + f[3]) / (12 * steps[j])
    return A


def modes(params: dict, settings: dict | None = None):
    """Damped modes about the steady spin from this solver's own right-hand side (the paper's
    second-order quaternion equation), its error estimate from the linearisation at half the
    steps."""
    return phys.modes_result(linearise(params), linearise(params, 0.5 * FD_STEPS), params,
                             {}, "4th-order central differences of the quaternion "
                             "right-hand side in fixed-frame perturbations (δr, θ, δv, δω)")
