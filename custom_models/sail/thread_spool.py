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

Channels (both blades): compare.physics.sail.channels, from the inertial states (the rk4
driver's body-frame states are rotated there first); D and W_spool as this solver integrated
them at every step (the general expression of the payout power in `_forces`). The stored thread
is counted at L_c in every variant, so the paper variant shows its angular-momentum drift, and
its velocity turn and unforced stored inertia show as energy drifts.

Integrators (thread_spool_driver.py)
-------------------------------------
"rk4" (the paper's, rotating frame, through the shared fixed-step dense driver) and "imr"
(default: implicit midpoint rule with energy–momentum spring forces, inertial frame).
`dt="auto"` (default): 1e-3 s for "imr"; for "rk4" 0.8 × 2.785/λ_max with
λ_max = 2 sqrt(c/m_min) + 4 d/m_min (highest chain frequency, m_min including the hub's reduced
mass at Q). A requested RK4 step above the stability limit runs and is caught (spring stretch
beyond `stretch_limit`·l0 or non-finite state) and reported as status "diverged", reason
"unstable step ...".

Where each concern lives: payout, release law, breakpoints, formula 18 and the channels (one
definition for this solver and the engines): compare/physics/sail.py; the packed parameters and
variant switches: thread_spool_model.py; forces and the rotating-frame right-hand side:
thread_spool_equations.py; the drivers: thread_spool_driver.py; here the leaf glue.

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

from compare.contract import LeafResult, check_once, merge_settings, require_positive
from compare.physics import sail as phys

from .driver import FAIL_NONFINITE, FAIL_STRETCH, REASONS, run_imr, run_rk4
from .model import LC, NN, OFF, OM0, RR, WSP, pack, stable_dt_rk4, variant_switches

CHANNELS = phys.CHANNELS
INTEGRATORS = ("rk4", "imr")
DEFAULT_SETTINGS = {"integrator": "imr", "dt": "auto", "variant": "conservative",
                    "velocity_turn": None, "stored_in_hub": None, "q_damper": None,
                    "newton_tol": 1e-12, "stretch_limit": 0.5, "eps_fallback": 1e-10}
AUTO_DT = {"imr": 1e-3}      # dt="auto" for imr; rk4's auto step comes from its stability limit


def body_to_inertial(Y: np.ndarray, n: int, L_c: float) -> tuple:
    """Body-frame states (rows; origin at the spool centre) -> inertial node positions and
    velocities (N, n, 3), origin on the spin axis."""
    ps, pc = np.sin(Y[:, 1])[:, None], np.cos(Y[:, 1])[:, None]
    Om = Y[:, 0][:, None]
    P = Y[:, OFF:OFF + 3 * n].reshape(len(Y), n, 3)
    V = Y[:, OFF + 3 * n:].reshape(len(Y), n, 3)
    bx, by = P[:, :, 0] + L_c, P[:, :, 1]
    vx, vy = V[:, :, 0] - Om * by, V[:, :, 1] + Om * bx      # + Ω e_z × ρ
    X = np.stack([pc * bx - ps * by, ps * bx + pc * by, P[:, :, 2]], axis=2)
    W = np.stack([pc * vx - ps * vy, ps * vx + pc * vy, V[:, :, 2]], axis=2)
    return X, W


def _step(s: dict, params: dict) -> float:
    dt = s["dt"]
    if dt is None or dt == "auto":
        dt = stable_dt_rk4(params) if s["integrator"] == "rk4" else AUTO_DT["imr"]
    dt = float(dt)
    if not dt > 0:
        raise ValueError(f"dt must be > 0, got {dt!r}")
    return dt


def _initial_state(P: np.ndarray, n: int, inertial: bool) -> np.ndarray:
    """Hub at Ω0; stored nodes parked at Q (irrelevant until released)."""
    y0 = np.zeros(OFF + 6 * n)
    y0[0] = P[OM0]
    park = (P[LC], 0.0, P[RR]) if inertial else (0.0, 0.0, P[RR])
    for j in range(n):
        y0[OFF + 3 * j:OFF + 3 * j + 3] = park
    return y0


@check_once
def check_settings(settings: dict | None, t_out: np.ndarray | None = None) -> dict:
    """The settings merged and checked before anything runs (ValueError with one line)."""
    s = merge_settings(settings, DEFAULT_SETTINGS, INTEGRATORS)
    variant_switches(s)
    require_positive(s, ("stretch_limit", "newton_tol", "eps_fallback"))
    require_positive(s, ("dt",), auto_ok=True)
    return s


def simulate(params: dict, t_out: np.ndarray, settings: dict | None = None) -> LeafResult:
    """Leaf contract: the scene's resolved parameters, the output grid, the settings."""
    s = check_settings(settings)
    t_out = np.asarray(t_out, float)
    if t_out[0] != 0.0 or np.any(np.diff(t_out) <= 0):
        raise ValueError("t_out must start at 0 and be strictly increasing")
    P, m, used = pack(params, s)
    n = int(P[NN])
    dt = _step(s, params)
    bt, bo, br, be = phys.breakpoints(params, t_out)
    inertial = s["integrator"] == "imr"
    y0 = _initial_state(P, n, inertial)
    w0 = time.perf_counter()
    if inertial:
        Y, b_out, stats, t_fail, code = run_imr(y0, P, m, bt, bo, br, dt, len(t_out),
                                                s["newton_tol"])
    else:
        Y, b_out, stats, t_fail, code = run_rk4(y0, P, m, bt, bo, br, be, dt, len(t_out))
    stats["integrate_s"] = time.perf_counter() - w0
    if inertial:
        X = Y[:, OFF:OFF + 3 * n].reshape(len(Y), n, 3)
        V = Y[:, OFF + 3 * n:].reshape(len(Y), n, 3)
    else:
        X, V = body_to_inertial(Y, n, P[LC])
    ch, extra = phys.channels(params, t_out, Y[:, 1], Y[:, 0], X, V, b_out,
                              dissipated=2 * Y[:, 2], spool_work=2 * Y[:, 3])
    status, reason = "ok", None
    if code != 0:
        status = "diverged"
        reason = REASONS.get(int(code), f"code {code}")
        if code in (FAIL_STRETCH, FAIL_NONFINITE) and not inertial:
            hs = stable_dt_rk4(params)
            if dt > hs / 0.8:
                reason = (f"unstable step: {reason} (dt={dt:.3g} s; estimated RK4 stability "
                          f"limit {hs / 0.8:.3g} s, use dt<={hs:.3g} or integrator='imr')")
        for k in ch:
            ch[k][t_out > t_fail] = np.nan
        extra["tip_angle_signed"][t_out > t_fail] = np.nan
    extra.update({"hub_rate_formula18": phys.formula18(params, t_out),
                  "hub_rate_formula18_discrete": phys.formula18_discrete(params, t_out),
                  "hub_rate_formula18_printed": phys.formula18(params, t_out, printed=True),
                  "boundary_node": b_out.astype(float), "dissipated": 2 * Y[:, 2],
                  # spool work on the Q-springs + the release work Σ m (r ω)² (both blades)
                  "payout_work": 2 * Y[:, 3] + np.cumsum(m)[b_out] * (P[RR] * P[WSP]) ** 2})
    return LeafResult(channels=ch, status=status,
            t_fail=None if code == 0 else float(t_fail), reason=reason,
            stats=stats, settings={**s, **used, "dt": dt}, extra=extra)
