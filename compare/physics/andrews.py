"""Andrews' squeezing mechanism (scene `andrews-squeezer`): the IVP Test Set's equations (Mazzia
& Magherini, problem "andrews"; Hairer & Wanner II §VII.7; Schiehlen 1990) that every solver of
the scene computes alike — parameters, M(q), f(q, q'), the loop closure g(q) and its Jacobian,
the joint points the engines build their bodies from, the energy terms — and the reference
integration in index-1 form with scipy at tight tolerance. Numpy and numba only (leaves import it).

Coordinates q = (β, Θ, γ, Φ, δ, Ω, ε), the test set's order: β the crank K1 (about O), Θ the
rod K2 relative to the crank, γ K3 (about B), Φ K4 relative to K5, δ K5 (about A), Ω K6
relative to K7, ε K7 (about A). T = ½ q'ᵀ M(q) q'; f holds the motor torque `mom` on β, the
spring c0 (rest length l0) between D on K3 and the fixed point C, and the velocity terms of
the relative coordinates. Six loop-closure equations g(q) = 0 (two loops).
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np

from ..contract import Channel

ANGLES = ("beta", "theta", "gamma", "phi", "delta", "omega", "epsilon")
CHANNELS = (*(Channel(a, "rad") for a in ANGLES), Channel("energy_balance", "J"),
            Channel("kinetic_energy", "J"), Channel("spring_energy", "J"))

# the test set's parameter names and values (SI: kg, m, kg·m², N/m, N·m), in its order
PARAMS = (
    ("m1", 0.04325), ("m2", 0.00365), ("m3", 0.02373), ("m4", 0.00706), ("m5", 0.07050),
    ("m6", 0.00706), ("m7", 0.05498),
    ("xa", -0.06934), ("ya", -0.00227), ("xb", -0.03635), ("yb", 0.03273), ("xc", 0.014),
    ("yc", 0.072), ("c0", 4530.0),
    ("I1", 2.194e-6), ("I2", 4.410e-7), ("I3", 5.255e-6), ("I4", 5.667e-7), ("I5", 1.169e-5),
    ("I6", 5.667e-7), ("I7", 1.912e-5),
    ("d", 28e-3), ("da", 115e-4), ("e", 2e-2), ("ea", 1421e-5), ("rr", 7e-3), ("ra", 92e-5),
    ("l0", 7785e-5), ("ss", 35e-3), ("sa", 1874e-5), ("sb", 1043e-5), ("sc", 18e-3),
    ("sd", 2e-2), ("ta", 2308e-5), ("tb", 916e-5), ("u", 4e-2), ("ua", 1228e-5),
    ("ub", 449e-5), ("zf", 2e-2), ("zt", 4e-2), ("fa", 1421e-5), ("mom", 33e-3))
NAMES = tuple(n for n, _ in PARAMS)
(M1, M2, M3, M4, M5, M6, M7, XA, YA, XB, YB, XC, YC, C0, I1, I2, I3, I4, I5, I6, I7, D, DA, E,
 EA, RR, RA, L0, SS, SA, SB, SC, SD, TA, TB, U, UA, UB, ZF, ZT, FA, MOM) = range(len(PARAMS))

# the test set's consistent initial angles (all velocities 0)
Q0 = np.array([-0.0617138900142764496358948458001, 0.0, 0.455279819163070380255912382449,
               0.222668390165885884674473185609, 0.487364979543842550225598953530,
               -0.222668390165885884674473185609, 1.23054744454982119249735015568])
# the test set's initial accelerations and multipliers (y(15:21), y(22:27))
W0 = np.array([14222.4439199541138705911625887, -10666.8329399655854029433719415,
               0.0, 0.0, 0.0, 0.0, 0.0])
LAMBDA0 = np.array([98.5668703962410896057654982170, -6.12268834425566265503114393122,
                    0.0, 0.0, 0.0, 0.0])
# the test set's reference solution at t = 0.03 s (PSIDE, rtol = atol = 1e-14, Cray C90): the
# angles y(1:7) and their rates y(8:14)
T_REF = 0.03
Q_REF = np.array([0.1581077119629904e2, -0.1575637105984298e2, 0.4082224013073101e-1,
                  -0.5347301163226948, 0.5244099658805304, 0.5347301163226948,
                  0.1048080741042263e1])
QD_REF = np.array([0.1139920302151208e4, -0.1424379294994111e4, 0.1103291221937134e2,
                   0.1929337464421385e2, 0.5735699284790808, -0.1929337464421385e2,
                   0.3231791658026955])


def pack(params: dict) -> np.ndarray:
    """The resolved parameters as one float array in the test set's order."""
    return np.array([float(params[n]) for n in NAMES])


