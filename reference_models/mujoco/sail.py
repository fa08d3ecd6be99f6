"""MuJoCo reference model of the heliogyro blade deployment (scene `sail-deploy`, seed 004).

Inertial frame, one blade (symmetric deployment: the hub carries J_hub/2, channels report both
blades; see reference_models/sail_common.py for the shared scene definition and release law).

- Hub: a body on a hinge about world z (inertia J_hub/2 about z) with a site Q at (L_c, 0, r).
- Nodes: n point-mass bodies, each on three world-aligned slide joints (body origin at Q in the
  reference configuration, so qpos = displacement from Q0).
- Thread: spatial tendons between neighbouring nodes with MuJoCo's passive tendon
  spring–damper (stiffness c, damping d on the tendon velocity, spring length l0). A tendon is
  switched on (tendon_stiffness/damping set) when its inner node is released.
- Boundary segment node→Q with the growing rest length l0(t): a `general` actuator on the
  tendon node_j→Q with integrator dynamics (act' = ctrl = r ω, so act = l0(t) exactly),
  gain c and affine bias (d r ω, −c, −d): force = c (act − ℓ) − d (ℓ' − r ω), i.e. the spring
  with rest length l0(t) and the damper on the true stretch rate. Only the boundary node's
  actuator has non-zero gain/bias (model arrays switched at release).
- Stored nodes, setting `stored`:
  * "hub" (default): the stored thread is part of the hub inertia (J_hub/2 + Σ_stored m_j L_c²,
    as in the custom conservative variant); a stored node is a parked body with no force on it.
    At t_j the hub inertia drops by m_j L_c² and the node is put exactly at Q with the hub-point
    velocity + r ω along the rotated X1 axis: angular momentum continuous, Ω without a jump.
    MuJoCo 4.0 takes the hinge's mass-matrix entry from mj_setConst, so a new body_inertia needs
    mj_setConst (state saved around it); without it the run silently keeps the old inertia
    (measured: angular-momentum drift 1.7e-5 in 2 s instead of 2e-14).
  * "equality": `connect` equalities site(node) ↔ site(Q) (solref timeconst 2·dt) hold the
    stored nodes; at t_j the equality is switched off through `data.eq_active[j] = 0` and the
    node gets the same release state. The constraint solver costs ~3x the wall time (n = 20,
    k = 1e7: 29.9 s vs 8.2 s for 2 s) and the soft constraint leaves a small drift (≤ 3e-9 in
    15 s, 5.7e-11 over 30 s at k = 1e7); it is kept as the constraint-based cross-check.

Events are landed on exactly (the last step before an event is shortened by changing
`opt.timestep`). Steps are taken one `mj_step` at a time so that the spool work
−∫ f_Q r ω dt is summed at every step from `actuator_force` (the Python loop costs < 2 % of a
step; sampled on the output grid the work aliased the boundary tension's ringing and the energy
balance was off by 2.5e-3 J in a 0.07 J system). With the stored thread in the hub the Jacobian
is dense (measured 17 vs 25 µs per step, n = 20), with equality-held nodes sparse (30 vs 39).
Explicit integrators need the step below the highest spring frequency: `dt="auto"` takes
0.8 × (2 for "euler", 2.785 for "rk4") / (2 sqrt(c/m_min)). Divergence (MuJoCo's bad-QACC
warning, non-finite state, or a spring stretched beyond `stretch_limit`·l0) ends the run with
status "diverged" and the reason; MuJoCo's auto-reset is disabled so it cannot hide a blow-up.
"""
from __future__ import annotations

import time as _time

import mujoco
import numpy as np

from ..sail_common import (channels, events, formula18, merge_settings, scene,
                           stable_dt_explicit, t_full)

DEFAULT_SETTINGS = {"integrator": "euler", "dt": "auto", "stretch_limit": 0.5, "planar": True,
                    "stored": "hub"}
STORED = ("hub", "equality")
INTEGRATORS = ("euler", "rk4")
_INT = {"euler": mujoco.mjtIntegrator.mjINT_EULER, "rk4": mujoco.mjtIntegrator.mjINT_RK4}
_FACTOR = {"euler": 2.0, "rk4": 2.785}


def _f(x):
    return repr(float(x))


