"""`simulate`: the spin-up run on the output grid.

The run starts in the identity chart; when a completed step comes near the chart's lock (a
post-step user function stops the run), it continues from that step on a new model in a new
chart (`chart.new_chart`); the output grid is kept because the step size is unchanged. At tilt
π it stops with status `diverged`. An unstable step shows as a jump of the energy balance,
which the compare layer's one energy rule (the scene's `energy_bound`) reports as `diverged`.
A fixed step longer than the output step runs on its own step grid and the channels are
interpolated linearly onto the output grid (as in the MuJoCo leaf); the final value is a step
end.
"""
import math
import time

import numpy as np

from compare.contract import LeafResult
from compare.physics import rotor as physics

from .chart import chart_coordinates, chart_motion, new_chart, quaternions, start
from .model import (
    Stop,
    build,
    last_step_of,
    rotor,
    sim_settings,
    solve,
    steps_of,
    stored,
)
from .settings import ADAPTIVE, SOLVERS, check_settings

MAX_CHART_CHANGES = 10000
REASON_TILT = "singular spring direction at tilt pi"
REASON_NONFINITE = "non-finite state"


def _coarse(params, t_out, s):
    """A fixed step longer than the output step: run on the step grid (N = ⌈t_end/dt⌉ equal
    steps, so the last one lands on t_end) and interpolate the channels linearly onto t_out,
    as the MuJoCo leaf does; the final value is a step end."""
    n = int(math.ceil((t_out[-1] - t_out[0]) / float(s["dt"]) - 1e-9))
    grid = np.linspace(t_out[0], t_out[-1], n + 1)
    res = simulate(params, grid, {**s, "dt": float(grid[1] - grid[0])})
    ok = np.isfinite(res.channels["omega_norm"])

    def interp(v):
        return (np.interp(t_out, grid[ok], v[ok], right=np.nan) if ok.sum() > 1
                else np.where(t_out == t_out[0], v[0], np.nan))

    q = np.stack([interp(res.extra["orientation"][:, j]) for j in range(4)], axis=1)
    w = np.stack([interp(res.extra["angular_velocity"][:, j]) for j in range(3)], axis=1)
    channels = {k: interp(v) for k, v in res.channels.items()}
    if res.t_fail is not None:
        late = t_out >= res.t_fail
        for v in (*channels.values(), q, w):
            v[late] = np.nan
    return LeafResult(channels=channels, status=res.status, t_fail=res.t_fail,
                      reason=res.reason, stats=res.stats,
                      settings={**res.settings, "dt": float(grid[1] - grid[0]),
                                "output": "linear interpolation between steps"},
                      extra={"orientation": q / np.linalg.norm(q, axis=1, keepdims=True),
                             "angular_velocity": w})


def fixed_step(dto, dt):
    """The largest step ≤ dt that divides the output step."""
    return dto / int(math.ceil(dto / dt - 1e-9))


def grid_samples(tt, t_out, i_good):
    """Output-grid index of each stored time and which of them are new samples on the grid."""
    n_out = len(t_out)
    dto = float(t_out[1] - t_out[0]) if n_out > 1 else 1.0
    idx = np.rint((tt - t_out[0]) / dto).astype(int)
    on_grid = (idx > i_good) & (idx < n_out) & \
        (np.abs(t_out[np.clip(idx, 0, n_out - 1)] - tt) <= 1e-6 * dto)
    return idx, on_grid


