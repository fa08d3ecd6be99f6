"""Crank–rocker press with slider (seed 003, scenes `press` and `press-cycle`): the leaf glue of
the two Lagrange solvers `press_partial` (the paper's finite-difference "partial systems") and
`press_exact` (the same equations with analytic derivatives).

Where each concern lives:
- scene physics shared with the engines (Kloss motor, working load, link layout, loop closure,
  breakpoints, the channels from a kinematic output): compare/physics/press.py;
- the packed parameter array and the inertia items: press_model.py;
- positions, analytic and finite-difference velocity analogues: press_kinematics.py;
- Lagrange's equations, energy terms and guards: press_equations.py;
- the idle and cycle drivers (shared integrators, shared event location): press_driver.py;
- here: settings, the initial state, channels, failure reasons, the linearised modes.

Both solvers stop with a reason (status "diverged", reason "singular: …") where the chart
(φ, ψ) breaks down (rod vertical) instead of dividing by zero.
"""
import math
import time

import numpy as np

from compare.contract import LeafResult, merge_settings, require_positive
from compare.physics import press as phys

from ..integrators import FAIL_REASONS, FIXED_TABLEAUS, LA_REASONS
from ..integrators.dense import DENSE_TABLEAUS
from .driver import LA_INTEGRATORS, integrate_cycle, integrate_idle
from .equations import (
    FAIL_ENERGY,
    FAIL_SINGULAR,
    FAIL_STENCIL,
    acc_exact,
    energy_terms,
    guard_any,
    mass_matrix_any,
    output_terms,
    rod_sine,
)
from .model import E0, E_SCALE, SOLVER, SOLVER_IDS, U, pack

CHANNELS = phys.CHANNELS
INTEGRATORS = tuple(LA_INTEGRATORS) + tuple(FIXED_TABLEAUS) + tuple(DENSE_TABLEAUS)
ADAPTIVE = tuple(DENSE_TABLEAUS)
# the settings both solvers take (each leaf adds its integrator and step)
COMMON_SETTINGS = {"theta": 1.4, "newton_tol": 1e-10, "max_iter": 30, "rtol": None,
                   "atol": None, "h_max": None, "max_steps": 10**8, "singular_tol": 0.02,
                   "energy_jump": 1e3, "event_tol": 1e-10}
REASONS = {**FAIL_REASONS, **LA_REASONS,
           FAIL_SINGULAR: "singular: the rod reached the vertical, where the loop-closure root "
                          "for x_B is double and the (phi, psi) chart's Jacobian is singular",
           FAIL_STENCIL: "singular: the finite-difference stencil of the partial systems "
                         "reaches past the double loop-closure root (rod near vertical)",
           FAIL_ENERGY: "unstable: the energy balance jumped"}


def settings_of(defaults: dict, settings: dict | None) -> dict:
    """The caller's settings over the leaf's defaults (the one shared merge), plus the checks
    of this model's own keys (ValueError with one line; nothing runs)."""
    s = merge_settings(settings, defaults, INTEGRATORS)
    if s["integrator"] == "wilson" and not float(s["theta"]) >= 1.0:
        raise ValueError(f"theta must be >= 1, got {s['theta']!r}")
    require_positive(s, tuple(k for k in ("dphi_deg", "dpsi_deg") if k in s))
    if s["integrator"] not in ADAPTIVE and not (s["dt"] and float(s["dt"]) > 0.0):
        raise ValueError(f"dt must be > 0, got {s['dt']!r}")
    return s


def initial_state(par: dict, p: np.ndarray) -> np.ndarray:
    """y0 = [φ, ψ, φ', ψ', W_motor, W_damper, W_press]; records the initial energy in p."""
    y0 = np.array([math.radians(par["phi0"]), math.radians(par["psi0"]), par["omega0"],
                   par["rocker_rate0"], 0.0, 0.0, 0.0])
    T, Vs, Vg, E = energy_terms(y0, p)
    p[E0], p[E_SCALE] = E, abs(T) + 1e-9
    return y0


def channels(par: dict, Y: np.ndarray, modes: np.ndarray, p: np.ndarray, t_out: np.ndarray,
             lost: np.ndarray) -> dict:
    """The scene's channels (compare.physics.press.channels) from the solver's states."""
    o = output_terms(np.ascontiguousarray(Y), np.ascontiguousarray(modes, float), p)
    return phys.channels(par, Y[:, 0], Y[:, 2], o[:, 0], Y[:, 1], o[:, 1], o[:, 2], o[:, 3],
                         Y[:, 4], Y[:, 5], Y[:, 6], lost)


def _reason(code, Y, p):
    reason = REASONS.get(int(code), f"failure code {code}")
    good = Y[np.all(np.isfinite(Y), axis=1)]
    if len(good):
        y = good[-1]
        s = rod_sine(y[0], y[1], p)
        tilt = math.degrees(math.acos(min(1.0, abs(s))))
        reason += f" (last output state: rod {tilt:.3g} deg from vertical"
        if code == FAIL_ENERGY:
            reason += f", energy balance {energy_terms(y, p)[3] - p[E0]:+.3g} J from start"
        reason += ")"
    return reason