@nb.njit(cache=True)
def mass_matrix(q, p):
    """The test set's M(q) (7×7, symmetric)."""
    m = np.zeros((7, 7))
    coth, siph, siom = math.cos(q[1]), math.sin(q[3]), math.sin(q[5])
    e_ea, zf_fa = p[E] - p[EA], p[ZF] - p[FA]
    m[0, 0] = (p[M1] * p[RA] ** 2 + p[M2] * (p[RR] ** 2 - 2 * p[DA] * p[RR] * coth + p[DA] ** 2)
               + p[I1] + p[I2])
    m[1, 0] = p[M2] * (p[DA] ** 2 - p[DA] * p[RR] * coth) + p[I2]
    m[1, 1] = p[M2] * p[DA] ** 2 + p[I2]
    m[2, 2] = p[M3] * (p[SA] ** 2 + p[SB] ** 2) + p[I3]
    m[3, 3] = p[M4] * e_ea ** 2 + p[I4]
    m[4, 3] = p[M4] * (e_ea ** 2 + p[ZT] * e_ea * siph) + p[I4]
    m[4, 4] = (p[M4] * (p[ZT] ** 2 + 2 * p[ZT] * e_ea * siph + e_ea ** 2)
               + p[M5] * (p[TA] ** 2 + p[TB] ** 2) + p[I4] + p[I5])
    m[5, 5] = p[M6] * zf_fa ** 2 + p[I6]
    m[6, 5] = p[M6] * (zf_fa ** 2 - p[U] * zf_fa * siom) + p[I6]
    m[6, 6] = (p[M6] * (zf_fa ** 2 - 2 * p[U] * zf_fa * siom + p[U] ** 2)
               + p[M7] * (p[UA] ** 2 + p[UB] ** 2) + p[I6] + p[I7])
    for i in range(7):
        for j in range(i):
            m[j, i] = m[i, j]
    return m


@nb.njit(cache=True)
def spring_point(q, p):
    """D, the spring's end on K3 (the other end is the fixed point C)."""
    coga, siga = math.cos(q[2]), math.sin(q[2])
    return p[SD] * coga + p[SC] * siga + p[XB], p[SD] * siga - p[SC] * coga + p[YB]


@nb.njit(cache=True)
def spring_length(q, p):
    xd, yd = spring_point(q, p)
    return math.sqrt((xd - p[XC]) ** 2 + (yd - p[YC]) ** 2)


@nb.njit(cache=True)
def forces(q, qd, p):
    """The test set's f(q, q'): applied forces and the velocity terms of T."""
    ff = np.empty(7)
    coga, siga = math.cos(q[2]), math.sin(q[2])
    xd, yd = spring_point(q, p)
    lang = math.sqrt((xd - p[XC]) ** 2 + (yd - p[YC]) ** 2)
    force = -p[C0] * (lang - p[L0]) / lang
    fx, fy = force * (xd - p[XC]), force * (yd - p[YC])
    sith, coph, coom = math.sin(q[1]), math.cos(q[3]), math.cos(q[5])
    bep, thp, php, dep, omp, epp = qd[0], qd[1], qd[3], qd[4], qd[5], qd[6]
    e_ea, zf_fa = p[E] - p[EA], p[ZF] - p[FA]
    ff[0] = p[MOM] - p[M2] * p[DA] * p[RR] * thp * (thp + 2 * bep) * sith
    ff[1] = p[M2] * p[DA] * p[RR] * bep ** 2 * sith
    ff[2] = fx * (p[SC] * coga - p[SD] * siga) + fy * (p[SD] * coga + p[SC] * siga)
    ff[3] = p[M4] * p[ZT] * e_ea * dep ** 2 * coph
    ff[4] = -p[M4] * p[ZT] * e_ea * php * (php + 2 * dep) * coph
    ff[5] = -p[M6] * p[U] * zf_fa * epp ** 2 * coom
    ff[6] = p[M6] * p[U] * zf_fa * omp * (omp + 2 * epp) * coom
    return ff


