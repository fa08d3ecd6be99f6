"""Scene data shared by the engine leaves of the `press` / `press-cycle` scenes.

Only the scene's *definition* lives here (defaults, the assembly and initial velocities that every
engine must be given, the motor law, where each lumped mass sits); the dynamics stay in each
engine. Imports numpy only.

Conventions (scene-press.md): A = l1(cos φ, sin φ); B = C + l3(cos ψ, sin ψ) with C = (x_C, 0);
|B − A| = l2; θ2 is the direction A→B. Angles in params are degrees.
"""
from __future__ import annotations

import math

import numpy as np

CHANNELS = ("crank_angle", "crank_rate", "crank_accel", "rocker_angle", "slider_x",
            "loop_violation", "energy_balance")

DEFAULT_PARAMS = {
    "l1": 0.015, "l2": 0.040, "l3": 0.030,
    "m1": 4.6, "m2": 20.0, "m3": 18.0, "m4": 100.0,
    "J1": 0.034, "J2": 0.036, "J3": 0.0441,
    "phi0": -64.1, "psi0": -46.34, "omega0": 43.5, "rocker_rate0": 0.0,
    "gravity": 9.81, "slider_stiffness": 1e6, "slider_damping": 0.0,
    "gear_ratio": 1.0, "mass_model": "paper", "assembly": 1,
    "t_end": 0.05, "output_dt": 0.00125,
}

# press-cycle defaults, as the custom solvers (custom_models/press.py) pick them; any value is
# accepted. The working load is -press_force * tanh(v_slider / press_force_vreg) while locked.
# NB: at the idle defaults the rocker only swings from -46.34 deg to -55.2 deg by 0.05 s, so a
# lock at -60 deg is not reached inside [lock_after, release_after) = [4, 30) ms.
CYCLE_DEFAULTS = {"lock_after": 0.004, "lock_angle": -60.0, "press_force": 2000.0,
                  "press_force_vreg": 0.01, "release_after": 0.03}


def press_load(v: float, F: float, vreg: float) -> float:
    """Working load on the slider while locked (N): -F tanh(v / vreg)."""
    return -F * math.tanh(v / vreg)


def press_power(v: float, a: float, F: float, vreg: float) -> tuple:
    """Dissipated power F tanh(v/vreg) v and its time derivative (for the Hermite quadrature)."""
    th = math.tanh(v / vreg)
    return F * th * v, F * (th + v / vreg * (1.0 - th * th)) * a


# motor 4A80B4U3, Kloss characteristic
P_N = 1500.0
OMEGA_SYNC = 2.0 * math.pi * 1500.0 / 60.0
S_N = 0.058
LAMBDA_K = 2.2
M_N = P_N / (OMEGA_SYNC * (1.0 - S_N))
M_K = LAMBDA_K * M_N
S_K = S_N * (LAMBDA_K + math.sqrt(LAMBDA_K ** 2 - 1.0))
ROTOR_INERTIA = 0.0033


def merged(params: dict | None, cycle: bool = False) -> dict:
    p = dict(DEFAULT_PARAMS)
    if cycle:
        p.update(CYCLE_DEFAULTS)
    p.update(params or {})
    for k in ("l1", "l2", "l3"):
        if not float(p[k]) > 0.0:
            raise ValueError(f"{k} must be > 0, got {p[k]!r}")
    for k in ("m1", "m2", "m3", "m4", "J1", "J2", "J3"):
        if not float(p[k]) >= 0.0:
            raise ValueError(f"{k} must be >= 0, got {p[k]!r}")
    if p["mass_model"] not in ("paper", "midpoint"):
        raise ValueError(f"mass_model must be 'paper' or 'midpoint', got {p['mass_model']!r}")
    if int(p["assembly"]) not in (1, 2):
        raise ValueError(f"assembly must be 1 or 2, got {p['assembly']!r}")
    return p


def fixed_step_settings(settings: dict | None, defaults: dict, integrators: tuple,
                        engine: str) -> dict:
    """Settings over an engine's defaults, with the checks every fixed-step engine needs."""
    s = {**defaults, **(settings or {})}
    if s["integrator"] not in integrators:
        raise ValueError(f"integrator must be one of {integrators}, got {s['integrator']!r}")
    if "rtol" in (settings or {}):
        raise ValueError(f"{engine} press runs fixed-step: give dt, not rtol")
    s["dt"] = float(s["dt"])
    if not s["dt"] > 0:
        raise ValueError(f"dt must be > 0, got {s['dt']!r}")
    return s


def motor_torque(crank_rate: float, u: float) -> float:
    """Crank torque u·M(s), M = 2 M_k/(s/s_k + s_k/s) written as 2 M_k s s_k/(s² + s_k²) (regular at s = 0)."""
    s = 1.0 - u * crank_rate / OMEGA_SYNC
    return u * 2.0 * M_K * s * S_K / (s * s + S_K * S_K)


