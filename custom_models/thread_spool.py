"""Thread unrolling from a spool, constant-dimension spring–mass model (seed 004, Tenenbaum 2014),
tested on the two-blade heliogyro deployment (scene `sail-deploy`, solver `thread-spool`).

Model (paper §III, §IV; numbering of the paper's equations in brackets)
----------------------------------------------------------------------
Body frame X1Y1Z1 of the spacecraft: origin at the spool centre, X1 the nominal departure
direction, spin axis Z parallel to Z1 through (−L_c, 0, ·). Thread wound in the X1Z1 plane on a
spool of radius r turning φ(t) = ω t; node i (paper's i = 1 … n, here index j = i − 1, node 0 =
the tip) sits at angle φ − Δφ·j, i.e. at (r sin, 0, r cos) of it [2, 17]; it reaches the
departure point Q = (0, 0, r) with body velocity (r φ', 0, 0) when φ = Δφ·j [1].
Δφ = L/(n r), l0 = r Δφ = L/n. Masses [6]: m_j = ρ_L l0, tip m_0 = ρ_L l0 + m_k (each node
carries one segment l0, so the blade mass is ρ_L L + m_k; the garbled eq. 6 is read this way).

Groups of nodes at any time (b = index of the boundary node = the last released one):
- stored (j > b): rigidly on the spool; their motion is prescribed and they exert no force on the
  released thread (the boundary node's spring goes to Q instead [7-9]);
- boundary (j = b): spring-damper to node b−1 (rest l0) and to Q with the variable rest length
  l0(t) = r(φ − Δφ b) [10]; when |Q − x_b| < eps the direction node→Q is taken as
  −e_x (paper eq. 11: {−1, 0, 0});
- free (j < b): spring–dampers (c, d) to both neighbours [3, 4] (the tip has one).
Rotating frame [14]: F_x = m(Ω' y + Ω²(x + L_c) + 2Ω y'), F_y = m(−Ω'(x + L_c) + Ω² y − 2Ω x'),
checked against −m Ω'×ρ − m Ω×(Ω×ρ) − 2m Ω×v. Hub [15, 16]: J Ω' = M_z = −2 L_c F_Qy (F_Q: the
force of the Q-spring on the boundary node; two symmetric blades).

Release law and the two variants (setting `variant`)
----------------------------------------------------
Release times are known in advance (φ = ω t): t_j = Δφ j / ω. Both integrators land a step on
every release time and release node j there: it is put at Q with body velocity (r ω, 0, 0),
which is exactly where the spool kinematics [2] delivers it (the paper's alternative in §III.1
of setting stored nodes from φ(t) instead of integrating eq. 2 — they influence nothing else).
The rest length of the previous boundary node's Q-spring equals l0 at that instant and Q = x_j,
so its spring force carries over continuously to the new neighbour spring.

- "paper": the node's body velocity is then turned, |v| kept, along the released thread
  (toward node j−1) [12]; J = J_hub (stored thread not in the hub's inertia); the Q-damper
  uses the departure velocity (r ω e_x) as the velocity of Q [8, 9].
- "conservative": stored thread counted at L_c in the hub's inertia,
  J_eff = J_hub + 2 L_c² Σ_stored m_j (it is what a mass held at Q by the hub carries: this is how
  the engines hold it); no velocity turn — the release velocity (r ω along X1, radial) has no
  moment about the spin axis, so the released node leaves with exactly the m L_c² Ω it had in
  J_eff: angular momentum is continuous at every release. The Q-damper acts on the true stretch
  rate of the variable-length segment, d/dt(|x_b − Q|) − r ω (so it dissipates d·rate² ≥ 0).
Each ingredient can be switched alone (settings `velocity_turn`, `stored_in_hub`,
`q_damper` = "paper" | "stretch") to measure what it costs.

Channels (both blades)
----------------------
hub_rate Ω; deployed_length: polyline length Q → boundary → … → tip (stretched arc, = r ω t
up to spring stretch); tip_angle Δu [19] = arccos of the X1 component of (x_tip − Q)/|x_tip − Q|
(unsigned, as printed; the signed in-plane angle atan2(y, x) is in extra["tip_angle_signed"],
negative = trailing); angular_momentum = J_hub Ω + 2[Σ_stored m L_c² Ω + Σ_released m (ρ×V)_z]
(the stored thread counted at L_c in every variant, so the paper variant shows its drift);
energy_balance = T + U + D − W_spool − W_release: T the inertial kinetic energy (hub, stored at
L_c, released nodes), U the elastic energy, D the dissipated energy ∫ d·w², W_spool the work
of the prescribed payout on the Q-spring (∫ −(c s + d w) r ω dt for the stretch damper; the
general expression in `_forces`), W_release = Σ ½ m (r ω)² per released node and blade (the
spool throws each node off at the payout speed). Constant for the conservative model (up to the
integrator's error); in the paper variant the velocity turn and the unforced stored inertia
show as drifts.

Integrators
-----------
- "rk4": the paper's fixed-step explicit RK4 in the rotating frame. `dt="auto"` picks
  0.8 × 2.785/λ_max with λ_max = 2 sqrt(c/m_min) + 4 d/m_min (highest chain frequency, m_min
  including the hub's reduced mass at Q); a requested step above the stability limit runs and
  is caught (spring stretch beyond `stretch_limit`·l0 or non-finite state) and reported as
  status "diverged", reason "unstable step ...".
- `dt="auto"` (default): 1e-3 s for "imr", the stability-derived step for "rk4".
- "imr" (default): implicit midpoint rule in the inertial frame with
  energy–momentum (discrete-gradient, Simo & Tarnow 1992) spring forces: each spring's force
  is c(1 − l0/ℓ̄) times the midpoint chord, ℓ̄ the mean of its start and end lengths. The
  total angular momentum is then conserved exactly (forces along the midpoint chords; the
  hub–node pair at Q balanced), for any step; the springs' work is exactly −ΔU, so the
  unresolved longitudinal modes (1e5 rad/s) cannot pump energy (the plain midpoint rule did:
  at dt = 1e-3 it went unstable within 20 s). Newton on the midpoint velocities and hub rate;
  the Newton matrix (spring stiffness + damping, bordered by the hub) is block-tridiagonal and
  solved in O(n) (`integrators.implicit.bordered_block3_solve`). Where Newton fails (just after
  a release the new boundary segment is nearly zero-length and its transverse stiffness T/ℓ is
  huge) the step is retried as 2, 4, … 4096 sub-steps (stats["step_retries"]).

Known limitation of the model itself (paper eq. 11 remarks on it): the new boundary segment
starts at zero length. If the released thread trails at a large angle α from X1 (fast spool,
light hub), the node released along X1 swings round Q on a segment of length ~ r ω (t − t_b);
the swing frequency ~ sqrt(T/(m ℓ)) is unbounded as ℓ → 0, and the energy balance then shows
excursions ~1e-6 J (fast spool, n = 10) that do not shrink with dt. Angular momentum is not
affected (central forces). The paper's velocity turn (eq. 12) avoids the swing but breaks
angular momentum.

Formulation check: rk4 (rotating frame, fictitious forces) and imr (inertial frame, none) share
only the spring law, so their agreement tests the rotating-frame equations [14-16].
"""
import time
import numpy as np
import numba as nb