@nb.njit(cache=True)
def closure(q, p):
    """g(q): the six loop-closure equations (the crank-rod joint E reached three ways)."""
    g = np.empty(6)
    ex = p[RR] * math.cos(q[0]) - p[D] * math.cos(q[0] + q[1])
    ey = p[RR] * math.sin(q[0]) - p[D] * math.sin(q[0] + q[1])
    g[0] = ex - p[SS] * math.sin(q[2]) - p[XB]
    g[1] = ey + p[SS] * math.cos(q[2]) - p[YB]
    g[2] = ex - p[E] * math.sin(q[3] + q[4]) - p[ZT] * math.cos(q[4]) - p[XA]
    g[3] = ey + p[E] * math.cos(q[3] + q[4]) - p[ZT] * math.sin(q[4]) - p[YA]
    g[4] = ex - p[ZF] * math.cos(q[5] + q[6]) - p[U] * math.sin(q[6]) - p[XA]
    g[5] = ey - p[ZF] * math.sin(q[5] + q[6]) + p[U] * math.cos(q[6]) - p[YA]
    return g


@nb.njit(cache=True)
def closure_jacobian(q, p):
    """G = ∂g/∂q (6×7), the test set's gp."""
    G = np.zeros((6, 7))
    sibe, cobe = math.sin(q[0]), math.cos(q[0])
    sibeth, cobeth = math.sin(q[0] + q[1]), math.cos(q[0] + q[1])
    siga, coga = math.sin(q[2]), math.cos(q[2])
    side, code = math.sin(q[4]), math.cos(q[4])
    siphde, cophde = math.sin(q[3] + q[4]), math.cos(q[3] + q[4])
    siep, coep = math.sin(q[6]), math.cos(q[6])
    siomep, coomep = math.sin(q[5] + q[6]), math.cos(q[5] + q[6])
    for r in (0, 2, 4):
        G[r, 0] = -p[RR] * sibe + p[D] * sibeth
        G[r, 1] = p[D] * sibeth
        G[r + 1, 0] = p[RR] * cobe - p[D] * cobeth
        G[r + 1, 1] = -p[D] * cobeth
    G[0, 2] = -p[SS] * coga
    G[1, 2] = -p[SS] * siga
    G[2, 3] = -p[E] * cophde
    G[2, 4] = -p[E] * cophde + p[ZT] * side
    G[3, 3] = -p[E] * siphde
    G[3, 4] = -p[E] * siphde - p[ZT] * code
    G[4, 5] = p[ZF] * siomep
    G[4, 6] = p[ZF] * siomep - p[U] * coep
    G[5, 5] = -p[ZF] * coomep
    G[5, 6] = -p[ZF] * coomep - p[U] * siep
    return G


@nb.njit(cache=True)
def closure_curvature(q, qd, p):
    """h(q, q') = (∂(G q')/∂q) q', so that G q'' + h = 0 on the constraint manifold."""
    h = np.empty(6)
    b, bt = qd[0], qd[0] + qd[1]
    ex = -p[RR] * math.cos(q[0]) * b * b + p[D] * math.cos(q[0] + q[1]) * bt * bt
    ey = -p[RR] * math.sin(q[0]) * b * b + p[D] * math.sin(q[0] + q[1]) * bt * bt
    pd, dd = qd[3] + qd[4], qd[4]
    oe, ee = qd[5] + qd[6], qd[6]
    h[0] = ex + p[SS] * math.sin(q[2]) * qd[2] ** 2
    h[1] = ey - p[SS] * math.cos(q[2]) * qd[2] ** 2
    h[2] = ex + p[E] * math.sin(q[3] + q[4]) * pd * pd + p[ZT] * math.cos(q[4]) * dd * dd
    h[3] = ey - p[E] * math.cos(q[3] + q[4]) * pd * pd + p[ZT] * math.sin(q[4]) * dd * dd
    h[4] = ex + p[ZF] * math.cos(q[5] + q[6]) * oe * oe + p[U] * math.sin(q[6]) * ee * ee
    h[5] = ey + p[ZF] * math.sin(q[5] + q[6]) * oe * oe - p[U] * math.cos(q[6]) * ee * ee
    return h


def _rot(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s], [s, c]])


# the body angles (K1…K7 in the plane) from q, and back: K2 turns by β + Θ, K4 by Φ + δ, K6 by
# Ω + ε (the test set's relative angles)
def body_angles(q):
    be, th, ga, ph, de, om, ep = (float(x) for x in q)
    return np.array([be, be + th, ga, ph + de, de, om + ep, ep])


def angles_from_bodies(a):
    """q from the seven body angles (arrays of any shape along the last axis)."""
    a = np.asarray(a, float)
    return np.stack([a[..., 0], a[..., 1] - a[..., 0], a[..., 2], a[..., 3] - a[..., 4],
                     a[..., 4], a[..., 5] - a[..., 6], a[..., 6]], axis=-1)