def _check_grid(t_out) -> np.ndarray:
    t_out = np.asarray(t_out, dtype=float)
    if t_out.ndim != 1 or len(t_out) < 2 or t_out[0] != 0.0 or np.any(np.diff(t_out) <= 0):
        raise ValueError("t_out must be an increasing grid starting at 0 with >= 2 points")
    return t_out


def _used_settings(solver: str, s: dict, used: dict, cycle: bool) -> dict:
    used = dict(used, integrator=s["integrator"], singular_tol=float(s["singular_tol"]),
                energy_jump=float(s["energy_jump"]))
    if s["integrator"] in LA_INTEGRATORS:
        used.update(newton_tol=float(s["newton_tol"]), max_iter=int(s["max_iter"]))
    if solver == "partial":
        used.update(dphi_deg=float(s["dphi_deg"]), dpsi_deg=float(s["dpsi_deg"]))
    if cycle:
        used["event_tol"] = float(s["event_tol"])
    return used


def simulate(solver: str, defaults: dict, params: dict, t_out: np.ndarray,
             settings: dict | None) -> LeafResult:
    """The leaf contract for both solvers: `press-cycle` when the parameters carry the lock."""
    cycle = phys.is_cycle(params)
    s = settings_of(defaults, settings)
    t_out = _check_grid(t_out)
    p = pack(params, s.get("dphi_deg", 0.1), s.get("dpsi_deg", 0.1), float(s["singular_tol"]),
             float(s["energy_jump"]))
    p[SOLVER] = SOLVER_IDS[solver]
    y0 = initial_state(params, p)
    n = len(t_out)
    code0 = guard_any(0.0, y0, p)
    if code0 in (FAIL_SINGULAR, FAIL_STENCIL):
        # the start itself sits at (or, for the finite differences, too near) the double root
        Y = np.full((n, len(y0)), np.nan)
        Y[0] = y0
        return LeafResult(channels={k: np.full(n, np.nan) for k in CHANNELS}, status="diverged",
                t_fail=0.0, reason=_reason(code0, Y, p) + " at the initial state",
                stats={"steps": 0, "rhs_evals": 0}, settings=dict(s), extra={})
    t0 = time.perf_counter()
    extra = {}
    if cycle:
        Y, modes, stats, t_fail, code, used, lock = integrate_cycle(y0, p, params, t_out, s)
        lost = np.where(t_out >= lock["t_lock"], lock["loss"], 0.0)
        extra = {"t_lock": np.array([lock["t_lock"]]),
                 "lock_energy_loss": np.array([lock["loss"]]),
                 "crank_rate_at_lock": np.array([lock["rate_before"], lock["rate_after"]]),
                 "locked": modes.copy(), "press_work": Y[:, 6].copy()}
    else:
        Y, stats, t_fail, code, used = integrate_idle(y0, p, t_out, s)
        modes, lost = np.zeros(n), np.zeros(n)
    stats.setdefault("integrate_s", time.perf_counter() - t0)   # the drivers' own where given
    ch = channels(params, Y, modes, p, t_out, lost)
    extra.update({"motor_work": Y[:, 4].copy(), "damper_loss": Y[:, 5].copy()})
    ok = code == 0
    return LeafResult(channels=ch, status="ok" if ok else "diverged",
            t_fail=None if ok else float(t_fail),
            reason=None if ok else _reason(code, Y, p),
            stats=stats, settings=_used_settings(solver, s, used, cycle), extra=extra)


def linearised_modes(params: dict, q=None) -> tuple:
    """Eigen-analysis of the idle system about the initial state (or q): ω² = eig(A⁻¹K), K the
    Hessian of V = V_spring + V_gravity in (φ, ψ) by central differences of the generalized
    forces at rest. Returns (omega (rad/s), T = 2π/ω) sorted by ω descending."""
    p = pack(params)
    q0 = np.radians([params["phi0"], params["psi0"]]) if q is None else np.asarray(q, float)
    p[U] = 0.0                                  # no motor torque: the conservative part only
    A = mass_matrix_any(q0[0], q0[1], p)
    K = np.zeros((2, 2))
    for k, dq in enumerate(np.eye(2) * 1e-6):
        fp = acc_exact(0.0, q0 + dq, np.zeros(2), p)[:2]
        fm = acc_exact(0.0, q0 - dq, np.zeros(2), p)[:2]
        Ap = mass_matrix_any(*(q0 + dq), p)
        Am = mass_matrix_any(*(q0 - dq), p)
        K[:, k] = -(Ap @ fp - Am @ fm) / 2e-6     # K = −∂Q/∂q
    w2 = np.sort(np.linalg.eigvals(np.linalg.solve(A, K)).real)[::-1]
    w = np.sqrt(np.maximum(w2, 0.0))
    return w, np.where(w > 0, 2 * np.pi / np.where(w > 0, w, 1), np.inf)