def build_xml(params, dt, integrator, planar=False, held=True):
    jac = "sparse" if held else "dense"
    p, n, l0, m, _ = scene(params)
    Lc, r = p["L_c"], p["r"]
    Jh = 0.5 * p["J_hub"]
    axes = ("1 0 0", "0 1 0") if planar else ("1 0 0", "0 1 0", "0 0 1")
    bodies = []
    for j in range(n):
        joints = "".join(f'<joint name="n{j}_{k}" type="slide" axis="{a}"/>'
                         for k, a in enumerate(axes))
        bodies.append(f'<body name="node{j}" pos="{_f(Lc)} 0 {_f(r)}">'
                      f'<inertial pos="0 0 0" mass="{_f(m[j])}" diaginertia="1e-12 1e-12 1e-12"/>'
                      f'{joints}<site name="n{j}" pos="0 0 0"/></body>')
    tendons = [f'<spatial name="s{j}" stiffness="0" damping="0" springlength="{_f(l0)}">'
               f'<site site="n{j}"/><site site="n{j + 1}"/></spatial>' for j in range(n - 1)]
    tendons += [f'<spatial name="q{j}"><site site="n{j}"/><site site="Q"/></spatial>'
                for j in range(n)]
    acts = [f'<general name="a{j}" tendon="q{j}" dyntype="integrator" gaintype="fixed" '
            f'gainprm="0" biastype="affine" biasprm="0 0 0" ctrllimited="false" '
            f'actlimited="false"/>' for j in range(n)]
    eqs = [f'<connect name="e{j}" site1="n{j}" site2="Q" solref="{_f(2 * dt)} 1"/>'
           for j in range(n)] if held else []
    return f"""<mujoco model="sail">
  <option timestep="{_f(dt)}" integrator="{ {"euler": "Euler", "rk4": "RK4"}[integrator]}" gravity="0 0 0" jacobian="{jac}" solver="Newton">
    <flag contact="disable" autoreset="disable"/>
  </option>
  <worldbody>
    <body name="hub">
      <inertial pos="0 0 0" mass="1" diaginertia="{_f(Jh)} {_f(Jh)} {_f(Jh)}"/>
      <joint name="hub" type="hinge" axis="0 0 1"/>
      <site name="Q" pos="{_f(Lc)} 0 {_f(r)}"/>
    </body>
    {''.join(bodies)}
  </worldbody>
  <tendon>{''.join(tendons)}</tendon>
  <actuator>{''.join(acts)}</actuator>
  <equality>{''.join(eqs)}</equality>
</mujoco>"""