def body_layout(params: dict):
    """Each body K1…K7 as (mass, inertia about its centre of mass, {point: local position from
    the centre of mass at body angle 0}) — the geometry the test set's M(q) and g(q) encode:
    K1 turns about O with its centre of mass at ra along the crank and the joint P (to K2) at
    rr; K2 runs from P back to E (length d), centre of mass da from P; K3 turns about B with E
    at R(γ)(0, −ss) and the spring end D at R(γ)(sd, −sc); K4 runs from G (on K5) to E at
    R(Φ+δ)(0, −e), centre of mass ea from E; K5 turns about A with G at R(δ)(zt, 0); K6 runs
    from H (on K7) to E at R(Ω+ε)(zf, 0), centre of mass fa from E; K7 turns about A with H at
    R(ε)(0, −u). The bodies turning about a fixed point (K1, K3, K5, K7; no gravity) enter
    the dynamics only through their inertia about it, m (a² + b²) + I: their centres of mass
    are put at (sa, sb), (ta, tb), (ua, ub) in their frames about the pivot."""
    P = {n: float(params[n]) for n in NAMES}
    v = np.array
    e_ea, zf_fa = P["e"] - P["ea"], P["zf"] - P["fa"]
    return {
        "K1": (P["m1"], P["I1"], {"O": v([-P["ra"], 0.0]), "P": v([P["rr"] - P["ra"], 0.0])}),
        "K2": (P["m2"], P["I2"], {"P": v([P["da"], 0.0]), "E": v([P["da"] - P["d"], 0.0])}),
        "K3": (P["m3"], P["I3"], {"B": v([-P["sa"], -P["sb"]]),
                                  "E": v([-P["sa"], -P["ss"] - P["sb"]]),
                                  "D": v([P["sd"] - P["sa"], -P["sc"] - P["sb"]])}),
        "K4": (P["m4"], P["I4"], {"G": v([0.0, e_ea]), "E": v([0.0, -P["ea"]])}),
        "K5": (P["m5"], P["I5"], {"A": v([-P["ta"], -P["tb"]]),
                                  "G": v([P["zt"] - P["ta"], -P["tb"]])}),
        "K6": (P["m6"], P["I6"], {"H": v([-zf_fa, 0.0]), "E": v([P["fa"], 0.0])}),
        "K7": (P["m7"], P["I7"], {"A": v([-P["ua"], -P["ub"]]),
                                  "H": v([-P["ua"], -P["u"] - P["ub"]])}),
    }


FIXED = {"O": ("xo", "yo"), "A": ("xa", "ya"), "B": ("xb", "yb"), "C": ("xc", "yc")}
# the revolute joints: (body, point, body or None = ground, point); ten joints on seven bodies
# leave one degree of freedom (21 coordinates, 20 constraints)
JOINTS = (("K1", "O", None, "O"), ("K1", "P", "K2", "P"), ("K3", "B", None, "B"),
          ("K5", "A", None, "A"), ("K7", "A", None, "A"), ("K5", "G", "K4", "G"),
          ("K7", "H", "K6", "H"), ("K2", "E", "K3", "E"), ("K2", "E", "K4", "E"),
          ("K2", "E", "K6", "E"))


def fixed_point(name, params):
    return np.zeros(2) if name == "O" else np.array([float(params[c]) for c in FIXED[name]])


def body_poses(q, params):
    """Each body's centre of mass (m) and angle (rad) at angles q, placed from the fixed pivots
    through the layout (K2, K4, K6 from their joints P, G, H)."""
    lay = body_layout(params)
    ang = dict(zip(("K1", "K2", "K3", "K4", "K5", "K6", "K7"), body_angles(q)))
    pose = {}

    def place(body, point, at):
        pose[body] = (at - _rot(ang[body]) @ lay[body][2][point], ang[body])

    def world(body, point):
        c, a = pose[body]
        return c + _rot(a) @ lay[body][2][point]
    place("K1", "O", fixed_point("O", params))
    place("K3", "B", fixed_point("B", params))
    place("K5", "A", fixed_point("A", params))
    place("K7", "A", fixed_point("A", params))
    place("K2", "P", world("K1", "P"))
    place("K4", "G", world("K5", "G"))
    place("K6", "H", world("K7", "H"))
    return pose, world


