"""Physics of the crank–rocker press (scenes `press`, `press-cycle`; seed 003, scene-press.md)
that every solver must compute alike: the motor characteristic, the working load, where the link
masses sit, the loop closure, the initial assembly, the cycle's breakpoints and the observables
built from a solver's kinematic output. Numpy and numba only (leaves import it).

Conventions: A = l1(cos φ, sin φ); B = C + l3(cos ψ, sin ψ) with C = (x_C, 0); |B − A| = l2;
θ2 is the direction A→B; assembly 1 has x_B > x_A. Angles in the parameters are degrees.
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np

from ..contract import Channel

# ---- motor 4A80B4U3, Kloss characteristic (scene-press.md) -----------------------------------
P_N, N_SYNC_RPM, S_N, LAMBDA_K = 1500.0, 1500.0, 0.058, 2.2
OMEGA_SYNC = 2.0 * math.pi * N_SYNC_RPM / 60.0
M_N = P_N / (OMEGA_SYNC * (1.0 - S_N))
M_K = LAMBDA_K * M_N
S_K = S_N * (LAMBDA_K + math.sqrt(LAMBDA_K ** 2 - 1.0))

# the parameters only `press-cycle` has: a leaf tells the two scenes apart by them
CYCLE_KEYS = ("lock_after", "lock_angle", "press_force", "press_force_vreg", "release_after")


def is_cycle(params: dict) -> bool:
    """press-cycle (lock/release) when the resolved parameters carry the lock parameters."""
    return "lock_after" in params


@nb.njit(cache=True)
def motor_torque(crank_rate: float, u: float) -> float:
    """Crank torque u·M(s), Kloss M = 2M_k/(s/s_k + s_k/s) written 2M_k s s_k/(s² + s_k²) so it
    is regular at synchronous speed (s = 0); slip s = 1 − u φ'/ω_sync."""
    s = 1.0 - u * crank_rate / OMEGA_SYNC
    return u * 2.0 * M_K * s * S_K / (s * s + S_K * S_K)


@nb.njit(cache=True)
def press_load(v: float, force: float, vreg: float) -> float:
    """Working load on the slider while locked (N): −F tanh(v / v_reg) (a Coulomb-type
    resistance, regularised so every solver integrates the same smooth law)."""
    return -force * math.tanh(v / vreg)


def press_power(v: float, a: float, force: float, vreg: float) -> tuple:
    """Power dissipated by the load, F tanh(v/v_reg) v, and its time derivative (for a Hermite
    quadrature of the press work)."""
    th = math.tanh(v / vreg)
    return force * th * v, force * (th + v / vreg * (1.0 - th * th)) * a


def crank_rotor_inertia(params: dict) -> float:
    """The motor rotor reflected to the crank, u²·J_rotor (the scene's `rotor_inertia`; 0, the
    paper's model, applies the motor characteristic to the crank without a rotor)."""
    u = float(params["gear_ratio"])
    return u * u * float(params["rotor_inertia"])


def link_layout(params: dict) -> dict:
    """Where each link's mass sits: {link: (com_x, mass, J)}, com_x measured along the link from
    its first point (crank O→A, rod A→B, rocker C→B); J about the centre of mass, the crank's
    including the rotor. "paper" (eq. 21): masses lumped at A, B and C (crank at A, rod at B,
    rocker at C); "midpoint": at the mid-links. The slider mass m4 sits at C."""
    mid = params["mass_model"] == "midpoint"
    l1, l2, l3 = float(params["l1"]), float(params["l2"]), float(params["l3"])
    return {
        "crank": (0.5 * l1 if mid else l1, float(params["m1"]),
                  float(params["J1"]) + crank_rotor_inertia(params)),
        "rod": (0.5 * l2 if mid else l2, float(params["m2"]), float(params["J2"])),
        "rocker": (0.5 * l3 if mid else 0.0, float(params["m3"]), float(params["J3"])),
    }


def assembly_sign(params: dict) -> float:
    return 1.0 if int(params["assembly"]) == 1 else -1.0


@nb.njit(cache=True)
def loop_closure(phi: float, psi: float, l1: float, l2: float, l3: float, sigma: float):
    """Joint positions from the loop closure (the paper's eq. 3, a quadratic in x_B, in closed
    form): x_B = x_A + σ√(l2² − (y_B − y_A)²). Returns (x_A, y_A, x_B, y_B, x_C, ok); ok = False
    where no real root exists."""
    xA, yA = l1 * math.cos(phi), l1 * math.sin(phi)
    yB = l3 * math.sin(psi)
    dy = yB - yA
    disc = l2 * l2 - dy * dy
    if disc < 0.0:
        return xA, yA, np.nan, yB, np.nan, False
    xB = xA + sigma * math.sqrt(disc)
    return xA, yA, xB, yB, xB - l3 * math.cos(psi), True


