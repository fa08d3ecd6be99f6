"""MuJoCo model of the crank–rod–rocker–slider press (`press`) and its lock/release cycle
(`press-cycle`).

Model: a kinematic tree world → crank (hinge at O) → rod (hinge at A) → rocker (hinge at B), and a
second tree world → slider (slide along x, joint stiffness = the slider spring, springref 0,
joint damping = the damper). The loop is closed by a site `connect` C_rocker ↔ C_slider with
solref (2·dt, 1) and solimp (0.9999, 0.9999, 0.001, 0.5, 2); RK4.
Hinge angles: q0 = φ, q1 = θ2 − φ, q2 = (ψ + π) − θ2 (the rocker frame points B → C), so
φ = q0 and ψ = q0 + q1 + q2 − π, both continuous.

Forces that depend on the state are evaluated in every RK4 stage: the Kloss motor torque (and the
press load) in a passive callback; the motor work, damper loss and press work are integrated as
three activations of zero-gain actuators with user dynamics (act_dot = power), so RK4 integrates
them to the same order as the motion. Both callbacks are process-wide globals: they are set for
the run and reset to None in `finally`.

press-cycle: the lock swaps the `connect` for a site `weld` (same solref/solimp) whose target
relative rotation is the one at the lock instant (site_quat of C_slider, with site_sameframe = 0).
The instant is located by bisection on the step with mj_getState/mj_setState; the plastic impact
is applied explicitly with MuJoCo's own mass matrix and equality Jacobian,
q̇⁺ = q̇⁻ − M⁻¹Jᵀ(JM⁻¹Jᵀ)⁺Jq̇⁻.
"""
from __future__ import annotations

import math

import numpy as np

from reference_models import press_common as pc

DEFAULT_SETTINGS = {"integrator": "rk4", "dt": 1e-4, "solref_factor": 4.0,
                    "solimp": (0.9999, 0.9999, 0.001, 0.5, 2.0)}
INTEGRATORS = ("rk4", "euler", "implicitfast", "implicit")

_BISECT_TOL = 1e-9   # s


def _check_settings(settings: dict) -> dict:
    s = pc.fixed_step_settings(settings, DEFAULT_SETTINGS, INTEGRATORS, "mujoco")
    s["solref_factor"] = float(s["solref_factor"])
    if not s["solref_factor"] > 0:
        raise ValueError("solref_factor must be > 0")
    s["solimp"] = tuple(float(x) for x in s["solimp"])
    if len(s["solimp"]) != 5:
        raise ValueError("solimp must have 5 numbers")
    return s


def _xml(p: dict, st: dict, s: dict, cycle: bool) -> str:
    lay = pc.link_layout(p)
    l1, l2, l3 = float(p["l1"]), float(p["l2"]), float(p["l3"])
    cx1, m1, J1 = lay["crank"]
    cx2, m2, J2 = lay["rod"]
    cx3, m3, J3 = lay["rocker"]
    J1 -= pc.crank_rotor_inertia(p)       # the rotor goes in as armature
    arm = pc.crank_rotor_inertia(p)
    # rocker frame points B -> C (length l3); its COM is cx3 from C, i.e. l3 - cx3 from B
    r3 = l3 - cx3
    tc = s["solref_factor"] * s["dt"]
    solref = f"{tc:.17g} 1"
    solimp = " ".join(f"{x:.17g}" for x in s["solimp"])

    def inertial(pos, m, J):
        m = max(m, 1e-12)
        J = max(J, 1e-12)
        return (f'<inertial pos="{pos:.17g} 0 0" mass="{m:.17g}" '
                f'diaginertia="{J:.17g} {J:.17g} {J:.17g}"/>')
    integ = {"rk4": "RK4", "euler": "Euler", "implicitfast": "implicitfast", "implicit": "implicit"}[s["integrator"]]
    weld = ""
    if cycle:
        weld = (f'<weld name="lock" site1="C_rocker" site2="C_slider" active="false" '
                f'solref="{solref}" solimp="{solimp}"/>')
    return f"""
<mujoco model="press">
  <option timestep="{s['dt']:.17g}" integrator="{integ}" gravity="0 {-float(p['gravity']):.17g} 0" jacobian="dense">
    <flag contact="disable" energy="enable" autoreset="disable"/>
  </option>
  <worldbody>
    <body name="crank" pos="0 0 0">
      <joint name="phi" type="hinge" axis="0 0 1" armature="{arm:.17g}"/>
      {inertial(cx1, m1, J1)}
      <body name="rod" pos="{l1:.17g} 0 0">
        <joint name="rel2" type="hinge" axis="0 0 1"/>
        {inertial(cx2, m2, J2)}
        <body name="rocker" pos="{l2:.17g} 0 0">
          <joint name="rel3" type="hinge" axis="0 0 1"/>
          {inertial(r3, m3, J3)}
          <site name="C_rocker" pos="{l3:.17g} 0 0"/>
        </body>
      </body>
    </body>
    <body name="slider" pos="{st['C'][0]:.17g} 0 0">
      <joint name="xs" type="slide" axis="1 0 0" stiffness="{float(p['slider_stiffness']):.17g}"
             springref="0" damping="{float(p['slider_damping']):.17g}"/>
      <inertial pos="0 0 0" mass="{max(float(p['m4']), 1e-12):.17g}" diaginertia="1e-6 1e-6 1e-6"/>
      <site name="C_slider" pos="0 0 0"/>
    </body>
  </worldbody>
  <equality>
    <connect name="loop" site1="C_rocker" site2="C_slider" solref="{solref}" solimp="{solimp}"/>
    {weld}
  </equality>
  <actuator>
    <general name="motor_work" joint="phi" dyntype="user" gainprm="0" biastype="none"/>
    <general name="damper_loss" joint="phi" dyntype="user" gainprm="0" biastype="none"/>
    <general name="press_work" joint="phi" dyntype="user" gainprm="0" biastype="none"/>
  </actuator>
</mujoco>
"""