from .integrators.implicit import block3_tridiag_factor, bordered_block3_solve

CHANNELS = ("hub_rate", "deployed_length", "tip_angle", "angular_momentum", "energy_balance")
INTEGRATORS = ("rk4", "imr")
VARIANTS = ("paper", "conservative")
LAST_NODE = ("attached", "released")
DEFAULT_SETTINGS = {"integrator": "imr", "dt": "auto", "variant": "conservative",
                    "velocity_turn": None, "stored_in_hub": None, "q_damper": None,
                    "newton_tol": 1e-12, "stretch_limit": 0.5, "eps_fallback": 1e-10}
AUTO_DT = {"imr": 1e-3}      # dt="auto" for imr; rk4's auto step comes from its stability limit
DEFAULT_PARAMS = {"J_hub": 0.004, "rho_L": 0.000735, "L": 5.0, "L_c": 0.05, "r": 0.01,
                  "Omega0": 6.0, "omega_spool": 3.5, "tip_mass": 0.0005, "n": 20,
                  "stiffness": 1e7, "damping": 1e-3, "t_end": 142.857, "output_dt": 0.05}

# packed parameter array
(JH, RHO, LL, LC, RR, OM0, WSP, MK, NN, CC, DD, L0, DPHI, STORED, TURN, QDAMP, EPS, SLIM,
 ENDREL) = range(19)
NP = 19
# state layout: [Omega, psi, D (dissipated, one blade), W (payout work, one blade), x(3n), v(3n)]
OFF = 4

FAIL_NONFINITE, FAIL_STRETCH, FAIL_NEWTON = 1, 10, 11
REASONS = {FAIL_NONFINITE: "non-finite state",
           FAIL_STRETCH: "spring stretch beyond stretch_limit*l0",
           FAIL_NEWTON: "Newton iteration of the implicit midpoint step did not converge"}


def pack(params, settings):
    n = int(params["n"])
    if n < 2:
        raise ValueError("n must be >= 2")
    L, r = float(params["L"]), float(params["r"])
    l0 = L / n
    variant = settings["variant"]
    if variant not in VARIANTS:
        raise ValueError(f"variant must be one of {VARIANTS}")
    paper = variant == "paper"
    turn = settings.get("velocity_turn")
    stored = settings.get("stored_in_hub")
    qd = settings.get("q_damper")
    turn = paper if turn is None else bool(turn)
    stored = (not paper) if stored is None else bool(stored)
    qd = ("paper" if paper else "stretch") if qd is None else qd
    if qd not in ("paper", "stretch"):
        raise ValueError("q_damper must be 'paper' or 'stretch'")
    P = np.zeros(NP)
    P[JH], P[RHO], P[LL], P[LC], P[RR] = (params["J_hub"], params["rho_L"], L, params["L_c"], r)
    P[OM0], P[WSP], P[MK], P[NN] = params["Omega0"], params["omega_spool"], params["tip_mass"], n
    P[CC], P[DD], P[L0], P[DPHI] = params["stiffness"], params["damping"], l0, l0 / r
    P[STORED], P[TURN], P[QDAMP] = float(stored), float(turn), 1.0 if qd == "paper" else 0.0
    P[EPS], P[SLIM] = settings["eps_fallback"], settings["stretch_limit"]
    last = params.get("last_node", "attached")
    if last not in LAST_NODE:
        raise ValueError(f"last_node must be one of {LAST_NODE}")
    P[ENDREL] = float(last == "released")
    m = np.full(n, params["rho_L"] * l0)
    m[0] += params["tip_mass"]
    return P, m, {"velocity_turn": turn, "stored_in_hub": stored, "q_damper": qd}


