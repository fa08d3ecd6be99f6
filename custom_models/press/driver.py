"""Time integration of the custom press model with the shared integrators: an idle run
(`press`: fixed-step RK or adaptive RK with dense output, or linear acceleration) and the
lock/release cycle (`press-cycle`: segments of the shared event-capable driver, the lock located
as a state event). Runge–Kutta methods take the allocation-free right-hand side `f_any_into`.
"""

import numpy as np

from ..integrators import FIXED_TABLEAUS, integrate_wilson
from ..integrators.dense import DENSE_TABLEAUS, RHS_INTO, first_class, solve
from ..integrators.events import (
    C_EVENT_ON,
    C_EVENT_TOL,
    EVENT,
    EVENT_FN,
    M_LA,
    M_RK,
    config,
    integrate_segment,
)
from ..integrators.explicit import GUARD
from ..integrators.linear_acceleration import (  # noqa: F401  (LA_INTEGRATORS: press.lagrange)
    ACC,
    LA_INTEGRATORS,
    la_args,
    steps_per_output,
)
from .equations import acc_any, energy_terms, f_any_into, guard_any, lock_event, mass_matrix_any
from .model import E_LOST, MODE


def integrate_idle(y0: np.ndarray, p: np.ndarray, t_out: np.ndarray, s: dict):
    """One idle run (scene `press`). Returns (Y, stats, t_fail, code, settings used).

    Runge–Kutta methods run on the dense-output drivers: the adaptive step is set by the
    tolerance alone (no cap unless h_max is given), a fixed step need not divide the output
    step (outputs between step ends by cubic Hermite)."""
    name = s["integrator"]
    if name in DENSE_TABLEAUS or name in FIXED_TABLEAUS:
        rtol = float(s["rtol"] or 1e-10)
        Y, stats, t_fail, code, used = solve(
            f_any_into, guard_any, y0, p, t_out, name, dt=s["dt"], rtol=rtol, atol=s["atol"],
            h_max=s["h_max"], max_steps=int(s["max_steps"]))
        used.pop("integrator")
        return Y, stats, t_fail, code, used
    n_sub = steps_per_output(t_out, s["dt"])
    theta, mode = la_args(s)
    Y, steps, evals, t_fail, code = integrate_wilson(
        first_class(acc_any, ACC), first_class(guard_any, GUARD), y0, 2, p, t_out, n_sub, theta,
        mode, float(s["newton_tol"]), int(s["max_iter"]))
    used = {"dt": float((t_out[1] - t_out[0]) / n_sub), "theta": theta}
    return Y, {"steps": int(steps), "rhs_evals": int(evals)}, t_fail, code, used


def _method(s: dict, h: float):
    """(tableau, cfg, settings used) of the event-capable driver for the chosen integrator."""
    name = s["integrator"]
    used = {"dt": float(h)}
    if name in FIXED_TABLEAUS:
        tb = FIXED_TABLEAUS[name]
        return (tb["A"], tb["B"], tb["C"]), config(M_RK), used
    theta, mode = la_args(s)
    used["theta"] = theta
    cfg = config(M_LA, theta=theta, la_mode=mode, tol=float(s["newton_tol"]),
                 max_iter=int(s["max_iter"]), n_q=2)
    return (np.zeros((1, 1)), np.zeros(1), np.zeros(1)), cfg, used


def plastic_lock(y: np.ndarray, p: np.ndarray) -> tuple:
    """The plastic lock: ψ' → 0 keeping the crank's generalized momentum p_φ = A11 φ' + A12 ψ'
    (A of the solver's own description). Returns (new state, kinetic energy lost)."""
    A = mass_matrix_any(y[0], y[1], p)
    T_before = energy_terms(y, p)[0]
    y = y.copy()
    y[2] = y[2] + A[0, 1] / A[0, 0] * y[3]
    y[3] = 0.0
    return y, T_before - energy_terms(y, p)[0]


def integrate_cycle(y0: np.ndarray, p: np.ndarray, par: dict, t_out: np.ndarray, s: dict):
    """press-cycle: idle → lock at ψ = lock_angle (first crossing after lock_after, located by
    bisection) → locked crank–slider under the working load → release at release_after → idle.
    Returns (Y, per-row mode, stats, t_fail, code, settings used, lock record)."""
    if s["integrator"] in DENSE_TABLEAUS:
        raise ValueError(f"press-cycle runs fixed-step integrators only, got {s['integrator']!r}")
    h = (t_out[1] - t_out[0]) / steps_per_output(t_out, s["dt"])
    tab, cfg, used = _method(s, h)
    t_end = float(t_out[-1])
    t_lock_after, t_release = float(par["lock_after"]), float(par["release_after"])
    Y = np.full((len(t_out), len(y0)), np.nan)
    Y[0] = y0
    modes = np.zeros(len(t_out))
    stats = {"steps": 0, "rhs_evals": 0}
    lock = {"t_lock": np.nan, "loss": 0.0, "rate_before": np.nan, "rate_after": np.nan}
    t, y, i = 0.0, y0.copy(), 1
    # phases: (mode, t_stop, event on)
    plan = [(0.0, min(t_lock_after, t_end), False), (0.0, min(t_release, t_end), True)]
    while plan:
        md, t_stop, ev = plan.pop(0)
        p[MODE] = md
        if t_stop > t:
            cfg[C_EVENT_ON], cfg[C_EVENT_TOL] = float(ev), float(s["event_tol"])
            code, t_new, y_new, i_new, st, evs = integrate_segment(
                first_class(f_any_into, RHS_INTO), first_class(acc_any, ACC),
                first_class(guard_any, GUARD), first_class(lock_event, EVENT_FN), y, p, t,
                t_stop, t_out, i, Y, h, tab, cfg)
            modes[i:i_new] = md
            stats["steps"] += st
            stats["rhs_evals"] += evs
            t, y, i = t_new, y_new, i_new
            if code not in (0, EVENT):
                return Y, modes, stats, t, code, used, lock
            if code == EVENT:
                lock["t_lock"], lock["rate_before"] = t, y[2]
                y, lock["loss"] = plastic_lock(y, p)
                lock["rate_after"] = y[2]
                p[E_LOST] = lock["loss"]
                plan = [(1.0, min(t_release, t_end), False), (0.0, t_end, False)]
                continue
        if ev and not plan:              # no lock before release: idle to the end
            plan = [(0.0, t_end, False)]
    return Y, modes, stats, None, 0, used, lock