def simulate(params, t_out, settings=None):
    s, t_out = merge_settings(settings, DEFAULT_SETTINGS, INTEGRATORS, t_out)
    p, n, l0, m, t_rel = scene(params)
    dt = s["dt"]
    if dt is None or dt == "auto":
        dt = stable_dt_explicit(p, _FACTOR[s["integrator"]])
    dt = float(dt)
    if s["stored"] not in STORED:
        raise ValueError(f"stored must be one of {STORED}")
    held = s["stored"] == "equality"
    planar = bool(s["planar"])
    nd = 2 if planar else 3
    model = mujoco.MjModel.from_xml_string(build_xml(p, dt, s["integrator"], planar, held))
    data = mujoco.MjData(model)
    Lc, r, c, d = p["L_c"], p["r"], p["stiffness"], p["damping"]
    rw = r * p["omega_spool"]
    hub_q = model.jnt_qposadr[model.joint("hub").id]
    hub_v = model.jnt_dofadr[model.joint("hub").id]
    qa = np.array([model.jnt_qposadr[model.joint(f"n{j}_0").id] for j in range(n)])
    va = np.array([model.jnt_dofadr[model.joint(f"n{j}_0").id] for j in range(n)])
    Q0 = np.array([Lc, 0.0, r])
    hub_body = model.body("hub").id

    def hub_inertia(b):
        """Half the hub plus, with stored="hub", the thread still stored (nodes > b)."""
        return 0.5 * p["J_hub"] + (0.0 if held else float(m[b + 1:].sum()) * Lc**2)

    def set_hub_inertia(J):
        # MuJoCo 4.0 keeps the hinge's mass-matrix entry from mj_setConst: a new body_inertia
        # takes effect only after it (measured: d.M unchanged by mj_forward alone)
        model.body_inertia[hub_body, 2] = J
        saved = data.qpos.copy(), data.qvel.copy(), data.act.copy()
        mujoco.mj_setConst(model, data)
        data.qpos[:], data.qvel[:], data.act[:] = saved

    def node_state():
        X = np.zeros((n, 3))
        V = np.zeros((n, 3))
        for j in range(n):
            X[j, :nd] = data.qpos[qa[j]:qa[j] + nd]
            V[j, :nd] = data.qvel[va[j]:va[j] + nd]
        X += Q0
        return X, V

    def release(j):
        psi, Om = data.qpos[hub_q], data.qvel[hub_v]
        cp, sp = np.cos(psi), np.sin(psi)
        Q = np.array([Lc * cp, Lc * sp, r])
        if held:
            data.eq_active[j] = 0
        else:
            set_hub_inertia(hub_inertia(j))
        data.qpos[qa[j]:qa[j] + nd] = (Q - Q0)[:nd]
        data.qvel[va[j]:va[j] + nd] = np.array([-Om * Q[1] + rw * cp, Om * Q[0] + rw * sp,
                                                0.0])[:nd]
        model.actuator_gainprm[j, 0] = c
        model.actuator_biasprm[j, :3] = (d * rw, -c, -d)
        data.act[j] = 0.0
        data.ctrl[j] = rw
        if j > 0:
            model.actuator_gainprm[j - 1, 0] = 0.0
            model.actuator_biasprm[j - 1, :3] = 0.0
            data.ctrl[j - 1] = 0.0
            model.tendon_stiffness[j - 1] = c
            model.tendon_damping[j - 1] = d

    # initial state: everything co-rotating with the hub, node 0 released at t = 0
    data.qvel[hub_v] = p["Omega0"]
    set_hub_inertia(hub_inertia(-1))
    for j in range(n):
        data.qvel[va[j] + 1] = p["Omega0"] * Lc if held else 0.0     # held, or parked
    release(0)
    mujoco.mj_forward(model, data)

    N = len(t_out)
    psi_o, Om_o = np.full(N, np.nan), np.full(N, np.nan)
    X_o, V_o = np.full((N, n, 3), np.nan), np.full((N, n, 3), np.nan)
    b_o = np.full(N, -1)
    W_o = np.full(N, np.nan)
    b = 0
    work = {"W": 0.0, "rate": rw}             # spool work on one blade; payout speed
    af = data.actuator_force
    t = 0.0
    steps = 0
    status, reason, t_fail = "ok", None, None
    wall0 = _time.perf_counter()

    def end_payout(j):
        """Full payout: the spool stops (act stays at l0, damper on the true stretch rate) and
        the last node stays tied to Q, or its Q-spring is removed (last_node "released")."""
        data.ctrl[j] = 0.0
        work["rate"] = 0.0
        keep = p["last_node"] == "attached"
        model.actuator_gainprm[j, 0] = c if keep else 0.0
        model.actuator_biasprm[j, :3] = (0.0, -c, -d) if keep else (0.0, 0.0, 0.0)

    for (te, io, jr) in events(t_out, t_rel, t_out[-1], t_full(p)):
        if te > t:
            K = int(np.floor((te - t) / dt * (1 + 1e-12)))
            rem = te - t - K * dt
            if K > 0:
                for _ in range(K):
                    mujoco.mj_step(model, data)
                    work["W"] += af[b] * work["rate"] * dt
                steps += K
            if rem > 1e-9 * dt:
                model.opt.timestep = rem
                mujoco.mj_step(model, data)
                work["W"] += af[b] * work["rate"] * rem
                model.opt.timestep = dt
                steps += 1
            t = te
            bad = data.warning[mujoco.mjtWarning.mjWARN_BADQACC].number > 0
            if bad or not np.all(np.isfinite(data.qpos)) or not np.all(np.isfinite(data.qvel)):
                status, t_fail = "diverged", t
                reason = "MuJoCo bad QACC / non-finite state (unstable step?)"
                break
            X, _ = node_state()
            seg = np.sqrt((np.diff(X[:b + 1], axis=0) ** 2).sum(1))
            if seg.size and np.max(np.abs(seg - l0)) > s["stretch_limit"] * l0:
                status, t_fail = "diverged", t
                reason = (f"unstable step: spring stretch beyond {s['stretch_limit']}*l0 "
                          f"(dt={dt:.3g}, estimated limit "
                          f"{stable_dt_explicit(p, _FACTOR[s['integrator']], 1.0):.3g})")
                break
        if jr > 0:
            release(jr)
            b = jr
        elif io < 0 and jr < 0:
            end_payout(b)
        if io >= 0:
            X, V = node_state()
            psi_o[io], Om_o[io] = data.qpos[hub_q], data.qvel[hub_v]
            X_o[io], V_o[io], b_o[io] = X, V, b
            W_o[io] = 2.0 * work["W"]                   # two blades
    wall = _time.perf_counter() - wall0
    ch, extra = channels(p, t_out, psi_o, Om_o, X_o, V_o, b_o, W_o)
    if t_fail is not None:
        for k in ch:
            ch[k][t_out > t_fail] = np.nan
    extra["hub_rate_formula18"] = formula18(p, t_out)
    extra["boundary_node"] = b_o.astype(float)
    return {"channels": ch, "status": status, "t_fail": t_fail, "reason": reason,
            "stats": {"steps": steps, "rhs_evals": steps * (4 if s["integrator"] == "rk4" else 1),
                      "wall_s": wall},
            "settings": {**s, "dt": dt}, "extra": extra}