@nb.njit(cache=True)
def _j_eff(P, m, b):
    """Hub inertia of the whole craft (both blades' stored thread if counted)."""
    J = P[JH]
    if P[STORED] > 0.5:
        s = 0.0
        for j in range(b + 1, m.shape[0]):
            s += m[j]
        J += 2.0 * P[LC] ** 2 * s
    return J


@nb.njit(cache=True)
def _payout(t, P):
    """(paid-out length, payout speed, Q-spring on) at time t. The spool pays out r·ω·t until the
    whole blade is out at t_full = L/(r ω); then it stops and the last node stays tied to Q by a
    spring of rest length l0 ("attached"), or leaves Q altogether ("released": the blade flies
    free and the hub spins on at constant rate)."""
    rw = P[RR] * P[WSP]
    if rw * t < P[LL]:
        return rw * t, rw, True
    return P[LL], 0.0, P[ENDREL] < 0.5


@nb.njit(cache=True)
def _segment(y, ox, ov, j):
    """Chord node j → j+1: components, length, unit vector and stretch rate."""
    dx = y[ox + 3 * j + 3] - y[ox + 3 * j]
    dy = y[ox + 3 * j + 4] - y[ox + 3 * j + 1]
    dz = y[ox + 3 * j + 5] - y[ox + 3 * j + 2]
    ell = np.sqrt(dx * dx + dy * dy + dz * dz)
    ex, ey, ez = dx / ell, dy / ell, dz / ell
    sd = (ex * (y[ov + 3 * j + 3] - y[ov + 3 * j]) + ey * (y[ov + 3 * j + 4] - y[ov + 3 * j + 1])
          + ez * (y[ov + 3 * j + 5] - y[ov + 3 * j + 2]))
    return dx, dy, dz, ell, ex, ey, ez, sd


@nb.njit(cache=True)
def _push_pair(F, j, fx, fy, fz):
    """Equal and opposite force of segment j on its two nodes."""
    F[3 * j] += fx
    F[3 * j + 1] += fy
    F[3 * j + 2] += fz
    F[3 * j + 3] -= fx
    F[3 * j + 4] -= fy
    F[3 * j + 5] -= fz


@nb.njit(cache=True)
def _forces(t, y, P, m, b, Q0, Q1, Q2, VQ0, VQ1, VQ2, p0, p1, p2, F):
    """Spring–damper forces on nodes 0..b (frame-independent law; positions/velocities from y,
    Q its position, VQ the material velocity of the hub point Q, p the payout direction, all in
    the frame of y). Fills F[0..3b+2]. Returns (F_Q on node b: fx, fy, fz, dissipation rate,
    payout power), one blade."""
    n = int(P[NN])
    c, d, l0 = P[CC], P[DD], P[L0]
    ox, ov = OFF, OFF + 3 * n
    for k in range(3 * (b + 1)):
        F[k] = 0.0
    diss = 0.0
    for j in range(b):
        dx, dy, dz, ell, ex, ey, ez, sd = _segment(y, ox, ov, j)
        f = c * (ell - l0) + d * sd
        _push_pair(F, j, f * ex, f * ey, f * ez)
        diss += d * sd * sd
    # boundary node b: Q-spring with variable rest length l0(t) = r(φ − Δφ b)  [7-11]
    paid, rw, q_on = _payout(t, P)
    if not q_on:
        return 0.0, 0.0, 0.0, diss, 0.0
    dx = Q0 - y[ox + 3 * b]
    dy = Q1 - y[ox + 3 * b + 1]
    dz = Q2 - y[ox + 3 * b + 2]
    ell = np.sqrt(dx * dx + dy * dy + dz * dz)
    if ell < P[EPS]:
        ex, ey, ez = -p0, -p1, -p2
    else:
        ex, ey, ez = dx / ell, dy / ell, dz / ell
    l0t = paid - l0 * b
    s = ell - l0t
    ldot = (ex * (VQ0 - y[ov + 3 * b]) + ey * (VQ1 - y[ov + 3 * b + 1])
            + ez * (VQ2 - y[ov + 3 * b + 2]))
    if P[QDAMP] > 0.5:
        w = ldot + rw * (ex * p0 + ey * p1 + ez * p2)     # paper [8]: v_Q = departure velocity
    else:
        w = ldot - rw                                    # true stretch rate of the segment
    f = c * s + d * w
    F[3 * b] += f * ex
    F[3 * b + 1] += f * ey
    F[3 * b + 2] += f * ez
    diss += d * w * w
    # d/dt(T + U + D) = −c s rω − d w (ℓ' − w): the work rate of the prescribed payout
    wsp = -c * s * rw - d * w * (ldot - w)
    return f * ex, f * ey, f * ez, diss, wsp


@nb.njit(cache=True)
def _rhs_rot(t, y, P, m, b, F, dy):
    """Right-hand side in the rotating body frame (paper §IV)."""
    n = int(P[NN])
    ox, ov = OFF, OFF + 3 * n
    rw = P[RR] * P[WSP]
    fqx, fqy, fqz, diss, wsp = _forces(t, y, P, m, b, 0.0, 0.0, P[RR], 0.0, 0.0, 0.0,
                                       1.0, 0.0, 0.0, F)
    Om = y[0]
    Mz = -2.0 * P[LC] * fqy                         # [15]: reaction at Q, arm L_c, two blades
    Omd = Mz / _j_eff(P, m, b)
    dy[0] = Omd
    dy[1] = Om
    dy[2] = diss
    dy[3] = wsp
    Lc = P[LC]
    for j in range(b + 1):
        x = y[ox + 3 * j]
        yy = y[ox + 3 * j + 1]
        vx = y[ov + 3 * j]
        vy = y[ov + 3 * j + 1]
        X = x + Lc
        dy[ox + 3 * j] = vx
        dy[ox + 3 * j + 1] = vy
        dy[ox + 3 * j + 2] = y[ov + 3 * j + 2]
        mi = 1.0 / m[j]
        dy[ov + 3 * j] = F[3 * j] * mi + Omd * yy + Om * Om * X + 2.0 * Om * vy        # [14]
        dy[ov + 3 * j + 1] = F[3 * j + 1] * mi - Omd * X + Om * Om * yy - 2.0 * Om * vx
        dy[ov + 3 * j + 2] = F[3 * j + 2] * mi
    for k in range(3 * (b + 1), 3 * n):            # stored nodes: set at release, not integrated
        dy[ox + k] = 0.0
        dy[ov + k] = 0.0
    return 0


