"""`simulate`: the spin-up run on the output grid.

With the native callback and an output grid uniform to round-off (the normal case), the whole
run is one `mujoco.rollout.rollout` call per block of up to 2^17 steps at one step
h = span / (intervals · N): the steps run in C, the states come back for every step and the
output rows are picked from them; the torque goes in as the rollout's constant `xfrc_applied`
control (rollout does not keep `xfrc_applied` of the data it is given). Otherwise (Python
callback, uneven grid) `mj_step(m, d, n)` runs the n steps of each output interval in one call.
Measured per RK4 step (the 10 s spin-up, 2 busy cores, CPU time): 7.8 µs → 5.0 (zero clock) →
4.2 µs (stages off, `model`); the 10 s run 125–165 ms through the per-interval loop → 73–77 ms.
"""
import math
import time

import mujoco
import mujoco.rollout
import numpy as np

from compare.contract import LeafResult
from compare.physics import rotor as physics
from compare.physics.rotation import quats_to_matrices

from .callback import Callback, fallback_reason
from .kernel import FLAG_REASONS, U_FLAG, U_TFAIL
from .model import build
from .settings import RHS_PER_STEP, check_settings

_ROLLOUT_BLOCK = 1 << 17             # steps per rollout call (bounds the state buffer)
FULL = mujoco.mjtState.mjSTATE_FULLPHYSICS
XFRC = mujoco.mjtState.mjSTATE_XFRC_APPLIED