def simulate(params: dict, t_out: np.ndarray, settings: dict | None = None, *, cycle: bool | None = None) -> dict:
    """Run the press (idle) scene; with lock_after/lock_angle/press_force/release_after in params
    (or cycle=True) the press-cycle scene."""
    import mujoco
    cycle, p, s, t_out, st = pc.prepare(params, t_out, settings, _check_settings, cycle)
    dt = s["dt"]
    m = mujoco.MjModel.from_xml_string(_xml(p, st, s, cycle))
    d = mujoco.MjData(m)
    u = float(p["gear_ratio"])
    c = float(p["slider_damping"])
    F = float(p.get("press_force", 0.0))
    vreg = float(p.get("press_force_vreg", 0.01))
    flags = {"locked": False}
    sid_r = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, "C_rocker")
    sid_s = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, "C_slider")
    eq_loop = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_EQUALITY, "loop")
    eq_lock = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_EQUALITY, "lock") if cycle else -1

    def passive(m_, d_):
        d_.qfrc_passive[0] += pc.motor_torque(d_.qvel[0], u)
        if flags["locked"] and F != 0.0:
            d_.qfrc_passive[3] += pc.press_load(d_.qvel[3], F, vreg)

    def act_dyn(m_, d_, i):
        if i == 0:
            return pc.motor_torque(d_.qvel[0], u) * d_.qvel[0]
        if i == 1:
            return c * d_.qvel[3] ** 2
        return -pc.press_load(d_.qvel[3], F, vreg) * d_.qvel[3] if flags["locked"] else 0.0

    # initial state
    d.qpos[:] = [st["phi"], st["theta2"] - st["phi"], st["psi"] + math.pi - st["theta2"], 0.0]
    d.qvel[:] = [st["phid"], st["theta2d"] - st["phid"], st["psid"] - st["theta2d"], st["vC"][0]]
    d.act[:] = 0.0

    n = len(t_out)
    ch = {k: np.full(n, np.nan) for k in pc.CHANNELS}
    extra = {}
    lock_loss = [0.0]
    steps = [0]
    spec = mujoco.mjtState.mjSTATE_INTEGRATION
    nstate = mujoco.mj_stateSize(m, spec)

    def psi_of(qpos):
        return qpos[0] + qpos[1] + qpos[2] - math.pi

    vmax = 1e-3 * (float(p["l1"]) + float(p["l2"]) + float(p["l3"]))   # the model has fallen apart

    def observe(k):
        mujoco.mj_forward(m, d)
        T = d.energy[1]
        V = d.energy[0]
        ch["crank_angle"][k] = d.qpos[0]
        ch["crank_rate"][k] = d.qvel[0]
        ch["crank_accel"][k] = d.qacc[0]
        ch["rocker_angle"][k] = psi_of(d.qpos)
        ch["slider_x"][k] = st["C"][0] + d.qpos[3]
        ch["loop_violation"][k] = float(np.linalg.norm(d.site_xpos[sid_r, :2] - d.site_xpos[sid_s, :2]))
        ch["energy_balance"][k] = T + V - d.act[0] + d.act[1] + d.act[2] + lock_loss[0]
        if not ch["loop_violation"][k] <= vmax:
            raise FloatingPointError(f"loop violation {ch['loop_violation'][k]:.3g} m exceeds {vmax:.3g} m")

    def step(h):
        m.opt.timestep = h
        mujoco.mj_step(m, d)
        steps[0] += 1
        if (not np.all(np.isfinite(d.qpos)) or not np.all(np.isfinite(d.qvel))
                or not np.all(np.isfinite(d.act))
                or d.warning[mujoco.mjtWarning.mjWARN_BADQACC].number > 0):
            raise FloatingPointError("non-finite state (MuJoCo bad qacc)"
                                     + (f": {warnings[-1].strip()}" if warnings else ""))

    bounds, out_index, events = pc.breakpoints(p, t_out, cycle)
    la, ra, psiL = events if cycle else (None, None, None)

    status, t_fail, reason = "ok", None, None
    warnings: list[str] = []
    prev_warning = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(warnings.append)     # no stdout, no MUJOCO_LOG.TXT
    mujoco.set_mjcb_passive(passive)
    mujoco.set_mjcb_act_dyn(act_dyn)
    try:
        observe(0)
        t = 0.0
        released = False
        t_lock = None
        for t1 in bounds[1:]:
            while t < t1 - 1e-15:
                nst = max(1, int(math.ceil((t1 - t) / dt - 1e-9)))
                h = (t1 - t) / nst
                armed = cycle and t_lock is None and la - 1e-15 <= t < ra - 1e-15
                if armed:
                    saved = np.empty(nstate)
                    mujoco.mj_getState(m, d, saved, spec)
                    g0 = psi_of(d.qpos) - psiL
                step(h)
                if armed:
                    g1 = psi_of(d.qpos) - psiL
                    if g0 == 0.0 or np.sign(g1) != np.sign(g0):
                        lo, hi = 0.0, h
                        nb = 0
                        while hi - lo > _BISECT_TOL:
                            mid = 0.5 * (lo + hi)
                            mujoco.mj_setState(m, d, saved, spec)
                            step(mid)
                            nb += 1
                            gm = psi_of(d.qpos) - psiL
                            if gm != 0.0 and np.sign(gm) == np.sign(g0):
                                lo = mid
                            else:
                                hi = mid
                        mujoco.mj_setState(m, d, saved, spec)
                        step(hi)
                        t_lock = d.time
                        # lock: swap connect -> weld at the current relative rotation
                        mujoco.mj_kinematics(m, d)
                        qrel = np.empty(4)
                        mujoco.mju_mat2Quat(qrel, d.site_xmat[sid_r])
                        m.site_quat[sid_s] = qrel           # slider body frame = world rotation
                        m.site_sameframe[sid_s] = 0
                        d.eq_active[eq_loop] = 0
                        d.eq_active[eq_lock] = 1
                        mujoco.mj_forward(m, d)
                        T_before = d.energy[1]
                        M = np.zeros((m.nv, m.nv))
                        mujoco.mj_fullM(m, d, M)
                        rows = d.efc_type[:d.nefc] == mujoco.mjtConstraint.mjCNSTR_EQUALITY
                        J = d.efc_J[:d.nefc * m.nv].reshape(d.nefc, m.nv)[rows]
                        J = J[np.any(np.abs(J) > 1e-14, axis=1)]
                        v = d.qvel.copy()
                        MiJt = np.linalg.solve(M, J.T)
                        lam = np.linalg.lstsq(J @ MiJt, J @ v, rcond=None)[0]
                        vn = v - MiJt @ lam
                        d.qvel[:] = vn
                        flags["locked"] = True
                        mujoco.mj_forward(m, d)
                        lock_loss[0] = T_before - d.energy[1]
                        extra.update({"lock_time": np.array([t_lock]),
                                      "lock_energy_loss": np.array([lock_loss[0]]),
                                      "lock_bisections": np.array([nb]),
                                      "crank_rate_jump": np.array([vn[0] - v[0]])})
                t = d.time
                if t > t1 - 1e-12:
                    t = t1
                    d.time = t1
            k = out_index.get(float(t1))
            if k is not None:
                observe(k)     # before a release at this instant: left limits, as the Exudyn leaf
            if cycle and flags["locked"] and not released and abs(t - ra) < 1e-12:
                d.eq_active[eq_lock] = 0
                d.eq_active[eq_loop] = 1
                flags["locked"] = False
                released = True
    except FloatingPointError as exc:
        status, t_fail, reason = "diverged", float(d.time), str(exc)
        bad = t_out > t_fail - 1e-15
        for name in ch:
            ch[name][bad] = np.nan
    finally:
        mujoco.set_mjcb_passive(None)
        mujoco.set_mjcb_act_dyn(None)
        mujoco.set_mju_user_warning(prev_warning)
    if cycle:
        extra.setdefault("lock_time", np.array([np.nan]))
        extra.setdefault("lock_energy_loss", np.array([np.nan]))
        extra["motor_work"] = np.array([d.act[0]])
        extra["press_work"] = np.array([d.act[2]])
    return {"channels": ch, "status": status, "t_fail": t_fail, "reason": reason,
            "stats": {"steps": steps[0], "rhs_evals": 4 * steps[0] if s["integrator"] == "rk4" else steps[0]},
            "settings": dict(s), "extra": extra}