@nb.njit(cache=True)
def _max_stretch(y, P, b, t, frame_inertial):
    """Largest |spring stretch| / l0 (the unstable-step guard)."""
    n = int(P[NN])
    ox = OFF
    l0 = P[L0]
    worst = 0.0
    for j in range(b):
        dx = y[ox + 3 * j + 3] - y[ox + 3 * j]
        dy = y[ox + 3 * j + 4] - y[ox + 3 * j + 1]
        dz = y[ox + 3 * j + 5] - y[ox + 3 * j + 2]
        s = abs(np.sqrt(dx * dx + dy * dy + dz * dz) - l0) / l0
        if s > worst:
            worst = s
    paid, rw, q_on = _payout(t, P)
    if not q_on:
        return worst
    if frame_inertial:
        ps, pc = np.sin(y[1]), np.cos(y[1])
        Q0, Q1, Q2 = P[LC] * pc, P[LC] * ps, P[RR]
    else:
        Q0, Q1, Q2 = 0.0, 0.0, P[RR]
    dx = Q0 - y[ox + 3 * b]
    dy = Q1 - y[ox + 3 * b + 1]
    dz = Q2 - y[ox + 3 * b + 2]
    s = abs(np.sqrt(dx * dx + dy * dy + dz * dz) - (paid - l0 * b)) / l0
    if s > worst:
        worst = s
    return worst


@nb.njit(cache=True)
def _release_rot(y, P, m, j):
    """Release node j at Q (body frame). Returns the kinetic-energy jump one blade books as
    release work: ½ m (r ω)² (the velocity turn, if on, is not booked: it shows in the balance)."""
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
    return 0.5 * m[j] * rw * rw


@nb.njit(cache=True)
def _split(T, dt):
    """Equal steps no longer than dt over a breakpoint interval T: (count ≥ 1, step)."""
    ns = max(1, int(np.ceil(T / dt - 1e-9)))
    return ns, T / ns


@nb.njit(cache=True)
def _store(io, y, b, wrel, Y, b_out, wrel_out):
    """Record the state at output row io (skipped for io < 0: a release-only breakpoint)."""
    if io >= 0:
        Y[io] = y
        b_out[io] = b
        wrel_out[io] = wrel


@nb.njit(cache=True)
def _run_rk4(y0, P, m, bk_t, bk_out, bk_rel, dt, n_out):
    """Fixed-step RK4 in the rotating frame; steps land on every breakpoint (outputs, releases).
    Returns (Y, b_out, wrel_out, steps, evals, t_fail, code)."""
    ny = y0.shape[0]
    n = int(P[NN])
    Y = np.full((n_out, ny), np.nan)
    b_out = np.zeros(n_out, np.int64)
    wrel_out = np.zeros(n_out)
    F = np.empty(3 * n)
    k1 = np.empty(ny)
    k2 = np.empty(ny)
    k3 = np.empty(ny)
    k4 = np.empty(ny)
    ys = np.empty(ny)
    y = y0.copy()
    b = 0
    wrel = _release_rot(y, P, m, 0)
    steps = 0
    slim = P[SLIM]
    for ib in range(bk_t.shape[0]):
        if ib > 0:
            t0 = bk_t[ib - 1]
            ns, h = _split(bk_t[ib] - t0, dt)
            for k in range(ns):
                t = t0 + k * h
                _rhs_rot(t, y, P, m, b, F, k1)
                for q in range(ny):
                    ys[q] = y[q] + 0.5 * h * k1[q]
                _rhs_rot(t + 0.5 * h, ys, P, m, b, F, k2)
                for q in range(ny):
                    ys[q] = y[q] + 0.5 * h * k2[q]
                _rhs_rot(t + 0.5 * h, ys, P, m, b, F, k3)
                for q in range(ny):
                    ys[q] = y[q] + h * k3[q]
                _rhs_rot(t + h, ys, P, m, b, F, k4)
                for q in range(ny):
                    y[q] += h / 6.0 * (k1[q] + 2.0 * k2[q] + 2.0 * k3[q] + k4[q])
                steps += 1
                if not np.isfinite(y[0]) or not np.isfinite(y[OFF + 3 * b]):
                    return Y, b_out, wrel_out, steps, 4 * steps, t + h, FAIL_NONFINITE
                if _max_stretch(y, P, b, t + h, False) > slim:
                    return Y, b_out, wrel_out, steps, 4 * steps, t + h, FAIL_STRETCH
        j = bk_rel[ib]
        if j > 0:
            b = j
            wrel += _release_rot(y, P, m, j)
        _store(bk_out[ib], y, b, wrel, Y, b_out, wrel_out)
    return Y, b_out, wrel_out, steps, 4 * steps, np.nan, 0