@nb.njit(cache=True)
def energy(q, qd, p):
    """(kinetic, spring potential) in J."""
    m = mass_matrix(q, p)
    T = 0.0
    for i in range(7):
        for j in range(7):
            T += 0.5 * qd[i] * m[i, j] * qd[j]
    ell = spring_length(q, p)
    return T, 0.5 * p[C0] * (ell - p[L0]) ** 2


def energy_channels(Q, QD, p) -> dict:
    """The energy balance T + V_spring − mom·(β − β₀) − E₀ (J; zero for an exact solution: the
    motor torque's work is mom·Δβ), T and V_spring, from any solver's angles and rates on its
    grid."""
    Q, QD = np.asarray(Q, float), np.asarray(QD, float)
    n = len(Q)
    T, V = np.full(n, np.nan), np.full(n, np.nan)
    for i in range(n):
        if np.all(np.isfinite(Q[i])) and np.all(np.isfinite(QD[i])):
            T[i], V[i] = energy(np.ascontiguousarray(Q[i]), np.ascontiguousarray(QD[i]), p)
    work = p[MOM] * (Q[:, 0] - Q[0, 0])
    return {"energy_balance": T + V - work - (T[0] + V[0]), "kinetic_energy": T,
            "spring_energy": V}


def channels(Q, QD, p) -> dict:
    """The scene's channels from a solver's angles Q (n, 7) and rates QD (n, 7)."""
    Q = np.asarray(Q, float)
    return {**{a: Q[:, k].copy() for k, a in enumerate(ANGLES)}, **energy_channels(Q, QD, p)}


@nb.njit(cache=True)
def index1_rhs(q, qd, p):
    """q'' and λ of the index-1 form [[M, Gᵀ], [G, 0]] [q''; λ] = [f; −h]."""
    K = np.zeros((13, 13))
    r = np.zeros(13)
    K[:7, :7] = mass_matrix(q, p)
    G = closure_jacobian(q, p)
    K[:7, 7:] = G.T
    K[7:, :7] = G
    r[:7] = forces(q, qd, p)
    r[7:] = -closure_curvature(q, qd, p)
    x = np.linalg.solve(K, r)
    return x[:7], x[7:]


def reference(params: dict, t_out, rtol: float = 1e-12, atol: float = 1e-12,
              method: str = "DOP853"):
    """The reference integration: the index-1 form with scipy's `method` at `rtol`, projected
    back onto g = 0 and G q' = 0 at every output time (the drift of the index-1 form is far
    below rtol over 0.03 s; the projection only keeps the outputs consistent). Returns
    (Q (n, 7), QD (n, 7), scipy's result)."""
    from scipy.integrate import solve_ivp
    p = pack(params)
    y0 = np.concatenate([np.asarray(initial_angles(params)), np.zeros(7)])

    def rhs(t, y):
        qdd, _ = index1_rhs(y[:7], y[7:], p)
        return np.concatenate([y[7:], qdd])

    sol = solve_ivp(rhs, (0.0, float(t_out[-1])), y0, method=method, rtol=rtol, atol=atol,
                    t_eval=np.asarray(t_out, float), dense_output=False)
    Y = sol.y.T
    Q, QD = Y[:, :7].copy(), Y[:, 7:].copy()
    for i in range(len(Q)):
        Q[i] = project(Q[i], p)
        G = closure_jacobian(Q[i], p)
        QD[i] -= G.T @ np.linalg.solve(G @ G.T, G @ QD[i])
    return Q, QD, sol


def initial_angles(params: dict, tol: float = 1e-14, max_iter: int = 50) -> np.ndarray:
    """The consistent initial angles every solver starts from: the test set's where they close
    the loops (its geometry), else β₀ kept and the six others closed by Newton from the test
    set's values. ValueError where no assembly is found near them."""
    p = pack(params)
    q = Q0.copy()
    for _ in range(max_iter):
        g = closure(q, p)
        if np.max(np.abs(g)) <= tol:
            return q
        q[1:] -= np.linalg.solve(closure_jacobian(q, p)[:, 1:], g)
        if not np.all(np.isfinite(q)):
            break
    raise ValueError(f"the loops do not close at beta = {Q0[0]:.6g} rad with this geometry "
                     "(no assembly near the test set's)")


def project(q, p, max_iter=5):
    """q moved onto g = 0 along Gᵀ (Gauss–Newton, minimum norm)."""
    q = np.array(q, float)
    for _ in range(max_iter):
        g = closure(q, p)
        if np.max(np.abs(g)) < 1e-16:
            break
        G = closure_jacobian(q, p)
        q -= G.T @ np.linalg.solve(G @ G.T, g)
    return q