def simulate(params, t_out, settings):
    """Spin-up run on the output grid t_out (uniform, t_out[0] = 0); see the leaf contract."""
    t_out = np.asarray(t_out, dtype=float)
    s = check_settings(settings, t_out)
    name = s["integrator"]
    adaptive = name in ADAPTIVE
    if not adaptive and len(t_out) > 1 and float(s["dt"]) > (t_out[1] - t_out[0]) * (1 + 1e-9):
        return _coarse(params, t_out, s)
    n_out = len(t_out)
    dto = float(t_out[1] - t_out[0]) if n_out > 1 else 1.0
    used = {"integrator": name}
    if adaptive:
        used["rtol"] = float(s["rtol"])
        h = dto
    else:
        dt = float(s["dt"])
        h = fixed_step(dto, dt)
        used["dt"] = h
        if abs(h - dt) > 1e-12 * dt:
            used["dt_requested"] = dt
    if name == "generalized_alpha":
        used["spectral_radius"] = float(s["spectral_radius"])

    Rs = np.full((n_out, 3, 3), np.nan)
    Ws = np.full((n_out, 3), np.nan)
    Wk = np.full(n_out, np.nan)
    Rs[0], Ws[0], _ = start(params)
    Wk[0] = 0.0

    # state to start the next Exudyn run from: time, rotation, angular velocity, work
    t_c, R_c, w_c, W_c = 0.0, Rs[0], Ws[0], 0.0
    i_good = 0                                          # last output sample filled
    A0 = np.eye(3)
    status, t_fail, reason = "ok", None, None
    steps = rhs_evals = charts = 0
    no_progress = 0
    h_adapt = None                                      # adaptive: step size to go on with
    solver = SOLVERS[name]
    wall0 = time.perf_counter()
    while i_good < n_out - 1:
        q0, qd0 = chart_coordinates(A0, R_c, w_c)
        model = build([rotor(params, A0, q0, qd0, W_c, float(params["torque"]))])
        mbs, flag = model["mbs"], model["flag"]
        t_start = t_c
        ex = None
        # adaptive runs go interval by interval (each run ends exactly on the grid, the end state
        # is the next run's initial state); fixed-step runs go to the end in one call
        while i_good < n_out - 1:
            t_end = t_out[i_good + 1] if adaptive else t_out[-1]
            n_steps = 1 if adaptive else max(1, int(round((t_end - t_c) / h)))
            ss = sim_settings(t_c, t_end, n_steps, 0.0, name, s["rtol"],
                              s["spectral_radius"], h_adapt)
            ex = solve(mbs, ss, solver, update=adaptive)
            steps += steps_of(mbs)
            if adaptive:
                h_adapt = last_step_of(mbs, h_adapt)
            tt, q, qd, w = stored(model)
            keep = tt > t_c + 1e-12 * max(1.0, t_c)
            tt, q, qd, w = tt[keep], q[keep, 0], qd[keep, 0], w[keep, 0]
            fin = np.isfinite(q).all(axis=1) & np.isfinite(qd).all(axis=1) & np.isfinite(w)
            if not np.all(fin):
                first = int(np.argmin(fin))
                flag["kind"], flag["t"] = "nonfinite", float(tt[first])
                tt, q, qd, w = tt[:first], q[:first], qd[:first], w[:first]
                ex = ex or Stop()
            if len(tt):
                Rd, wd = chart_motion(A0, q, qd)
                idx, on_grid = grid_samples(tt, t_out, i_good)
                Rs[idx[on_grid]], Ws[idx[on_grid]], Wk[idx[on_grid]] = \
                    Rd[on_grid], wd[on_grid], w[on_grid]
                if np.any(on_grid):
                    i_good = int(idx[on_grid][-1])
                t_c, R_c, w_c, W_c = float(tt[-1]), Rd[-1], wd[-1], float(w[-1])
            if ex is not None or not adaptive or flag["kind"] is not None:
                break
        rhs_evals += flag["calls"]
        if status != "ok":
            break
        if ex is None and flag["kind"] == "chart":     # stopped by the post-step check
            ex = Stop()
        if ex is None:
            if i_good < n_out - 1:                      # ran without error but fell short
                status, t_fail = "diverged", float(t_out[i_good + 1])
                reason = "exudyn run ended before t_end"
            break
        kind = flag["kind"]
        no_progress = no_progress + 1 if t_c <= t_start else 0
        if kind == "chart" and no_progress < 2 and charts < MAX_CHART_CHANGES:
            A0 = new_chart(R_c)
            charts += 1
            continue
        status = "diverged"
        t_fail = float(flag["t"]) if flag["t"] is not None else float(t_c)
        if kind == "tilt":
            reason = REASON_TILT
        elif kind == "nonfinite":
            reason = REASON_NONFINITE
        elif kind == "chart":
            reason = ("Cardan chart lock persists after a chart change (state running away: "
                      "step too large?)" if no_progress >= 2 else "too many chart changes")
        else:
            msg = str(ex).strip().splitlines()
            reason = "exudyn: " + (msg[0] if msg else type(ex).__name__)
        break

    wall = time.perf_counter() - wall0
    last = i_good if status != "ok" else n_out - 1
    Rs[last + 1:], Ws[last + 1:], Wk[last + 1:] = np.nan, np.nan, np.nan
    ch = physics.channels(params, Rs, Ws, Wk)
    quat = np.full((n_out, 4), np.nan)
    quat[: last + 1] = quaternions(Rs[: last + 1])
    used["chart_changes"] = charts
    return LeafResult(channels=ch, status=status, t_fail=t_fail, reason=reason,
                      stats={"steps": int(steps), "rhs_evals": int(rhs_evals),
                             "integrate_s": wall}, settings=used,
                      extra={"orientation": quat, "angular_velocity": Ws.copy()})