# ----------------------------------------------------------------------------------------------
# implicit midpoint rule, inertial frame (origin on the spin axis, at the spool-centre height)


@nb.njit(cache=True)
def _release_in(y, P, m, j):
    """Release node j at Q (inertial frame): at Q, velocity of the hub point + r ω along the
    rotated X1 axis (turned along the thread in the paper variant)."""
    n = int(P[NN])
    ox, ov = OFF, OFF + 3 * n
    rw = P[RR] * P[WSP]
    Om, ps, pc = y[0], np.sin(y[1]), np.cos(y[1])
    Q0, Q1, Q2 = P[LC] * pc, P[LC] * ps, P[RR]
    y[ox + 3 * j] = Q0
    y[ox + 3 * j + 1] = Q1
    y[ox + 3 * j + 2] = Q2
    ux, uy, uz = pc, ps, 0.0
    if P[TURN] > 0.5 and j > 0:
        dx = y[ox + 3 * j - 3] - Q0
        dy = y[ox + 3 * j - 2] - Q1
        dz = y[ox + 3 * j - 1] - Q2
        ell = np.sqrt(dx * dx + dy * dy + dz * dz)
        if ell > 0.0:
            ux, uy, uz = dx / ell, dy / ell, dz / ell
    y[ov + 3 * j] = -Om * Q1 + rw * ux
    y[ov + 3 * j + 1] = Om * Q0 + rw * uy
    y[ov + 3 * j + 2] = rw * uz
    return 0.5 * m[j] * rw * rw


@nb.njit(cache=True)
def _lengths(y, P, b, ps, pc, out):
    """Spring lengths (inertial state y): out[j] = |x_{j+1} − x_j| (j < b), out[b] = |Q − x_b|."""
    ox = OFF
    for j in range(b):
        dx = y[ox + 3 * j + 3] - y[ox + 3 * j]
        dy = y[ox + 3 * j + 4] - y[ox + 3 * j + 1]
        dz = y[ox + 3 * j + 5] - y[ox + 3 * j + 2]
        out[j] = np.sqrt(dx * dx + dy * dy + dz * dz)
    dx = P[LC] * pc - y[ox + 3 * b]
    dy = P[LC] * ps - y[ox + 3 * b + 1]
    dz = P[RR] - y[ox + 3 * b + 2]
    out[b] = np.sqrt(dx * dx + dy * dy + dz * dz)


@nb.njit(cache=True)
def _forces_dg(tm, Ym, P, m, b, Q0, Q1, Q2, VQ0, VQ1, p0, p1, p2, l_a, l_e, F, TR):
    """Energy–momentum (discrete-gradient) spring forces at the step midpoint (Simo & Tarnow
    1992 for a spring V = ½c(ℓ − l0)²): force on a = c(1 − l0/ℓ̄)(x_b − x_a)_mid with
    ℓ̄ = (ℓ_start + ℓ_end)/2. The work over the step is exactly −ΔV (no energy pumping by the
    unresolved longitudinal modes) and the force stays along the midpoint chord (angular
    momentum exact under the midpoint rule). Dampers: midpoint velocities along the midpoint
    chord. TR[j] receives the transverse stiffness c(1 − l0/ℓ̄) for the Newton matrix."""
    n = int(P[NN])
    c, d, l0 = P[CC], P[DD], P[L0]
    ox, ov = OFF, OFF + 3 * n
    for k in range(3 * (b + 1)):
        F[k] = 0.0
    diss = 0.0
    for j in range(b):
        dx, dy, dz, ell, ex, ey, ez, sd = _segment(Ym, ox, ov, j)
        kt = c * (1.0 - 2.0 * l0 / (l_a[j] + l_e[j]))
        TR[j] = kt
        _push_pair(F, j, kt * dx + d * sd * ex, kt * dy + d * sd * ey, kt * dz + d * sd * ez)
        diss += d * sd * sd
    paid, rw, q_on = _payout(tm, P)
    if not q_on:
        TR[b] = 0.0
        return 0.0, 0.0, diss, 0.0
    dx = Q0 - Ym[ox + 3 * b]
    dy = Q1 - Ym[ox + 3 * b + 1]
    dz = Q2 - Ym[ox + 3 * b + 2]
    ell = np.sqrt(dx * dx + dy * dy + dz * dz)
    l0t = paid - l0 * b
    lbar = 0.5 * (l_a[b] + l_e[b])
    if ell < P[EPS] or lbar < P[EPS]:
        ex, ey, ez = -p0, -p1, -p2
        kt = 0.0
        fs = c * (ell - l0t)
    else:
        ex, ey, ez = dx / ell, dy / ell, dz / ell
        kt = c * (1.0 - l0t / lbar)
        fs = kt * ell
    TR[b] = kt
    ldot = ex * (VQ0 - Ym[ov + 3 * b]) + ey * (VQ1 - Ym[ov + 3 * b + 1]) - ez * Ym[ov + 3 * b + 2]
    if P[QDAMP] > 0.5:
        w = ldot + rw * (ex * p0 + ey * p1 + ez * p2)
    else:
        w = ldot - rw
    f = fs + d * w
    F[3 * b] += f * ex
    F[3 * b + 1] += f * ey
    F[3 * b + 2] += f * ez
    diss += d * w * w
    s = fs / c
    wsp = -c * s * rw - d * w * (ldot - w)
    return f * ex, f * ey, diss, wsp


