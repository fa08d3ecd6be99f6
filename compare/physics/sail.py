"""Physics of the heliogyro blade deployment (scene `sail-deploy`, seed 004) that every solver
must compute alike: the lumped thread, the payout law, the release law, the breakpoints, the
closed forms (formula 18 as printed and rebuilt, its lumped version, the yo-yo despin) and the
scene's channels from a common kinematic output. Numpy and numba only (leaves import it).

Geometry (inertial frame, spin axis = z through the origin): the departure point
Q = R_z(ψ)(L_c, 0, r). Node j (0 = tip … n−1 = root, m_j = ρ_L l0, the tip + m_k, l0 = L/n)
is held at Q by the hub until its release time t_j = j Δφ/ω (Δφ = L/(n r)). It is then released
with the hub-point velocity plus r ω along the rotated X1 axis — the spool's surface velocity at
Q, radial: no moment about the axis, so angular momentum is continuous (the engines' and the
conservative custom variant's release law; the paper's variant turns it, custom only).
The last released node (the boundary) is tied to Q by a spring of rest length
l0(t) = r ω (t − t_b) while the spool pays out.
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np

from ..contract import Channel

# deployed_length is a polyline length from node positions at L_c + s from the axis: it rounds
# with L_c where L_c exceeds the length (early in the payout, where two models that pay out
# alike differ by that rounding alone)
CHANNELS = (Channel("hub_rate", "rad/s"), Channel("deployed_length", "m", rounding="L_c"),
            Channel("tip_angle", "rad"), Channel("angular_momentum", "kg·m²/s"),
            Channel("energy_balance", "J"))


def thread(params: dict) -> tuple:
    """The lumped thread: (n, l0, masses m (n,), release times t_rel (n,), t_rel[0] = 0)."""
    n = int(params["n"])
    l0 = params["L"] / n
    m = np.full(n, params["rho_L"] * l0)
    m[0] += params["tip_mass"]
    t_rel = (l0 / params["r"]) * np.arange(n) / params["omega_spool"]
    return n, l0, m, t_rel


def t_full(params: dict) -> float:
    """End of payout: the whole blade is out at L/(r ω)."""
    return params["L"] / (params["r"] * params["omega_spool"])


@nb.njit(cache=True)
def payout(t: float, L: float, rw: float, end_released: bool) -> tuple:
    """(paid-out length, payout speed, Q-spring on) at time t. The spool pays out r·ω·t until the
    whole blade is out at t_full = L/(r ω); then it stops and the last node stays tied to Q by a
    spring of rest length l0 ("attached"), or leaves Q altogether ("released": the blade flies
    free and the hub spins on at constant rate). rw = r ω."""
    if rw * t < L:
        return rw * t, rw, True
    return L, 0.0, not end_released


def payout_of(params: dict, t: float) -> tuple:
    return payout(t, params["L"], params["r"] * params["omega_spool"],
                  params["last_node"] == "released")


@nb.njit(cache=True)
def release_state(psi: float, omega: float, L_c: float, r: float, rw: float) -> tuple:
    """The release law: a node leaves at Q = R_z(ψ)(L_c, 0, r) with the hub-point velocity
    Ω e_z × Q plus r ω along the rotated X1 axis. Returns (Q (3), V (3)) as six floats."""
    c, s = math.cos(psi), math.sin(psi)
    q0, q1 = L_c * c, L_c * s
    return q0, q1, r, -omega * q1 + rw * c, omega * q0 + rw * s, 0.0


def breakpoints(params: dict, t_out: np.ndarray) -> tuple:
    """Merged step breakpoints of a run: (times, output index or −1, node released there or −1,
    end of payout there). Outputs, releases t_j (j ≥ 1) and the end of payout t_full, where the
    payout speed drops to 0, so that no step straddles a kink; times within 1e-10 s merge."""
    n, _, _, t_rel = thread(params)
    t_end = t_out[-1]
    ev = {}
    for i, t in enumerate(t_out):
        ev[round(float(t), 10)] = [float(t), i, -1, False]
    extra = [(t_rel[j], j, False) for j in range(1, n)] + [(t_full(params), -1, True)]
    for t, j, end in extra:
        if t >= t_end - 1e-12:
            continue
        key = round(float(t), 10)
        if key in ev:
            ev[key][2] = max(ev[key][2], j)
            ev[key][3] = ev[key][3] or end
        else:
            ev[key] = [float(t), -1, j, end]
    rows = sorted(ev.values())
    return (np.array([r[0] for r in rows]), np.array([r[1] for r in rows], np.int64),
            np.array([r[2] for r in rows], np.int64), np.array([r[3] for r in rows], bool))


def formula18(params: dict, t, printed: bool = False) -> np.ndarray:
    """Rebuilt formula 18: hub spin from conservation of angular momentum, rigid straight radial
    blades of deployed length ℓ(t) = min(r ω t, L) rooted at L_c from the axis, tip masses at
    L_c + ℓ, the thread still on the spools counted at L_c (both blades):

        I(ℓ) = J + 2[ρ_L (L − ℓ) L_c² + ρ_L ((L_c + ℓ)³ − L_c³)/3 + m_k (L_c + ℓ)²]
        Ω(t) = I(0) Ω0 / I(ℓ(t)),   I(0) = J + 2 (ρ_L L + m_k) L_c².

    Our copy of the paper prints (garbled) Ω = J Ω0 / (J + (2/3) ρ_L L³ + 2 m_k L²): no L_c, no
    stored thread; `printed=True` returns that (with ℓ(t) in place of L)."""
    J, rho, L, Lc = params["J_hub"], params["rho_L"], params["L"], params["L_c"]
    mk, Om0 = params["tip_mass"], params["Omega0"]
    ell = np.minimum(params["r"] * params["omega_spool"] * np.asarray(t, float), L)
    if printed:
        return J * Om0 / (J + 2.0 / 3.0 * rho * ell**3 + 2.0 * mk * ell**2)
    I0 = J + 2.0 * (rho * L + mk) * Lc**2
    I = J + 2.0 * (rho * (L - ell) * Lc**2 + rho * ((Lc + ell) ** 3 - Lc**3) / 3.0
                   + mk * (Lc + ell) ** 2)
    return I0 * Om0 / I


def formula18_discrete(params: dict, t) -> np.ndarray:
    """Formula 18 for the lumped thread itself: the released nodes on a straight radial line at
    their unstretched positions (boundary node at l0(t) from Q, then every l0), stored nodes at
    L_c, conservative bookkeeping. Differs from the continuous formula by O(l0) lumping."""
    n, l0, m, _ = thread(params)
    L, r, w, Lc = params["L"], params["r"], params["omega_spool"], params["L_c"]
    J = params["J_hub"]
    I0 = J + 2 * m.sum() * Lc**2
    t = np.asarray(t, float)
    out = np.empty_like(t)
    phi = np.minimum(w * t, L / r)
    bs = np.minimum(np.floor(phi * n * r / L + 1e-12).astype(np.int64), n - 1)
    for b in np.unique(bs):                      # the instants of one boundary node at once
        i = np.nonzero(bs == b)[0]
        lt = r * phi[i] - l0 * b
        R = Lc + lt[:, None] + l0 * (b - np.arange(b + 1))
        I = J + 2 * (np.sum(m[:b + 1] * R**2, axis=1) + m[b + 1:].sum() * Lc**2)
        out[i] = I0 * params["Omega0"] / I
    return out


def yoyo_despin(params: dict, ell) -> np.ndarray:
    """Classic yo-yo despin closed form (two tip masses m on massless cords unwinding
    tangentially from a hub of radius R = L_c, cords free — no spool): with
    k² = (J + 2 m R²)/(2 m R²) and λ = ℓ/R, Ω = Ω0 (k² − λ²)/(k² + λ²); zero at ℓ = R k.
    A comparison for light hubs only (our payout is prescribed, not free)."""
    R, J, mk = params["L_c"], params["J_hub"], params["tip_mass"] + params["rho_L"] * params["L"]
    k2 = (J + 2 * mk * R**2) / (2 * mk * R**2)
    lam2 = (np.asarray(ell) / R) ** 2
    return params["Omega0"] * (k2 - lam2) / (k2 + lam2)


def channels(params: dict, t, psi, omega, X, V, b_out, dissipated=None, spool_work=None):
    """The scene's channels from a solver's kinematic output in the inertial frame.

    psi, omega: hub angle and rate (N,); X, V: node positions/velocities (N, n, 3) (origin on
    the spin axis); b_out: boundary index (N,; −1 = no state). Stored nodes (j > b) are counted
    at Q (inertia m L_c², velocity of the hub point).
    hub_rate Ω; deployed_length: polyline length Q → boundary → … → tip (stretched arc, = r ω t
    up to spring stretch); tip_angle Δu [19]: arccos of the X1 component of (x_tip − Q)/|…|
    (unsigned, as printed; the signed in-plane angle atan2 in extra "tip_angle_signed", negative
    = trailing); angular_momentum J Ω + 2[Σ_stored m L_c² Ω + Σ_released m (x × v)_z];
    energy_balance T + U + D − W_spool − W_release (both blades): T kinetic, U elastic,
    D = ∫ d·w² dissipated, W_spool the work of the prescribed payout on the Q-spring,
    W_release = Σ ½ m (r ω)² per released node and blade (the spool throws each node off at
    the payout speed). D and W_spool as the solver integrated them at every step where it
    passes them (`dissipated`, `spool_work`, both blades), else by the trapezoid rule on the
    output grid (which aliases the fast ringing of the boundary tension: 4e-4 J at 0.05 s
    sampling for a 0.07 J system). Returns (channels, extra)."""
    n, l0, m, _ = thread(params)
    Lc, r, c, d, J = (params["L_c"], params["r"], params["stiffness"], params["damping"],
                      params["J_hub"])
    rw = r * params["omega_spool"]
    N = len(t)
    out = {k: np.full(N, np.nan) for k in CHANNELS}
    signed = np.full(N, np.nan)
    kinetic = np.full(N, np.nan)
    rate_D = np.zeros(N)
    rate_W = np.zeros(N)
    TU = np.full(N, np.nan)
    wrel = np.zeros(N)
    # the drawing's input: released nodes tip → boundary, then Q (one blade, inertial frame)
    shape = np.full((N, n + 1, 3), np.nan)
    b_out = np.asarray(b_out).astype(np.int64)
    valid = (b_out >= 0) & np.isfinite(omega)
    # rows of one boundary index b at once (b is constant between releases)
    for b in np.unique(b_out[valid]):
        i = np.nonzero(valid & (b_out == b))[0]
        om, cp, sp = omega[i], np.cos(psi[i]), np.sin(psi[i])
        Q = np.stack([Lc * cp, Lc * sp, np.full(len(i), r)], axis=1)
        shape[i, :b + 1], shape[i, b + 1] = X[i, :b + 1], Q
        VQ = om[:, None] * np.stack([-Q[:, 1], Q[:, 0], np.zeros(len(i))], axis=1)
        x, v, mm = X[i, :b + 1], V[i, :b + 1], m[:b + 1]
        ms = m[b + 1:].sum()
        H = J * om + 2 * (ms * Lc**2 * om + np.sum(
            mm * (x[..., 0] * v[..., 1] - x[..., 1] * v[..., 0]), axis=1))
        T = 0.5 * J * om**2 + ms * Lc**2 * om**2 + np.sum(mm * (v**2).sum(2), axis=1)
        seg = np.diff(x, axis=1)
        lens = np.sqrt((seg**2).sum(2))
        e = seg / np.where(lens > 0, lens, 1.0)[..., None]
        sd = (e * np.diff(v, axis=1)).sum(2)
        dq = Q - x[:, b]
        lq = np.sqrt((dq**2).sum(1))
        far = lq > 1e-10
        eq = np.where(far[:, None], dq / np.where(far, lq, 1.0)[:, None],
                      -np.stack([cp, sp, np.zeros(len(i))], axis=1))
        ldot = (eq * (VQ - v[:, b])).sum(1)
        paid, rate, q_on = np.array([payout_of(params, ti) for ti in t[i]], float).T
        q_on = q_on > 0.5
        w = np.where(q_on, ldot - rate, 0.0)
        s = np.where(q_on, lq - (paid - b * l0), 0.0)
        U = c * (np.sum((lens - l0) ** 2, axis=1) + s * s)            # two blades
        rate_D[i] = 2 * d * (np.sum(sd**2, axis=1) + w * w)
        rate_W[i] = -2 * (c * s + d * w) * rate
        TU[i] = T + U
        kinetic[i] = T
        wrel[i] = np.sum(m[:b + 1]) * rw**2          # 2 blades x ½ m (rω)²
        out["hub_rate"][i] = om
        out["angular_momentum"][i] = H
        out["deployed_length"][i] = lens.sum(1) + np.where(q_on, lq, 0.0)
        tip = x[:, 0] - Q                             # Δu [19], in the body frame
        tb0, tb1 = cp * tip[:, 0] + sp * tip[:, 1], -sp * tip[:, 0] + cp * tip[:, 1]
        nt = np.sqrt(tb0**2 + tb1**2 + tip[:, 2] ** 2)
        pos = nt > 0
        out["tip_angle"][i] = np.where(
            pos, np.arccos(np.clip(tb0 / np.where(pos, nt, 1.0), -1, 1)), 0.0)
        signed[i] = np.where(pos, np.arctan2(tb1, tb0), 0.0)
    ok = np.isfinite(TU)
    dt = np.diff(t)
    if dissipated is None:
        D = np.zeros(N)
        D[1:] = np.cumsum(0.5 * (rate_D[1:] + rate_D[:-1]) * dt)
    else:
        D = np.asarray(dissipated, float)
    if spool_work is None:
        W = np.zeros(N)
        W[1:] = np.cumsum(0.5 * (rate_W[1:] + rate_W[:-1]) * dt)
    else:
        W = np.asarray(spool_work, float)
    out["energy_balance"] = np.where(ok, TU + D - W - wrel, np.nan)
    return out, {"tip_angle_signed": signed, "kinetic_energy": kinetic,
                 "hub_angle": np.asarray(psi, float), "thread_shape": shape}


def release_grid(params: dict, t_end: float, points: int = 4001) -> np.ndarray:
    """A grid over [0, t_end] that holds every release time inside it (Ω of the lumped
    formula has a kink at each)."""
    _, _, _, t_rel = thread(params)
    return np.union1d(np.linspace(0.0, t_end, points), t_rel[t_rel < t_end])


def stored_thread_momentum(params: dict, t, omega) -> np.ndarray:
    """ΔH(t) of the paper's model against a conservative one: the paper leaves the stored thread
    out of the hub inertia, so the hub's spin changes never reach the 2 L_c² Σ_stored m_j that
    the channel counts at L_c — ΔH(t) = 2 L_c² ∫₀ᵗ M_stored(t') dΩ(t') along the spin history
    `omega` on `t` (stored mass constant between releases)."""
    _, _, m, t_rel = thread(params)
    t, omega = np.asarray(t, float), np.asarray(omega, float)
    stored = np.array([m[t_rel > ti + 1e-12].sum() for ti in t[:-1]])
    dH = 2 * params["L_c"] ** 2 * stored * np.diff(omega)
    return np.concatenate(([0.0], np.cumsum(dH)))


def root_lag(params: dict, omega: float) -> float:
    """The thread's quasi-steady lag at the departure point [rad]: a node paid out at r·ω from Q
    hangs where the centrifugal pull m Ω² L_c sinθ balances the Coriolis push 2 m Ω r ω cosθ,
    tan θ = 2 r ω / (Ω L_c) (independent of its distance from Q)."""
    return math.atan2(2 * params["r"] * params["omega_spool"], abs(omega) * params["L_c"])


def formula18_lag(params: dict, t) -> tuple:
    """The lumped formula 18 (`formula18_discrete`) with the thread's quasi-steady lag put back:
    (Ω [rad/s] on t, x on t: the lag's solvability, no quasi-steady lag where |x| > 1).

    Formula 18 holds the released thread rigid, straight and radial. A thread paid out at r·ω
    from Q trails the radial by θ; node j at s_j along it from Q is then at
    R_j² = L_c² + 2 L_c s_j cosθ + s_j² from the axis, 2 m_j L_c s_j (1 − cosθ) less inertia per
    blade, and its velocity r·ω along the thread carries −m_j r ω L_c sinθ about the axis.
    θ balances the moments about Q on the straight thread (weights S1 = Σ m_j s_j,
    S2 = Σ m_j s_j²): the centrifugal pull Ω² L_c S1 sinθ and the despin's Euler force
    |Ω̇| (S2 + L_c S1 cosθ) against the Coriolis push 2 Ω r ω S1, i.e. A sinθ + B cosθ = C with
    A = Ω² L_c, B = |Ω̇| L_c, C = 2 Ω r ω − |Ω̇| S2/S1, x = C/√(A² + B²) (at Ω̇ = 0:
    sinθ = 2 r ω/(Ω L_c)). Ω and Ω̇ = Ω İ/I (İ = 4 r ω Σ m_j (L_c + s_j)) are the formula's;
    Ω = (H₀ + 2 sgn(Ω₀) r ω L_c sinθ Σ m_j) / I(θ). No transient, stretch or curvature."""
    n, l0, m, _ = thread(params)
    L, r, w, Lc, J = params["L"], params["r"], params["omega_spool"], params["L_c"], params["J_hub"]
    t = np.asarray(t, float)
    f = formula18_discrete(params, t)
    H0 = (J + 2 * m.sum() * Lc**2) * params["Omega0"]
    out, xs = np.empty_like(t), np.empty_like(t)
    phi = np.minimum(w * t, L / r)
    bs = np.minimum(np.floor(phi * n * r / L + 1e-12).astype(np.int64), n - 1)
    for b in np.unique(bs):                      # the instants of one boundary node at once
        i = np.nonzero(bs == b)[0]
        s = (r * phi[i] - l0 * b)[:, None] + l0 * (b - np.arange(b + 1))
        mm, stored = m[:b + 1], m[b + 1:].sum() * Lc**2
        pay = np.where(r * w * t[i] < L, r * w, 0.0)
        om = np.abs(f[i])
        I_rigid = J + 2 * (np.sum(mm * (Lc + s) ** 2, axis=1) + stored)
        om_dot = om * 4 * pay * np.sum(mm * (Lc + s), axis=1) / I_rigid
        S1, S2 = np.sum(mm * s, axis=1), np.sum(mm * s * s, axis=1)
        A, B = om**2 * Lc, om_dot * Lc
        C = 2 * om * pay - np.where(S1 > 0, om_dot * S2 / np.where(S1 > 0, S1, 1.0), 0.0)
        R = np.hypot(A, B)
        x = np.where(R > 0, C / np.where(R > 0, R, 1.0), np.where(C == 0, 0.0, np.inf))
        th = np.arcsin(np.clip(x, -1.0, 1.0)) - np.arctan2(B, A)
        I = J + 2 * (np.sum(mm * (Lc**2 + 2 * Lc * s * np.cos(th)[:, None] + s * s), axis=1)
                     + stored)
        rel = 2 * np.sign(params["Omega0"]) * pay * Lc * np.sin(th) * mm.sum()
        out[i], xs[i] = (H0 + rel) / I, x
    return out, xs
