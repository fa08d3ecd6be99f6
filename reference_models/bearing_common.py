"""What both engine leaves of the `bearing-rotor` scene share apart from their dynamics: the
output-step plan, the stability estimate of the bearing modes, the divergence guard on the
energy balance, and turning the kinematic output into a `LeafResult` through the scene's ONE
implementation of the observables (`compare.physics.bearing_rotor.channels`).

The force laws are not here: each engine evaluates `bearing_rotor.body_loads` at every force
evaluation (Exudyn user function, MuJoCo passive callback).
"""
from __future__ import annotations

import math

import numpy as np

from compare.contract import LeafResult
from compare.physics import bearing_rotor as br

EXTRA_CHANNELS = ("kinetic", "potential", "motor_work", "dissipated")
RK4_STABILITY = 2.785          # |h·λ| on the negative real axis / 2.83 on the imaginary axis
ENERGY_JUMP = 0.05             # |ΔE| above this share of the energy scale: diverged
JOURNAL_BOUND = 0.25           # a journal farther than this × l from its bearing: diverged
                               # (k_b l/4 of force: garbage; keeps Exudyn's chart off its lock)
OMEGA_BOUND = 1e5              # rad/s, |ω| beyond this: diverged


def stiffest_rate(params: dict) -> float:
    """Upper bound (1/s) of |λ| of the linearised bearing modes at rest: lateral (mass m,
    stiffness 2k_b, damping 2c_b), rocking (J_t, k_b l²/2, c_b l²/2), axial (m, k_axial). An
    explicit step h is stable only if h·|λ| stays inside the method's region (~2.8 for RK4)."""
    m, jt, l = params["m"], params["J_t"], params["l"]
    kb, cb = params["k_b"], params["c_b"]
    rate = 0.0
    for inertia, k, c in ((m, 2 * kb, 2 * cb), (jt, 0.5 * kb * l * l, 0.5 * cb * l * l),
                          (m, params["k_axial"], 0.0)):
        a = c / (2 * inertia)
        rate = max(rate, a + math.sqrt(a * a + k / inertia))
    return rate


def stability_note(params: dict, h: float) -> str:
    """The explicit-step stability verdict in words, for a divergence reason."""
    limit = RK4_STABILITY / stiffest_rate(params)
    if h > limit:
        return (f"; step {h:.3g} s exceeds the RK4 stability limit ~{limit:.3g} s of the bearing "
                f"modes (k_b = {params['k_b']:g} N/m): lower dt or use an adaptive integrator")
    return ""


def step_plan(t_out: np.ndarray, dt: float) -> tuple[int, float]:
    """(steps per output interval, step) with the largest step ≤ dt that divides output_dt."""
    dto = float(t_out[1] - t_out[0]) if len(t_out) > 1 else float(dt)
    n = max(1, int(math.ceil(dto / dt - 1e-9)))
    return n, dto / n


def energy_blowup(ch: dict, tol: float = ENERGY_JUMP):
    """First index where |E − E(0)| exceeds tol × the running energy scale, and a reason."""
    e = ch["energy_balance"]
    err = np.abs(e - e[0])
    scale = np.fmax.accumulate(np.abs(ch["kinetic"]) + np.abs(ch["potential"] - ch["potential"][0])
                               + np.abs(ch["motor_work"]) + np.abs(ch["dissipated"]) + 1e-12)
    with np.errstate(invalid="ignore"):
        bad = np.nonzero(~(err <= tol * scale))[0]
    if bad.size == 0:
        return None
    i = int(bad[0])
    return i, (f"energy balance error {err[i]:.3g} J exceeds {tol:g} x energy scale "
               f"{scale[i]:.3g} J (integration unstable)")


def result(params: dict, t_out: np.ndarray, r_cm, v_cm, quat, omega, motor_work, dissipated,
           status: str, t_fail, reason, stats: dict, settings: dict, h: float | None) -> LeafResult:
    """Channels (shared observables), NaN from t_fail on, the energy guard, extras."""
    n = len(t_out)
    good = np.all(np.isfinite(r_cm), axis=1) & np.all(np.isfinite(quat), axis=1)
    k = int(np.argmin(good)) if not good.all() else n      # samples [0, k) are filled
    filled = {name: np.full(n, np.nan) for name in
              ("spin_rate", "spin_angle", "journal_a_x", "journal_a_y", "journal_b_x",
               "journal_b_y", "energy_balance") + EXTRA_CHANNELS}
    orient = np.full((n, 4), np.nan)
    ja = np.full((n, 3), np.nan)
    jb = np.full((n, 3), np.nan)
    if k > 0:
        q = quat[:k] / np.linalg.norm(quat[:k], axis=1, keepdims=True)
        ch = br.channels(params, t_out[:k], r_cm[:k], v_cm[:k], q, omega[:k],
                         motor_work[:k], dissipated[:k])
        # also for a run already stopped: its last samples before the stop may be garbage
        blow = energy_blowup(ch)
        if blow is not None and (t_fail is None or t_out[blow[0]] < t_fail):
            t_fail = float(t_out[blow[0]])
            reason = blow[1] + (stability_note(params, h) if h else "")
            status = "diverged"
        for name in filled:
            filled[name][:k] = ch[name]
        orient[:k] = q
        ja[:k], jb[:k] = br.journal_positions(params, r_cm[:k], q)
    if status != "ok":
        late = t_out >= t_fail
        for v in filled.values():
            v[late] = np.nan
        orient[late] = ja[late] = jb[late] = np.nan
    return LeafResult(channels=filled, status=status, t_fail=t_fail, reason=reason, stats=stats,
                      settings=settings,
                      extra={"orientation": orient, "journal_a": ja, "journal_b": jb})