@nb.njit(cache=True)
def _spring_jac(dx, dy, dz, tr, c, d, hh, G):
    """G = hh (hh K + d e eᵀ), K = tr (I − e eᵀ) + c e eᵀ the spring's stiffness matrix."""
    ell = np.sqrt(dx * dx + dy * dy + dz * dz)
    e0, e1, e2 = dx / ell, dy / ell, dz / ell
    e = (e0, e1, e2)
    for a in range(3):
        for q in range(3):
            kk = (c - tr) * e[a] * e[q]
            if a == q:
                kk += tr
            G[a, q] = hh * (hh * kk + d * e[a] * e[q])


@nb.njit(cache=True)
def _step_imr(t, h, y, P, m, b, tol, F, Ym, Dm, Bm, Dinv, U, R, X, G, l_a, l_e, TR, Y1):
    """One step of the implicit midpoint rule with energy–momentum spring forces, inertial
    frame. Unknowns: midpoint velocities of nodes 0..b and the midpoint hub rate (Newton,
    block-tridiagonal matrix bordered by the hub). Returns (code, newton_iterations)."""
    n = int(P[NN])
    ox, ov = OFF, OFF + 3 * n
    hh = 0.5 * h
    c, d = P[CC], P[DD]
    J1 = 0.5 * _j_eff(P, m, b)            # one blade's share of the hub
    Nb = b + 1
    tm = t + hh
    ny = y.shape[0]
    _lengths(y, P, b, np.sin(y[1]), np.cos(y[1]), l_a)
    for q in range(ny):
        Ym[q] = y[q]
        Y1[q] = y[q]
    it = 0
    dprev = np.inf
    fqx = fqy = diss = wsp = 0.0
    dmax, vmax, dOm = 0.0, 1.0, 0.0
    q_on = _payout(tm, P)[2]
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
        fqx, fqy, diss, wsp = _forces_dg(tm, Ym, P, m, b, Q0, Q1, Q2, -Om * Q1, Om * Q0,
                                         pc, ps, 0.0, l_a, l_e, F, TR)
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
        if not block3_tridiag_factor(Dm, Bm, Nb, Dinv):
            return FAIL_NEWTON, it
        dOm = bordered_block3_solve(Bm, Dinv, Nb, U, delta, R, rho, X)
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


@nb.njit(cache=True)
def _run_imr(y0, P, m, bk_t, bk_out, bk_rel, dt, n_out, tol):
    ny = y0.shape[0]
    n = int(P[NN])
    Y = np.full((n_out, ny), np.nan)
    b_out = np.zeros(n_out, np.int64)
    wrel_out = np.zeros(n_out)
    F = np.empty(3 * n)
    Ym = np.empty(ny)
    Dm = np.empty((n, 3, 3))
    Bm = np.zeros((n, 3, 3))
    Dinv = np.empty((n, 3, 3))
    U = np.zeros((n, 3))
    R = np.zeros((n, 3))
    X = np.zeros((n, 3))
    G = np.empty((3, 3))
    l_a = np.empty(n)
    l_e = np.empty(n)
    TR = np.empty(n)
    Y1 = np.empty(ny)
    ysave = np.empty(ny)
    y = y0.copy()
    b = 0
    wrel = _release_in(y, P, m, 0)
    steps = 0
    iters = 0
    retries = 0
    slim = P[SLIM]
    for ib in range(bk_t.shape[0]):
        if ib > 0:
            t0 = bk_t[ib - 1]
            ns, h = _split(bk_t[ib] - t0, dt)
            for k in range(ns):
                t = t0 + k * h
                # Newton may fail where the boundary segment is nearly zero-length (just after
                # a release, stiff springs): retry the step as 2, 4, ... 4096 sub-steps
                for q in range(ny):
                    ysave[q] = y[q]
                for lev in range(13):
                    nsub = 1 << lev
                    hs = h / nsub
                    code = 0
                    for ks in range(nsub):
                        code, it = _step_imr(t + ks * hs, hs, y, P, m, b, tol, F, Ym, Dm, Bm,
                                             Dinv, U, R, X, G, l_a, l_e, TR, Y1)
                        steps += 1
                        iters += it
                        if code != 0:
                            break
                    if code == 0:
                        break
                    retries += 1
                    for q in range(ny):
                        y[q] = ysave[q]
                if code != 0:
                    return Y, b_out, wrel_out, steps, iters, t + h, code
                if _max_stretch(y, P, b, t + h, True) > slim:
                    return Y, b_out, wrel_out, steps, iters, t + h, FAIL_STRETCH
        j = bk_rel[ib]
        if j > 0:
            b = j
            wrel += _release_in(y, P, m, j)
        _store(bk_out[ib], y, b, wrel, Y, b_out, wrel_out)
    return Y, b_out, wrel_out, steps, iters + 1000000000 * retries, np.nan, 0


# ----------------------------------------------------------------------------------------------


def inertial_to_body(Y, n, L_c):
    """Inertial-frame states (rows) -> body-frame states, same layout."""
    Z = Y.copy()
    ps, pc = np.sin(Y[:, 1])[:, None], np.cos(Y[:, 1])[:, None]
    Om = Y[:, 0][:, None]
    P = Y[:, OFF:OFF + 3 * n].reshape(len(Y), n, 3)
    V = Y[:, OFF + 3 * n:].reshape(len(Y), n, 3)
    bx = pc * P[:, :, 0] + ps * P[:, :, 1]
    by = -ps * P[:, :, 0] + pc * P[:, :, 1]
    vx = pc * V[:, :, 0] + ps * V[:, :, 1] + Om * by
    vy = -ps * V[:, :, 0] + pc * V[:, :, 1] - Om * bx
    Xb = np.stack([bx - L_c, by, P[:, :, 2]], axis=2)
    Vb = np.stack([vx, vy, V[:, :, 2]], axis=2)
    Z[:, OFF:OFF + 3 * n] = Xb.reshape(len(Y), -1)
    Z[:, OFF + 3 * n:] = Vb.reshape(len(Y), -1)
    return Z


