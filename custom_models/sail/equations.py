"""Forces of the thread-spool model: the spring–damper law shared by both frames, the rotating-
frame right-hand side of the paper (§IV, eqs. 14–16) and the energy–momentum (discrete-gradient)
spring forces of the inertial implicit midpoint rule.

Groups of nodes at any time (b = index of the boundary node = the last released one):
- stored (j > b): on the spool, prescribed, no force on the released thread;
- boundary (j = b): spring–damper to node b−1 (rest l0) and to Q with the variable rest length
  l0(t) = r(φ − Δφ b) [10]; when |Q − x_b| < eps the direction node→Q is taken as −e_x (paper
  eq. 11: {−1, 0, 0});
- free (j < b): spring–dampers (c, d) to both neighbours [3, 4] (the tip has one).
Rotating frame [14]: F_x = m(Ω' y + Ω²(x + L_c) + 2Ω y'), F_y = m(−Ω'(x + L_c) + Ω² y − 2Ω x'),
checked against −m Ω'×ρ − m Ω×(Ω×ρ) − 2m Ω×v. Hub [15, 16]: J Ω' = M_z = −2 L_c F_Qy (F_Q: the
force of the Q-spring on the boundary node; two symmetric blades).
"""
import numba as nb
import numpy as np

from .model import CC, DD, EPS, L0, LC, NN, OFF, QDAMP, RR, j_eff, payout


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
def _forces(t, y, P, m, b, Q, VQ, pdir, F):
    """Spring–damper forces on nodes 0..b (frame-independent law; positions/velocities from y,
    Q its position, VQ the material velocity of the hub point Q, p the payout direction, all in
    the frame of y). Fills F[0..3b+2]. Returns (F_Q on node b: fx, fy, fz, dissipation rate,
    payout power), one blade."""
    Q0, Q1, Q2 = Q
    VQ0, VQ1, VQ2 = VQ
    p0, p1, p2 = pdir
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
    paid, rw, q_on = payout(t, P)
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
    fqx, fqy, fqz, diss, wsp = _forces(t, y, P, m, b, (0.0, 0.0, P[RR]), (0.0, 0.0, 0.0),
                                       (1.0, 0.0, 0.0), F)
    Om = y[0]
    Mz = -2.0 * P[LC] * fqy                         # [15]: reaction at Q, arm L_c, two blades
    Omd = Mz / j_eff(P, m, b)
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
    paid, rw, q_on = payout(t, P)
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
def _forces_dg(tm, Ym, P, m, b, Q, VQ, pdir, w):
    """Energy–momentum (discrete-gradient) spring forces at the step midpoint (Simo & Tarnow
    1992 for a spring V = ½c(ℓ − l0)²): force on a = c(1 − l0/ℓ̄)(x_b − x_a)_mid with
    ℓ̄ = (ℓ_start + ℓ_end)/2. The work over the step is exactly −ΔV (no energy pumping by the
    unresolved longitudinal modes) and the force stays along the midpoint chord (angular
    momentum exact under the midpoint rule). Dampers: midpoint velocities along the midpoint
    chord. w.TR[j] receives the transverse stiffness c(1 − l0/ℓ̄) for the Newton matrix; w.l_a,
    w.l_e hold the spring lengths at the start and end of the step, w.F receives the forces."""
    Q0, Q1, Q2 = Q
    VQ0, VQ1 = VQ
    p0, p1, p2 = pdir
    l_a, l_e, F, TR = w.l_a, w.l_e, w.F, w.TR
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
    paid, rw, q_on = payout(tm, P)
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
