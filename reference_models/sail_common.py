"""Scene data shared by the engine leaves of `sail-deploy` (thread unrolling from two spools on a
spinning hub, seed 004). Imports numpy only; the dynamics stay in each engine.

The engines model ONE blade in the inertial frame with half the hub inertia (two symmetric
blades: J Ω' = 2 M_blade  <=>  (J/2) Ω' = M_blade) and report both blades' totals.

Geometry (inertial frame, spin axis = world z through the origin): the departure point
Q = R_z(ψ) (L_c, 0, r). Node j (0 = tip … n−1 = root, mass m_j = ρ_L l0, tip + m_k,
l0 = L/n) is held at Q by the hub until its release time t_j = j Δφ/ω (Δφ = L/(n r));
it is then released with the hub-point velocity plus r ω along the rotated X1 axis (the spool's
surface velocity at Q, radial: no moment about the axis, so angular momentum is continuous).
Neighbour springs (c, d, rest l0) act between released nodes; the last released node (the
boundary) is tied to Q by a spring of rest length l0(t) = r ω (t − t_b) with a damper on the
true stretch rate d/dt|x_b − Q| − r ω. This is the "conservative" variant of the custom solver
`thread-spool` (custom_models/thread_spool.py).
"""
from __future__ import annotations

import numpy as np

CHANNELS = ("hub_rate", "deployed_length", "tip_angle", "angular_momentum", "energy_balance")

DEFAULT_PARAMS = {"J_hub": 0.004, "rho_L": 0.000735, "L": 5.0, "L_c": 0.05, "r": 0.01,
                  "Omega0": 6.0, "omega_spool": 3.5, "tip_mass": 0.0005, "n": 20,
                  "stiffness": 1e7, "damping": 1e-3, "last_node": "attached", "t_end": 142.857,
                  "output_dt": 0.05}


def merge_settings(settings, defaults, integrators, t_out):
    """Settings over the leaf's defaults, checked (unknown keys and integrators are errors)."""
    s = {**defaults, **(settings or {})}
    unknown = set(s) - set(defaults)
    if unknown:
        raise ValueError(f"unknown settings {sorted(unknown)}")
    if s["integrator"] not in integrators:
        raise ValueError(f"integrator must be one of {integrators}")
    t_out = np.asarray(t_out, float)
    if np.any(np.diff(t_out) <= 0):
        raise ValueError("t_out must be strictly increasing")
    return s, t_out


def payout(p, t):
    """(paid-out length, payout speed, Q-spring on) at time t: r ω t until the whole blade is
    out at t_full = L/(r ω); then the spool stops and the last node stays tied to Q at rest
    length l0 (last_node "attached") or leaves it ("released"). As custom_models.thread_spool."""
    rw = p["r"] * p["omega_spool"]
    if rw * t < p["L"]:
        return rw * t, rw, True
    return p["L"], 0.0, p["last_node"] == "attached"


def t_full(p):
    return p["L"] / (p["r"] * p["omega_spool"])


def scene(params):
    p = {**DEFAULT_PARAMS, **params}
    if p["last_node"] not in ("attached", "released"):
        raise ValueError("last_node must be 'attached' or 'released'")
    n = int(p["n"])
    l0 = p["L"] / n
    m = np.full(n, p["rho_L"] * l0)
    m[0] += p["tip_mass"]
    dphi = l0 / p["r"]
    t_rel = dphi * np.arange(n) / p["omega_spool"]
    return p, n, l0, m, t_rel


def stable_dt_explicit(params, factor=2.0, safety=0.8):
    """Stable step of an explicit scheme (stability interval `factor` on the imaginary axis:
    2 for symplectic Euler, 2.785 for RK4) from the highest chain frequency 2 sqrt(c/m_min)."""
    p, n, l0, m, _ = scene(params)
    lam = 2.0 * np.sqrt(p["stiffness"] / m.min()) + 4.0 * p["damping"] / m.min()
    return safety * factor / lam


def events(t_out, t_rel, t_end, t_stop=None):
    """Merged breakpoints: list of (time, output index or -1, node released or -1); the end of
    payout `t_stop` (if before t_end) as (t_stop, -1, -1)."""
    ev = [(t, i, -1) for i, t in enumerate(t_out)]
    ev += [(t, -1, j) for j, t in enumerate(t_rel) if 0 < t < t_end - 1e-12]
    if t_stop is not None and t_stop < t_end - 1e-12:
        ev.append((t_stop, -1, -1))
    ev.sort(key=lambda e: (e[0], -e[2]))          # release before output at equal times
    return ev