def crank_rotor_inertia(p: dict) -> float:
    u = float(p["gear_ratio"])
    return 0.0 if u == 1.0 else u * u * ROTOR_INERTIA


def initial_state(p: dict) -> dict:
    """Assembly and consistent velocities from (φ0, ψ0, φ̇0, ψ̇0).

    Returns angles phi, theta2, psi (rad), rates, joint points A, B, C and their velocities.
    Raises ValueError where the loop cannot close or the root is double (rod vertical).
    """
    l1, l2, l3 = float(p["l1"]), float(p["l2"]), float(p["l3"])
    phi, psi = math.radians(float(p["phi0"])), math.radians(float(p["psi0"]))
    phid, psid = float(p["omega0"]), float(p["rocker_rate0"])
    A = np.array([l1 * math.cos(phi), l1 * math.sin(phi)])
    yB = l3 * math.sin(psi)
    dy = yB - A[1]
    disc = l2 * l2 - dy * dy
    if disc < 0.0:
        raise ValueError(f"loop cannot close at phi0={p['phi0']}, psi0={p['psi0']} (|yB - yA| > l2)")
    if disc < (1e-9 * l2) ** 2:
        raise ValueError("initial configuration is a double root (rod vertical): assembly undefined")
    sigma = 1.0 if int(p["assembly"]) == 1 else -1.0
    xB = A[0] + sigma * math.sqrt(disc)
    B = np.array([xB, yB])
    C = np.array([xB - l3 * math.cos(psi), 0.0])
    th2 = math.atan2(B[1] - A[1], B[0] - A[0])
    vA = l1 * phid * np.array([-math.sin(phi), math.cos(phi)])
    # rod rigid: y-component of v_B = v_A + l2 θ̇2 (−sin θ2, cos θ2) must equal l3 cos ψ ψ̇
    th2d = (l3 * math.cos(psi) * psid - vA[1]) / (l2 * math.cos(th2))
    vB = vA + l2 * th2d * np.array([-math.sin(th2), math.cos(th2)])
    vC = vB - l3 * psid * np.array([-math.sin(psi), math.cos(psi)])
    return {"phi": phi, "theta2": th2, "psi": psi, "phid": phid, "theta2d": th2d, "psid": psid,
            "A": A, "B": B, "C": C, "vA": vA, "vB": vB, "vC": vC}


def link_layout(p: dict) -> dict:
    """Where each link's mass sits, in the link frame (x along the link direction used by the
    engine: crank O→A, rod A→B, rocker C→B).  Returns {link: (com_x, mass, J)}; com_x measured
    from the link's first point (O, A, C)."""
    mid = p["mass_model"] == "midpoint"
    l1, l2, l3 = float(p["l1"]), float(p["l2"]), float(p["l3"])
    return {
        "crank": (0.5 * l1 if mid else l1, float(p["m1"]), float(p["J1"]) + crank_rotor_inertia(p)),
        "rod": (0.5 * l2 if mid else l2, float(p["m2"]), float(p["J2"])),
        # paper: rocker mass at C (com_x = 0); midpoint: half-way C→B
        "rocker": (0.5 * l3 if mid else 0.0, float(p["m3"]), float(p["J3"])),
    }


def output_grid_check(t_out: np.ndarray, dt: float) -> np.ndarray:
    t_out = np.asarray(t_out, dtype=float)
    if t_out.ndim != 1 or len(t_out) < 1 or t_out[0] != 0.0 or np.any(np.diff(t_out) <= 0):
        raise ValueError("t_out must be increasing and start at 0")
    if not (dt > 0.0):
        raise ValueError(f"dt must be > 0, got {dt!r}")
    return t_out


CYCLE_KEYS = ("lock_after", "lock_angle", "press_force", "release_after")


def prepare(params, t_out, settings, check_settings, cycle=None):
    """The shared start of an engine leaf: the scene (press-cycle when any cycle parameter is
    given, or cycle=True), the leaf's checked settings, the checked output grid and the
    consistent initial state. Returns (cycle, p, s, t_out, state)."""
    if cycle is None:
        cycle = any(k in (params or {}) for k in CYCLE_KEYS)
    p = merged(params, cycle=cycle)
    s = check_settings(settings)
    t_out = output_grid_check(t_out, s["dt"])
    return cycle, p, s, t_out, initial_state(p)


def breakpoints(p, t_out, cycle):
    """Segment ends of an engine run: the output times plus, for press-cycle, lock_after and
    release_after. Returns (bounds, output index by time, (lock_after, release_after,
    lock angle in rad) or None)."""
    bounds = list(t_out)
    events = None
    if cycle:
        la, ra = float(p["lock_after"]), float(p["release_after"])
        events = (la, ra, math.radians(float(p["lock_angle"])))
        for tb in (la, ra):
            if 0.0 < tb < t_out[-1] and not np.any(np.isclose(t_out, tb, rtol=0, atol=1e-12)):
                bounds.append(tb)
        bounds = sorted(bounds)
    return bounds, {float(t): k for k, t in enumerate(t_out)}, events
