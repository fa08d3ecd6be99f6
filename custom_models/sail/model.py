"""The thread-spool model's data: the scene's resolved parameters and the variant switches packed
into one float array P for the compiled code, the state layout, the hub inertia and the payout
(the shared law of compare.physics.sail).

State y = [Ω, ψ, D (dissipated, one blade), W (payout work, one blade), x (3n), v (3n)]: nodes
0 (tip) … n−1, in the body frame (rk4) or the inertial frame (imr).
"""
from collections import namedtuple

import numba as nb
import numpy as np

from compare.physics import sail as phys

VARIANTS = ("paper", "conservative")

# packed parameter array
(JH, RHO, LL, LC, RR, OM0, WSP, MK, NN, CC, DD, L0, DPHI, STORED, TURN, QDAMP, EPS, SLIM,
 ENDREL) = range(19)
NP = 19
OFF = 4                       # x starts at y[OFF], v at y[OFF + 3n]

# working arrays of one implicit-midpoint step (n nodes, ny state entries): forces F, midpoint
# state Ym and end state Y1, the bordered block-tridiagonal Newton system (Dm, Bm, Dinv, U, R,
# X, G) and its solver's scratch (Wf, Xu), spring lengths at the step's start and end (l_a,
# l_e), transverse stiffnesses TR, the state saved for a retried step (ysave)
ImrWork = namedtuple("ImrWork", "F Ym Y1 Dm Bm Dinv U R X G Wf Xu l_a l_e TR ysave")


@nb.njit(cache=True)
def imr_work(n, ny):
    return ImrWork(np.empty(3 * n), np.empty(ny), np.empty(ny), np.empty((n, 3, 3)),
                   np.zeros((n, 3, 3)), np.empty((n, 3, 3)), np.zeros((n, 3)),
                   np.zeros((n, 3)), np.zeros((n, 3)), np.empty((3, 3)), np.empty((2, 3, 3)),
                   np.empty((n, 3)), np.empty(n), np.empty(n), np.empty(n), np.empty(ny))


def variant_switches(settings: dict) -> dict:
    """The three ingredients of a variant, each switchable alone (None: the variant's own)."""
    variant = settings["variant"]
    if variant not in VARIANTS:
        raise ValueError(f"variant must be one of {VARIANTS}, got {variant!r}")
    paper = variant == "paper"
    turn, stored, qd = settings["velocity_turn"], settings["stored_in_hub"], settings["q_damper"]
    turn = paper if turn is None else bool(turn)
    stored = (not paper) if stored is None else bool(stored)
    qd = ("paper" if paper else "stretch") if qd is None else qd
    if qd not in ("paper", "stretch"):
        raise ValueError(f"q_damper must be 'paper' or 'stretch', got {qd!r}")
    return {"velocity_turn": turn, "stored_in_hub": stored, "q_damper": qd}


def pack(params: dict, settings: dict) -> tuple:
    """(P, node masses m, the variant switches used)."""
    n, l0, m, _ = phys.thread(params)
    sw = variant_switches(settings)
    P = np.zeros(NP)
    P[JH], P[RHO], P[LL], P[LC], P[RR] = (params["J_hub"], params["rho_L"], params["L"],
                                          params["L_c"], params["r"])
    P[OM0], P[WSP], P[MK], P[NN] = params["Omega0"], params["omega_spool"], params["tip_mass"], n
    P[CC], P[DD], P[L0], P[DPHI] = params["stiffness"], params["damping"], l0, l0 / params["r"]
    P[STORED], P[TURN] = float(sw["stored_in_hub"]), float(sw["velocity_turn"])
    P[QDAMP] = 1.0 if sw["q_damper"] == "paper" else 0.0
    P[EPS], P[SLIM] = settings["eps_fallback"], settings["stretch_limit"]
    P[ENDREL] = float(params["last_node"] == "released")
    return P, m, sw


@nb.njit(cache=True)
def j_eff(P, m, b):
    """Hub inertia of the whole craft (both blades' stored thread if counted)."""
    J = P[JH]
    if P[STORED] > 0.5:
        s = 0.0
        for j in range(b + 1, m.shape[0]):
            s += m[j]
        J += 2.0 * P[LC] ** 2 * s
    return J


@nb.njit(cache=True)
def payout(t, P):
    """(paid-out length, payout speed, Q-spring on) at t: the shared payout law."""
    return phys.payout(t, P[LL], P[RR] * P[WSP], P[ENDREL] > 0.5)


def stable_dt_rk4(params: dict, safety: float = 0.8) -> float:
    """Largest stable RK4 step estimated from the highest chain frequency
    λ_max = 2 sqrt(c/m_min) + 4 d/m_min, m_min including the hub's reduced mass at Q; RK4's
    stability interval on the imaginary axis is 2.785."""
    n = int(params["n"])
    m_min = params["rho_L"] * params["L"] / n
    m_hub = params["J_hub"] / (2 * params["L_c"] ** 2)     # hub's reduced mass at Q, per blade
    m_eff = 1.0 / (1.0 / m_min + 1.0 / m_hub) if m_hub < 10 * m_min else m_min
    lam = 2.0 * np.sqrt(params["stiffness"] / m_eff) + 4.0 * params["damping"] / m_eff
    return safety * 2.785 / lam
