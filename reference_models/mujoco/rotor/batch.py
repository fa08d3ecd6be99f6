"""`regimes`, the map's batch path: many points through the same steps as `simulate`, the
model compiled once per distinct set of MODEL_FIELDS (torque and k are data, not model) and
each run reduced to its regime by `physics.regime_summaries`, the rule the compiled custom
batch applies.
"""
import math

import mujoco
import mujoco.rollout
import numpy as np

from compare.contract import LeafResult
from compare.physics import rotor as physics

from .callback import Callback, native_callback
from .kernel import U_POISON
from .model import MODEL_FIELDS, compile_model, load
from .settings import check_settings
from .time import FULL, XFRC, channels, run, uniform_steps


def regimes(params_list, t_out, settings, channel, levels, window):
    """The map's batch path, reduced to the regime on |ω| (`physics.regime_summaries`; None for
    another channel). `levels`: (n, 2) per point. With the native callback on a uniform grid
    (the normal case) the points sharing MODEL_FIELDS run as one `mujoco.rollout` call
    (`_rolled_together`); else each point is `time.run` on its group's model."""
    if channel != "omega_norm":
        return None
    s = check_settings(settings)
    t_out = np.asarray(t_out, dtype=float)
    groups: dict = {}
    for i, p in enumerate(params_list):
        key = repr([np.asarray(p[f], float).tolist() for f in MODEL_FIELDS])
        groups.setdefault(key, []).append(i)
    runs = [None] * len(params_list)
    for idx in groups.values():
        m = compile_model(params_list[idx[0]], s, s["integrator"])
        group = [params_list[i] for i in idx]
        done = _rolled_together(m, group, t_out, s)
        for i, r in zip(idx, done or [run(p, t_out, s, m) for p in group]):
            runs[i] = r
    levels = np.asarray(levels, float)
    return physics.regime_summaries(t_out, runs, levels[:, 0], levels[:, 1], window)


_BATCH_ROWS = 1 << 18          # states per rollout call (rolls × steps): ≈ 20 MB for the rotor
_USER = mujoco.mjtState.mjSTATE_USERDATA


def _rolled_together(m, group, t_out, s):
    """Every point of `group` (one model) in one `mujoco.rollout` call per ≤ _BATCH_ROWS
    states: each roll's initial state, drive wrench and userdata are its own (the wrench and
    the userdata as the rollout's constant control), the steps those of `time.run`. A flagged stage
    makes the roll's state NaN (`U_POISON`): such a run comes back `diverged` and the caller
    runs it alone, which says why. None where `time.run` would not take one rollout (Python
    callback, a step longer than the output step, an uneven grid)."""
    one_step = uniform_steps(t_out, s["dt"])
    if one_step is None or s["callback"] != "native" or native_callback() is None:
        return None
    n_per, m.opt.timestep = one_step
    d = mujoco.MjData(m)
    bid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "rotor")
    spec = XFRC.value | _USER.value
    x0 = np.empty((len(group), mujoco.mj_stateSize(m, FULL)))
    ctrl = np.empty((len(group), 1, mujoco.mj_stateSize(m, spec)))
    for x, c, p in zip(x0, ctrl, group):
        load(d, bid, p, s, float(p["torque"]))
        d.userdata[U_POISON] = 1.0
        mujoco.mj_getState(m, d, x, FULL)
        mujoco.mj_getState(m, d, c[0], spec)
    nstep = n_per * (len(t_out) - 1)
    per_call = max(1, _BATCH_ROWS // nstep)
    nq, runs = 1 + m.nq, []
    with Callback("native"):
        for a in range(0, len(group), per_call):
            st, _ = mujoco.rollout.rollout(m, d, x0[a:a + per_call], ctrl[a:a + per_call],
                                           control_spec=spec, nstep=nstep)
            for p, rows in zip(group[a:a + per_call], st[:, n_per - 1::n_per]):
                if not np.all(np.isfinite(rows)):
                    runs.append(LeafResult(channels={}, status="diverged", t_fail=math.nan))
                    continue
                quat = np.vstack([x0[len(runs), 1:nq], rows[:, 1:nq]])
                vel = np.vstack([x0[len(runs), nq:nq + m.nv], rows[:, nq:nq + m.nv]])
                work = np.concatenate([[0.0], rows[:, nq + m.nv]])
                runs.append(LeafResult(channels=channels(p, s["spring"], quat, vel, work)))
    return runs