def channels_from_body(Y, b_out, wrel, P, m, t):
    """Scene channels from body-frame states (see the module docstring for the definitions)."""
    n = int(P[NN])
    Lc, r, c, l0, rw = P[LC], P[RR], P[CC], P[L0], P[RR] * P[WSP]
    N = len(Y)
    out = {k: np.full(N, np.nan) for k in CHANNELS}
    signed = np.full(N, np.nan)
    kin = np.full(N, np.nan)
    for i in range(N):
        if not np.isfinite(Y[i, 0]):
            continue
        b = int(b_out[i])
        Om = Y[i, 0]
        x = Y[i, OFF:OFF + 3 * n].reshape(n, 3)[:b + 1]
        v = Y[i, OFF + 3 * n:].reshape(n, 3)[:b + 1]
        mm = m[:b + 1]
        ms = m[b + 1:].sum()
        X = x[:, 0] + Lc
        Vx = v[:, 0] - Om * x[:, 1]
        Vy = v[:, 1] + Om * X
        Vz = v[:, 2]
        H = P[JH] * Om + 2.0 * (ms * Lc**2 * Om + np.sum(mm * (X * Vy - x[:, 1] * Vx)))
        T = 0.5 * P[JH] * Om**2 + ms * Lc**2 * Om**2 + np.sum(mm * (Vx**2 + Vy**2 + Vz**2))
        seg = np.diff(x, axis=0)
        lens = np.sqrt((seg**2).sum(axis=1))
        dq = x[b] - np.array([0.0, 0.0, r])
        lq = np.sqrt(dq @ dq)
        t_l0 = None
        U = c * np.sum((lens - l0) ** 2)           # two blades
        out["hub_rate"][i] = Om
        out["angular_momentum"][i] = H
        out["deployed_length"][i] = lens.sum() + (lq if _payout(t[i], P)[2] else 0.0)
        tip = x[0] - np.array([0.0, 0.0, r])
        nt = np.sqrt(tip @ tip)
        out["tip_angle"][i] = np.arccos(np.clip(tip[0] / nt, -1, 1)) if nt > 0 else 0.0
        signed[i] = np.arctan2(tip[1], tip[0]) if nt > 0 else 0.0
        kin[i] = T
        out["energy_balance"][i] = T + U  # completed by the caller (Q-spring, D, W)
        del t_l0
    return out, signed, kin


def _q_spring_energy(Y, b_out, t, P):
    n = int(P[NN])
    r, c = P[RR], P[CC]
    e = np.zeros(len(Y))
    for i in range(len(Y)):
        b = int(b_out[i])
        xb = Y[i, OFF + 3 * b:OFF + 3 * b + 3]
        lq = np.sqrt(xb[0]**2 + xb[1]**2 + (xb[2] - r)**2)
        paid, rw, q_on = _payout(t[i], P)
        s = lq - (paid - P[L0] * b)
        e[i] = 0.5 * c * s * s if q_on else 0.0
    return e


def stable_dt_rk4(params, safety=0.8):
    """Largest stable RK4 step estimated from the highest chain frequency (see docstring)."""
    n = int(params["n"])
    m_min = params["rho_L"] * params["L"] / n
    m_hub = params["J_hub"] / (2 * params["L_c"] ** 2)     # hub's reduced mass at Q, per blade
    m_eff = 1.0 / (1.0 / m_min + 1.0 / m_hub) if m_hub < 10 * m_min else m_min
    lam = 2.0 * np.sqrt(params["stiffness"] / m_eff) + 4.0 * params["damping"] / m_eff
    return safety * 2.785 / lam


def _breakpoints(t_out, P):
    """Merged step breakpoints: (times, output index or −1, node released or −1). Outputs,
    releases t_j = j Δφ/ω (j ≥ 1) and the end of payout t_full = L/(r ω), where the payout
    speed drops to 0, so that no step straddles a kink."""
    n = int(P[NN])
    t_end = t_out[-1]
    ev = {}
    for i, t in enumerate(t_out):
        ev[round(float(t), 10)] = [float(t), i, -1]
    t_full = P[LL] / (P[RR] * P[WSP])
    extra = [(P[DPHI] * j / P[WSP], j) for j in range(1, n)] + [(t_full, -1)]
    for t, j in extra:
        if t >= t_end - 1e-12:
            continue
        key = round(float(t), 10)
        if key in ev:
            ev[key][2] = max(ev[key][2], j)
        else:
            ev[key] = [float(t), -1, j]
    rows = sorted(ev.values())
    return (np.array([r[0] for r in rows]), np.array([r[1] for r in rows], np.int64),
            np.array([r[2] for r in rows], np.int64))


def formula18(params, t, printed=False):
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