def initial_state(params: dict) -> dict:
    """Assembly and consistent velocities from (φ0, ψ0, φ̇0, ψ̇0): angles phi, theta2, psi (rad),
    their rates, the joint points A, B, C and their velocities. Raises ValueError where the loop
    cannot close or the root is double (rod vertical)."""
    l1, l2, l3 = float(params["l1"]), float(params["l2"]), float(params["l3"])
    phi, psi = math.radians(float(params["phi0"])), math.radians(float(params["psi0"]))
    phid, psid = float(params["omega0"]), float(params["rocker_rate0"])
    xA, yA, xB, yB, xC, ok = loop_closure(phi, psi, l1, l2, l3, assembly_sign(params))
    if not ok:
        raise ValueError(f"the loop cannot close at phi0={params['phi0']}, "
                         f"psi0={params['psi0']} deg (|y_B - y_A| > l2)")
    if abs(xB - xA) < 1e-9 * l2:
        raise ValueError("initial configuration is a double root (rod vertical): assembly "
                         "undefined")
    A, B, C = np.array([xA, yA]), np.array([xB, yB]), np.array([xC, 0.0])
    th2 = math.atan2(B[1] - A[1], B[0] - A[0])
    vA = l1 * phid * np.array([-math.sin(phi), math.cos(phi)])
    # rod rigid: the y-component of v_B = v_A + l2 θ̇2 (−sin θ2, cos θ2) must be l3 cos ψ ψ̇
    th2d = (l3 * math.cos(psi) * psid - vA[1]) / (l2 * math.cos(th2))
    vB = vA + l2 * th2d * np.array([-math.sin(th2), math.cos(th2)])
    vC = vB - l3 * psid * np.array([-math.sin(psi), math.cos(psi)])
    return {"phi": phi, "theta2": th2, "psi": psi, "phid": phid, "theta2d": th2d, "psid": psid,
            "A": A, "B": B, "C": C, "vA": vA, "vB": vB, "vC": vC}


def chain_jacobians(params: dict, th):
    """The open chain crank–rod–rocker (joint angles relative, as a kinematic tree has them;
    absolute link angles `th`): per link its mass, inertia, centre-of-mass Jacobian (2 × 3) and
    the lengths from the crank pivot to that centre along each link."""
    lay = link_layout(params)
    ls = [float(params["l1"]), float(params["l2"]), float(params["l3"])]
    along = [lay["crank"][0], lay["rod"][0], ls[2] - lay["rocker"][0]]   # rocker: from B
    out = []
    for b, (m, J) in enumerate(lay[k][1:] for k in ("crank", "rod", "rocker")):
        lens = ls[:b] + [along[b]]
        Jc = np.zeros((2, 3))
        for i in range(b + 1):
            for j in range(i, b + 1):
                Jc[:, i] += lens[j] * np.array([-math.sin(th[j]), math.cos(th[j])])
        out.append((m, J, Jc, lens))
    return out


def open_tree_at_start(params: dict):
    """The press as a kinematic tree whose loop is closed at C by a constraint (how an engine
    builds it: crank → rod → rocker, the slider apart), at the initial state: mass matrix M,
    generalized forces less velocity terms Q − h, the loop's Jacobian G (2 × 4, C on the rocker
    minus the slider) and its velocity term γ, over q = (crank, rod − crank, rocker − rod,
    slider x). qacc = M⁻¹(Q − h) is the tree's free acceleration; with the constraint force
    f = −(G M⁻¹ Gᵀ)⁻¹ (G qacc + γ) it is the rigid press's (lagrange-exact's, to round-off)."""
    st = initial_state(params)
    th = [st["phi"], st["theta2"], st["psi"] + math.pi]
    thd = [st["phid"], st["theta2d"], st["psid"]]
    u = [np.array([math.cos(a), math.sin(a)]) for a in th]
    M, force = np.zeros((4, 4)), np.zeros(4)
    for m, J, Jc, lens in chain_jacobians(params, th):
        b = len(lens) - 1
        Jt = np.array([1.0] * (b + 1) + [0.0] * (3 - b))
        bias = -sum(lens[j] * thd[j] ** 2 * u[j] for j in range(b + 1))
        M[:3, :3] += m * Jc.T @ Jc
        M += J * np.outer(Jt, Jt)
        force[:3] += Jc.T @ (m * np.array([0.0, -float(params["gravity"])]) - m * bias)
    M[3, 3] += float(params["m4"])
    force[0] += motor_torque(st["phid"], float(params["gear_ratio"]))
    force[3] -= float(params["slider_damping"]) * st["vC"][0]   # the spring is at rest
    ls = [float(params["l1"]), float(params["l2"]), float(params["l3"])]
    G = np.zeros((2, 4))
    for i in range(3):
        for j in range(i, 3):
            G[:, i] += ls[j] * np.array([-math.sin(th[j]), math.cos(th[j])])
    G[:, 3] = (-1.0, 0.0)
    gamma = -sum(ls[j] * thd[j] ** 2 * u[j] for j in range(3))
    return M, force, G, gamma