def _rollout(m, d, n_per, n_out):
    """Run n_out − 1 output intervals of n_per steps each through mujoco.rollout; returns the
    (time, qpos, qvel, act) rows at the output times that were reached (stops at the first
    block with a callback flag or a non-finite state) and the number of steps taken."""
    nstate = mujoco.mj_stateSize(m, FULL)
    x = np.empty(nstate)
    mujoco.mj_getState(m, d, x, FULL)
    ctrl = np.empty(mujoco.mj_stateSize(m, XFRC))
    mujoco.mj_getState(m, d, ctrl, XFRC)
    ctrl = ctrl.reshape(1, 1, -1)
    per_block = max(1, _ROLLOUT_BLOCK // n_per) * n_per
    total = (n_out - 1) * n_per
    rows, done = [], 0
    while done < total:
        nstep = min(per_block, total - done)
        st, _ = mujoco.rollout.rollout(m, d, x, ctrl, control_spec=XFRC.value, nstep=nstep)
        st = st[0]
        rows.append(st[n_per - 1::n_per])
        done += nstep
        x = st[-1].copy()
        if d.userdata[U_FLAG] != 0.0 or not np.all(np.isfinite(x)):
            break
    return (np.concatenate(rows) if rows else np.empty((0, nstate))), done


def _bad_warnings(d):
    return sum(int(d.warning[int(w)].number) for w in (mujoco.mjtWarning.mjWARN_BADQPOS,
                                                        mujoco.mjtWarning.mjWARN_BADQVEL,
                                                        mujoco.mjtWarning.mjWARN_BADQACC))


def channels(params, spring, quat, vel, work):
    """The shared rotor channels; only the Cardan variant brings its own spring potential."""
    R = quats_to_matrices(np.ascontiguousarray(quat, dtype=float))
    u_spring = None
    if spring == "cardan":
        n = R[:, :, 2]
        beta = np.arcsin(np.clip(n[:, 0], -1, 1))
        alpha = np.arctan2(-n[:, 1], n[:, 2])
        u_spring = 0.5 * float(params["k"]) * (alpha**2 + beta**2)
    return physics.channels(params, R, np.einsum("nij,nj->ni", R, vel), work, u_spring)


def _step_loop(m, d, chunks, step_t, quat, vel, work):
    """mj_step(m, d, n) per output interval, checks after each; fills the rows reached."""
    status, t_fail, reason, steps = "ok", None, None, 0
    ud = d.userdata
    t_now = 0.0
    cur_h = None
    for i, (n, h) in enumerate(chunks):
        if h != cur_h:
            m.opt.timestep = cur_h = h
        mujoco.mj_step(m, d, n)
        steps += n
        t_expect = step_t[i + 1]
        qp, qv = d.qpos, d.qvel
        bad = None
        if ud[U_FLAG] != 0.0:
            bad = FLAG_REASONS.get(float(ud[U_FLAG]), "callback flag")
            t_fail = float(ud[U_TFAIL])
        elif _bad_warnings(d):
            bad = "MuJoCo reported a bad (NaN/huge) qpos/qvel/qacc"
        elif not (np.all(np.isfinite(qp)) and np.all(np.isfinite(qv))
                  and math.isfinite(d.act[0])):
            bad = "non-finite state"
        elif abs(d.time - t_expect) > 1e-9 * max(1.0, t_expect):
            bad = f"time did not advance as expected (MuJoCo reset?) t={d.time:.6g}"
        if bad is not None:
            status, reason = "diverged", bad
            if t_fail is None or not math.isfinite(t_fail):
                t_fail = float(t_expect)
            t_fail = float(min(max(t_fail, t_now), t_expect))
            break
        quat[i + 1], vel[i + 1], work[i + 1] = qp, qv, d.act[0]
        t_now = t_expect
    return status, t_fail, reason, steps


def simulate(params: dict, t_out: np.ndarray, settings: dict) -> dict:
    """Integrate the rotor; channels on t_out (see module doc and the leaf-model contract).

    Steps: each output interval Δ is split into N = ceil(Δ/dt) equal steps (h = Δ/N ≤ dt; h = dt
    when dt divides Δ, reported as ``settings['dt_effective']``); on a grid uniform to
    round-off every interval takes the mean step. If dt > Δ the integrator steps at exactly dt
    and the channels are interpolated linearly onto t_out."""
    s = check_settings(settings)
    t_out = np.asarray(t_out, dtype=float)
    if t_out.ndim != 1 or t_out.size < 1 or t_out[0] != 0.0 or np.any(np.diff(t_out) <= 0):
        raise ValueError("t_out must be increasing and start at 0")
    return run(params, t_out, s)


def uniform_steps(t_out, dt):
    """(steps per output interval, step) where the grid is uniform but for round-off (np.diff
    of a linspace) and no coarser than dt: the whole run is one step size, so one rollout.
    None otherwise."""
    intervals = np.diff(t_out)
    if not intervals.size or dt > intervals.min() * (1 + 1e-9) or \
            np.ptp(intervals) > 1e-9 * intervals.mean():
        return None
    n = max(1, int(math.ceil(intervals[0] / dt - 1e-9)))
    return n, float((t_out[-1] - t_out[0]) / (n * intervals.size))


def run(params, t_out, s, model=None):
    """`simulate` on checked settings and grid; `model`: a compiled one to reuse (`build`)."""
    m, d, bid = build(params, s, s["integrator"], float(params["torque"]), model)

    dt = s["dt"]
    intervals = np.diff(t_out)
    coarse = bool(intervals.size) and dt > intervals.min() * (1 + 1e-9)
    if coarse:   # step grid t = j·dt, interpolate
        nsteps = int(math.ceil(t_out[-1] / dt - 1e-9))
        step_t = dt * np.arange(nsteps + 1)
        chunks = [(1, dt)] * nsteps
    else:
        ns = np.maximum(1, np.ceil(intervals / dt - 1e-9).astype(int))
        chunks = list(zip(ns.tolist(), (intervals / ns).tolist()))
        one_step = uniform_steps(t_out, dt)
        if one_step:
            chunks = [one_step] * intervals.size
        step_t = t_out
    nrec = len(chunks) + 1
    quat = np.full((nrec, 4), np.nan)
    vel = np.full((nrec, 3), np.nan)
    work = np.full(nrec, np.nan)
    quat[0], vel[0], work[0] = d.qpos, d.qvel, 0.0

    status, t_fail, reason, steps = "ok", None, None, 0
    ud = d.userdata
    uniform = len(set(chunks)) == 1
    wall0 = time.perf_counter()
    with Callback(s["callback"]) as cbk:
        if cbk.kind == "native" and uniform:
            m.opt.timestep = chunks[0][1]
            rows, steps = _rollout(m, d, chunks[0][0], nrec)
            nq = 1 + m.nq
            fin = np.all(np.isfinite(rows), axis=1)
            good = int(np.argmin(fin)) if not fin.all() else len(rows)
            if ud[U_FLAG] != 0.0:
                t_fail = float(ud[U_TFAIL])
                reason = FLAG_REASONS.get(float(ud[U_FLAG]), "callback flag")
                good = min(good, int(np.searchsorted(step_t[1:], t_fail, side="left")))
            elif good < len(rows) or len(rows) < nrec - 1:
                reason = "non-finite state"
                t_fail = float(step_t[min(good + 1, nrec - 1)])
            quat[1:good + 1] = rows[:good, 1:nq]
            vel[1:good + 1] = rows[:good, nq:nq + m.nv]
            work[1:good + 1] = rows[:good, nq + m.nv]
            if reason is not None:
                status = "diverged"
        else:
            status, t_fail, reason, steps = _step_loop(m, d, chunks, step_t, quat, vel, work)
        kind = cbk.kind
    wall = time.perf_counter() - wall0

    ch = channels(params, s["spring"], quat, vel, work)
    orient = quat / np.linalg.norm(quat, axis=1, keepdims=True)
    if coarse:
        good = np.isfinite(work)
        tt = step_t[good]
        out = {}
        for name, v in ch.items():
            out[name] = np.interp(t_out, tt, v[good], right=np.nan) if tt.size > 1 else \
                np.where(t_out == 0, v[0], np.nan)
        ch = out
        o = np.stack([np.interp(t_out, tt, orient[good, j], right=np.nan) if tt.size > 1 else
                      np.where(t_out == 0, orient[0, j], np.nan) for j in range(4)], axis=1)
        orient = o / np.linalg.norm(o, axis=1, keepdims=True)
    if status != "ok":
        late = t_out >= t_fail
        for v in ch.values():
            v[late] = np.nan
        orient[late] = np.nan
    used = dict(s)
    used["callback"] = kind
    used["dt_effective"] = float(dt if coarse else min(h for _, h in chunks) if chunks else dt)
    if kind != s["callback"]:
        used["callback_fallback_reason"] = fallback_reason()
    return LeafResult(
        channels={name: np.ascontiguousarray(v, dtype=np.float64) for name, v in ch.items()},
        status=status, t_fail=t_fail, reason=reason,
        stats={"steps": int(steps), "rhs_evals": int(steps * RHS_PER_STEP[s["integrator"]]),
               "integrate_s": wall},
        settings=used, extra={"orientation": orient})