def channels(params, t, psi, Om, X, V, b_out, spool_work=None):
    """Scene channels from inertial states on the output grid.

    psi, Om: hub angle and rate (N,); X, V: node positions/velocities (N, n, 3) in the inertial
    frame (origin on the spin axis); b_out: boundary index (N,). Stored nodes (j > b) are counted
    at Q (inertia m L_c², velocity of the hub point). Energy balance as in the custom solver:
    T + U + D − W_spool − W_release, with D and W_spool integrated by the trapezoid rule on the
    output grid, unless the leaf integrated the spool work itself at every step (`spool_work`,
    (N,), both blades): the trapezoid rule on the output grid aliases the fast longitudinal
    ringing of the boundary tension (measured: 4e-4 J residual at 0.05 s sampling, 8e-5 J at
    1 ms, for a 0.07 J system).
    """
    p, n, l0, m, _ = scene(params)
    Lc, r, c, d, rw = p["L_c"], p["r"], p["stiffness"], p["damping"], p["r"] * p["omega_spool"]
    N = len(t)
    out = {k: np.full(N, np.nan) for k in CHANNELS}
    signed = np.full(N, np.nan)
    rate_D = np.zeros(N)
    rate_W = np.zeros(N)
    TU = np.full(N, np.nan)
    wrel = np.zeros(N)
    for i in range(N):
        b = int(b_out[i])
        if b < 0 or not np.isfinite(Om[i]):
            continue
        cp, sp = np.cos(psi[i]), np.sin(psi[i])
        Q = np.array([Lc * cp, Lc * sp, r])
        VQ = Om[i] * np.array([-Q[1], Q[0], 0.0])
        x, v, mm = X[i, :b + 1], V[i, :b + 1], m[:b + 1]
        ms = m[b + 1:].sum()
        H = p["J_hub"] * Om[i] + 2 * (ms * Lc**2 * Om[i]
                                      + np.sum(mm * (x[:, 0] * v[:, 1] - x[:, 1] * v[:, 0])))
        T = 0.5 * p["J_hub"] * Om[i]**2 + ms * Lc**2 * Om[i]**2 + np.sum(mm * (v**2).sum(1))
        seg = np.diff(x, axis=0)
        lens = np.sqrt((seg**2).sum(1))
        e = seg / np.where(lens > 0, lens, 1.0)[:, None]
        sd = (e * np.diff(v, axis=0)).sum(1)
        dq = Q - x[b]
        lq = np.sqrt(dq @ dq)
        eq = dq / lq if lq > 1e-10 else -np.array([cp, sp, 0.0])
        ldot = eq @ (VQ - v[b])
        paid, rate, q_on = payout(p, t[i])
        w = (ldot - rate) if q_on else 0.0
        s = (lq - (paid - b * l0)) if q_on else 0.0
        U = c * (np.sum((lens - l0) ** 2) + s * s)            # two blades
        rate_D[i] = 2 * d * (np.sum(sd**2) + w * w)
        rate_W[i] = -2 * (c * s + d * w) * rate
        TU[i] = T + U
        wrel[i] = np.sum(m[:b + 1]) * rw**2          # 2 blades x ½ m (rω)²
        out["hub_rate"][i] = Om[i]
        out["angular_momentum"][i] = H
        out["deployed_length"][i] = lens.sum() + (lq if q_on else 0.0)
        # Δu [19]: angle at Q between the tip and the X1 axis (body frame)
        tip = x[0] - Q
        tb = np.array([cp * tip[0] + sp * tip[1], -sp * tip[0] + cp * tip[1], tip[2]])
        nt = np.sqrt(tb @ tb)
        out["tip_angle"][i] = np.arccos(np.clip(tb[0] / nt, -1, 1)) if nt > 0 else 0.0
        signed[i] = np.arctan2(tb[1], tb[0]) if nt > 0 else 0.0
    ok = np.isfinite(TU)
    D = np.zeros(N)
    W = np.zeros(N)
    dt = np.diff(t)
    D[1:] = np.cumsum(0.5 * (rate_D[1:] + rate_D[:-1]) * dt)
    W[1:] = np.cumsum(0.5 * (rate_W[1:] + rate_W[:-1]) * dt)
    if spool_work is not None:
        W = np.asarray(spool_work, float)
    out["energy_balance"] = np.where(ok, TU + D - W - wrel, np.nan)
    return out, {"tip_angle_signed": signed}


def formula18(params, t):
    """Rebuilt formula 18 (see custom_models/thread_spool.formula18)."""
    p = {**DEFAULT_PARAMS, **params}
    J, rho, L, Lc, mk = p["J_hub"], p["rho_L"], p["L"], p["L_c"], p["tip_mass"]
    ell = np.minimum(p["r"] * p["omega_spool"] * np.asarray(t, float), L)
    I0 = J + 2.0 * (rho * L + mk) * Lc**2
    I = J + 2.0 * (rho * (L - ell) * Lc**2 + rho * ((Lc + ell) ** 3 - Lc**3) / 3.0
                   + mk * (Lc + ell) ** 2)
    return I0 * p["Omega0"] / I
