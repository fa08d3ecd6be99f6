"""The `lagrange-partial` driver the one-coordinate closed-loop models share (Andrews' squeezer,
Bricard's mechanism): the checked settings, the linear-acceleration run of a model's compiled
`acc`/`guard`, and the full state q = q(x), q' = J x' read back from the partial systems.
A model module supplies `acc`, `guard`, `analogues(x, p)` → (q, J, J', ok), `full_state`,
`WARM` (the first warm-start slot of p) and `NP` (the physical parameters' length).
"""
import time

import numba as nb
import numpy as np

from compare.contract import LeafResult, merge_settings, require_positive

from .integrators import integrate_wilson
from .integrators.dense import first_class
from .integrators.explicit import GUARD
from .integrators.linear_acceleration import ACC, la_args, steps_per_output


@nb.njit(cache=True)
def partial_systems(q0, qp, qm, h):
    """J = ∂q/∂x and J' = ∂²q/∂x² by central differences from the closed mechanism at x
    (q0) and x ± h (qp, qm): O(h²)."""
    J = (qp - qm) / (2.0 * h)
    J2 = (qp - 2.0 * q0 + qm) / (h * h)
    return J, J2


def partial_settings(settings: dict | None, defaults: dict, integrators: tuple,
                     virtual: str) -> dict:
    """Settings merged and checked (ValueError with one line); `virtual` names the partial
    systems' virtual step."""
    s = merge_settings(settings, defaults, integrators)
    require_positive(s, ("dt", virtual, "newton_tol", "closure_tol", "max_iter"))
    if s["integrator"] == "wilson" and not float(s["theta"]) >= 1.0:
        raise ValueError(f"theta must be >= 1, got {s['theta']!r}")
    return s


def run_partial(model, phys, p: np.ndarray, y0: np.ndarray, warm: np.ndarray, t_out: np.ndarray,
                s: dict, virtual: str, rate: str, reasons: dict) -> LeafResult:
    """Integrate [x, x'] from y0 with the model's parameter vector p; the warm start is reset
    to `warm` (the initial dependent coordinates) before the state is read back, so the read
    follows the same branch as the run. `rate` names the extra channel x'."""
    n_sub = steps_per_output(t_out, float(s["dt"]))
    theta, mode = la_args(s)
    t0 = time.perf_counter()
    Y, steps, evals, t_fail, code = integrate_wilson(
        first_class(model.acc, ACC), first_class(model.guard, GUARD), y0, 1, p, t_out, n_sub,
        theta, mode, float(s["newton_tol"]), int(s["max_iter"]))
    wall = time.perf_counter() - t0
    flag = getattr(model, "FLAG", None)
    if code != 0 and flag is not None and p[flag]:
        code = int(p[flag])     # the loop that stopped closing, not the NaN it left behind
    p[model.WARM:model.WARM + len(warm)] = warm
    Q, QD = model.full_state(Y, p)
    ch = phys.channels(Q, QD, p[:model.NP])
    ok = code == 0
    used = {"integrator": s["integrator"], "dt": float((t_out[1] - t_out[0]) / n_sub),
            "theta": theta, virtual: float(s[virtual]), "newton_tol": float(s["newton_tol"]),
            "closure_tol": float(s["closure_tol"]), "max_iter": int(s["max_iter"])}
    return LeafResult(channels=ch, status="ok" if ok else "diverged",
                      t_fail=None if ok else float(t_fail),
                      reason=None if ok else reasons.get(int(code), f"failure code {code}"),
                      stats={"steps": int(steps), "rhs_evals": int(evals), "integrate_s": wall},
                      settings=used, extra={rate: Y[:, 1].copy()})


def full_state(Y: np.ndarray, p: np.ndarray, analogues, n_q: int, warm: int):
    """The n_q coordinates and rates (q = q(x), q' = J x') of each row of [x, x'] (NaN rows
    kept), each closure warm-started from the last (slots p[warm:warm + n_q − 1])."""
    n = len(Y)
    Q, QD = np.full((n, n_q), np.nan), np.full((n, n_q), np.nan)
    for i in range(n):
        if np.isfinite(Y[i, 0]) and np.isfinite(Y[i, 1]):
            qf, J, _, ok = analogues(Y[i, 0], p)
            if ok:
                p[warm:warm + n_q - 1] = qf[1:]
                Q[i], QD[i] = qf, J * Y[i, 1]
    return Q, QD