def soft_closure_offset(params: dict, impedance: float, diagonal: np.ndarray) -> float:
    """How much a loop closed by a soft constraint of `impedance` d (MuJoCo's solimp) moves the
    crank's acceleration at the start, against the rigid closure: the constraint force solves
    (A + R) f = −a₀ instead of A f = −a₀, A = G M⁻¹ Gᵀ, R = (1 − d)/d · diag(`diagonal`) (the
    engine's diagonal estimate of A), a₀ the loop's acceleration without it; the difference
    M⁻¹Gᵀ(f_soft − f_rigid) on the crank (rad/s²)."""
    M, force, G, gamma = open_tree_at_start(params)
    Minv = np.linalg.inv(M)
    A = G @ Minv @ G.T
    a0 = G @ Minv @ force + gamma
    R = np.diag((1.0 - impedance) / impedance * np.asarray(diagonal, float))
    df = np.linalg.solve(A, a0) - np.linalg.solve(A + R, a0)
    return float((Minv @ G.T @ df)[0])


def breakpoints(params: dict, t_out: np.ndarray):
    """Segment ends of a run: the output times plus, for press-cycle, lock_after and
    release_after. Returns (sorted times, output index by time, (lock_after, release_after,
    lock angle in rad) or None for `press`)."""
    bounds = [float(t) for t in t_out]
    events = None
    if is_cycle(params):
        la, ra = float(params["lock_after"]), float(params["release_after"])
        events = (la, ra, math.radians(float(params["lock_angle"])))
        for tb in (la, ra):
            if 0.0 < tb < t_out[-1] and not np.any(np.isclose(t_out, tb, rtol=0, atol=1e-12)):
                bounds.append(tb)
        bounds = sorted(bounds)
    return bounds, {float(t): k for k, t in enumerate(t_out)}, events


# ---- observables from a solver's kinematic output --------------------------------------------
CHANNELS = (Channel("crank_angle", "rad"), Channel("crank_rate", "rad/s"),
            Channel("crank_accel", "rad/s²"), Channel("rocker_angle", "rad"),
            Channel("slider_x", "m"), Channel("loop_violation", "m", rounding="l2"),
            Channel("energy_balance", "J"))


def loop_violation(params: dict, phi, psi, slider_x):
    """How far the reported (φ, ψ, x_C) are from closing the loop: | |B − A| − l2 | with
    A = l1(cos φ, sin φ) and B = (x_C + l3 cos ψ, l3 sin ψ) (m)."""
    l1, l2, l3 = float(params["l1"]), float(params["l2"]), float(params["l3"])
    ax, ay = l1 * np.cos(phi), l1 * np.sin(phi)
    bx, by = slider_x + l3 * np.cos(psi), l3 * np.sin(psi)
    return np.abs(np.hypot(bx - ax, by - ay) - l2)


def energy_balance(kinetic, potential, motor_work, damper_loss, press_work, lock_loss):
    """E = T + V_spring + V_gravity − W_motor + W_damper + W_press + (the loss at the lock): a
    constant for an exact solution (J)."""
    return kinetic + potential - motor_work + damper_loss + press_work + lock_loss


def channels(params: dict, phi, phid, phidd, psi, slider_x, kinetic, potential, motor_work,
             damper_loss, press_work, lock_loss) -> dict:
    """The scene's channels from a solver's kinematic output (arrays on the output grid, or
    scalars for one output)."""
    return {"crank_angle": phi, "crank_rate": phid, "crank_accel": phidd, "rocker_angle": psi,
            "slider_x": slider_x, "loop_violation": loop_violation(params, phi, psi, slider_x),
            "energy_balance": energy_balance(kinetic, potential, motor_work, damper_loss,
                                             press_work, lock_loss)}