def formula18_discrete(params, t):
    """Formula 18 for the lumped model itself: the released nodes on a straight radial line at
    their unstretched positions (boundary node at l0(t) from Q, then every l0), stored nodes at
    L_c, conservative bookkeeping. Differs from the continuous formula by O(l0) lumping."""
    n = int(params["n"])
    L, r, w, Lc = params["L"], params["r"], params["omega_spool"], params["L_c"]
    l0 = L / n
    m = np.full(n, params["rho_L"] * l0)
    m[0] += params["tip_mass"]
    J = params["J_hub"]
    I0 = J + 2 * m.sum() * Lc**2
    t = np.asarray(t, float)
    out = np.empty_like(t)
    for i, ti in enumerate(t):
        phi = min(w * ti, L / r)
        b = min(int(np.floor(phi * n * r / L + 1e-12)), n - 1)
        lt = r * phi - l0 * b
        R = Lc + lt + l0 * (b - np.arange(b + 1))
        I = J + 2 * (np.sum(m[:b + 1] * R**2) + m[b + 1:].sum() * Lc**2)
        out[i] = I0 * params["Omega0"] / I
    return out


def yoyo_despin(params, ell):
    """Classic yo-yo despin closed form (two tip masses m on massless cords unwinding
    tangentially from a hub of radius R = L_c, cords free — no spool): with
    k² = (J + 2 m R²)/(2 m R²) and λ = ℓ/R, Ω = Ω0 (k² − λ²)/(k² + λ²); zero at ℓ = R k.
    Used only as a comparison for light hubs (our payout is prescribed, not free)."""
    R, J, mk = params["L_c"], params["J_hub"], params["tip_mass"] + params["rho_L"] * params["L"]
    k2 = (J + 2 * mk * R**2) / (2 * mk * R**2)
    lam2 = (np.asarray(ell) / R) ** 2
    return params["Omega0"] * (k2 - lam2) / (k2 + lam2)


def _merge_settings(settings):
    s = dict(DEFAULT_SETTINGS)
    if settings:
        unknown = set(settings) - set(DEFAULT_SETTINGS)
        if unknown:
            raise ValueError(f"unknown settings {sorted(unknown)}")
        s.update(settings)
    if s["integrator"] not in INTEGRATORS:
        raise ValueError(f"integrator must be one of {INTEGRATORS}")
    return s


def simulate(params, t_out, settings=None):
    """Leaf-model contract (reference_models/README.md)."""
    s = _merge_settings(settings)
    params = {**DEFAULT_PARAMS, **params}
    t_out = np.asarray(t_out, float)
    if t_out[0] != 0.0 or np.any(np.diff(t_out) <= 0):
        raise ValueError("t_out must start at 0 and be strictly increasing")
    P, m, used = pack(params, s)
    n = int(P[NN])
    dt = s["dt"]
    if dt is None or dt == "auto":
        dt = stable_dt_rk4(params) if s["integrator"] == "rk4" else AUTO_DT["imr"]
    dt = float(dt)
    if not dt > 0:
        raise ValueError("dt must be > 0")
    bt, bo, br = _breakpoints(t_out, P)
    y0 = np.zeros(OFF + 6 * n)
    y0[0] = P[OM0]
    inertial = s["integrator"] == "imr"
    if inertial:                      # stored nodes parked at Q (irrelevant until released)
        for j in range(n):
            y0[OFF + 3 * j:OFF + 3 * j + 3] = (P[LC], 0.0, P[RR])
    else:
        for j in range(n):
            y0[OFF + 3 * j:OFF + 3 * j + 3] = (0.0, 0.0, P[RR])
    w0 = time.perf_counter()
    if inertial:
        Y, b_out, wrel, steps, evals, t_fail, code = _run_imr(y0, P, m, bt, bo, br, dt,
                                                              len(t_out), s["newton_tol"])
        Yb = inertial_to_body(Y, n, P[LC])
    else:
        Y, b_out, wrel, steps, evals, t_fail, code = _run_rk4(y0, P, m, bt, bo, br, dt,
                                                              len(t_out))
        Yb = Y
    wall = time.perf_counter() - w0
    ch, signed, kin = channels_from_body(Yb, b_out, wrel, P, m, t_out)
    eq = _q_spring_energy(Yb, b_out, t_out, P)
    ch["energy_balance"] = (ch["energy_balance"] + 2 * eq + 2 * Yb[:, 2] - 2 * Yb[:, 3]
                            - 2 * wrel)
    status, reason = "ok", None
    if code != 0:
        status = "diverged"
        reason = REASONS.get(int(code), f"code {code}")
        if code in (FAIL_STRETCH, FAIL_NONFINITE) and s["integrator"] == "rk4":
            hs = stable_dt_rk4(params)
            reason = (f"unstable step: {reason} (dt={dt:.3g} s; estimated RK4 stability limit "
                      f"{hs / 0.8:.3g} s, use dt<={hs:.3g} or integrator='imr')"
                      if dt > hs / 0.8 else reason)
        for k in ch:
            ch[k][t_out > t_fail] = np.nan
        signed[t_out > t_fail] = np.nan
    extra = {"hub_rate_formula18": formula18(params, t_out),
             "hub_rate_formula18_discrete": formula18_discrete(params, t_out),
             "hub_rate_formula18_printed": formula18(params, t_out, printed=True),
             "tip_angle_signed": signed, "kinetic_energy": kin,
             "boundary_node": b_out.astype(float),
             "dissipated": 2 * Yb[:, 2], "payout_work": 2 * Yb[:, 3] + 2 * wrel}
    used_settings = {**s, **used, "dt": dt}
    return {"channels": ch, "status": status,
            "t_fail": None if code == 0 else float(t_fail), "reason": reason,
            "stats": {"steps": int(steps), "rhs_evals": int(evals) if not inertial else -1,
                      "newton_iterations": int(evals) % 1000000000 if inertial else 0,
                      "step_retries": int(evals) // 1000000000 if inertial else 0,
                      "wall_s": wall},
            "settings": used_settings, "extra": extra}
