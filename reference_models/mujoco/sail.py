"""MuJoCo reference model of the heliogyro blade deployment (scene `sail-deploy`, seed 004).

Inertial frame, one blade (symmetric deployment: the hub carries J_hub/2, channels report both
blades; the scene physics — thread, payout, release law, breakpoints, channels — is
compare/physics/sail.py).

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

from compare.contract import LeafResult, check_once, merge_settings, require_positive
from compare.physics import sail as phys

from ..sail_common import check_grid, stable_dt_explicit

DEFAULT_SETTINGS = {"integrator": "euler", "dt": "auto", "stretch_limit": 0.5, "planar": True,
                    "stored": "hub"}
STORED = ("hub", "equality")
INTEGRATORS = ("euler", "rk4")
_INT = {"euler": mujoco.mjtIntegrator.mjINT_EULER, "rk4": mujoco.mjtIntegrator.mjINT_RK4}
_FACTOR = {"euler": 2.0, "rk4": 2.785}
# The error estimate's coarser members (compare/leafinfo.py `COARSER_DT`): the auto step is 0.8
# of the stability bound (sail_common.stable_dt_explicit, whose λ bounds the chain's highest
# frequency from above), so 1.2× the step stays at 0.96 of it; halving costs 2× the run.
COARSER_DT = {"euler": (1.1, 1.2), "rk4": (1.1, 1.2)}


def _f(x):
    return repr(float(x))


def build_xml(params, dt, integrator, planar=False, held=True):
    jac = "sparse" if held else "dense"
    n, l0, m, _ = phys.thread(params)
    Lc, r = params["L_c"], params["r"]
    Jh = 0.5 * params["J_hub"]
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
    integ = {"euler": "Euler", "rk4": "RK4"}[integrator]
    return f"""<mujoco model="sail">
  <option timestep="{_f(dt)}" integrator="{integ}" gravity="0 0 0" jacobian="{jac}"
          solver="Newton">
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


class _Sail:
    """build (model, data, the initial state with node 0 released) / release / step /
    observe."""

    def __init__(self, p: dict, s: dict, dt: float, n_out: int):
        self.p, self.s, self.dt = p, s, dt
        self.n, self.l0, self.m, self.t_rel = phys.thread(p)
        self.held = s["stored"] == "equality"
        self.nd = 2 if bool(s["planar"]) else 3
        self.model = model = mujoco.MjModel.from_xml_string(
            build_xml(p, dt, s["integrator"], bool(s["planar"]), self.held))
        self.data = data = mujoco.MjData(model)
        self.rw = p["r"] * p["omega_spool"]
        self.hub_q = model.jnt_qposadr[model.joint("hub").id]
        self.hub_v = model.jnt_dofadr[model.joint("hub").id]
        self.qa = np.array([model.jnt_qposadr[model.joint(f"n{j}_0").id] for j in range(self.n)])
        self.va = np.array([model.jnt_dofadr[model.joint(f"n{j}_0").id] for j in range(self.n)])
        self.Q0 = np.array([p["L_c"], 0.0, p["r"]])
        self.hub_body = model.body("hub").id
        self.b = 0
        self.steps = 0
        self.work = {"W": 0.0, "rate": self.rw}    # spool work on one blade; payout speed
        self.out = {"psi": np.full(n_out, np.nan), "omega": np.full(n_out, np.nan),
                    "X": np.full((n_out, self.n, 3), np.nan),
                    "V": np.full((n_out, self.n, 3), np.nan),
                    "b": np.full(n_out, -1), "W": np.full(n_out, np.nan)}
        # initial state: everything co-rotating with the hub, node 0 released at t = 0
        data.qvel[self.hub_v] = p["Omega0"]
        self.set_hub_inertia(self.hub_inertia(-1))
        for j in range(self.n):
            data.qvel[self.va[j] + 1] = p["Omega0"] * p["L_c"] if self.held else 0.0
        self.release(0)
        mujoco.mj_forward(model, data)

    def hub_inertia(self, b: int) -> float:
        """Half the hub plus, with stored="hub", the thread still stored (nodes > b)."""
        extra = 0.0 if self.held else float(self.m[b + 1:].sum()) * self.p["L_c"]**2
        return 0.5 * self.p["J_hub"] + extra

    def set_hub_inertia(self, J: float) -> None:
        # MuJoCo 4.0 keeps the hinge's mass-matrix entry from mj_setConst: a new body_inertia
        # takes effect only after it (measured: d.M unchanged by mj_forward alone)
        model, data = self.model, self.data
        model.body_inertia[self.hub_body, 2] = J
        saved = data.qpos.copy(), data.qvel.copy(), data.act.copy()
        mujoco.mj_setConst(model, data)
        data.qpos[:], data.qvel[:], data.act[:] = saved

    def node_state(self) -> tuple:
        X = np.zeros((self.n, 3))
        V = np.zeros((self.n, 3))
        nd, data = self.nd, self.data
        for j in range(self.n):
            X[j, :nd] = data.qpos[self.qa[j]:self.qa[j] + nd]
            V[j, :nd] = data.qvel[self.va[j]:self.va[j] + nd]
        X += self.Q0
        return X, V

    def release(self, j: int) -> None:
        """Node j leaves Q by the shared release law; its actuator becomes the Q-spring."""
        model, data, nd = self.model, self.data, self.nd
        c, d = self.p["stiffness"], self.p["damping"]
        q0, q1, q2, v0, v1, v2 = phys.release_state(data.qpos[self.hub_q], data.qvel[self.hub_v],
                                                    self.p["L_c"], self.p["r"], self.rw)
        if self.held:
            data.eq_active[j] = 0
        else:
            self.set_hub_inertia(self.hub_inertia(j))
        data.qpos[self.qa[j]:self.qa[j] + nd] = (np.array([q0, q1, q2]) - self.Q0)[:nd]
        data.qvel[self.va[j]:self.va[j] + nd] = np.array([v0, v1, v2])[:nd]
        model.actuator_gainprm[j, 0] = c
        model.actuator_biasprm[j, :3] = (d * self.rw, -c, -d)
        data.act[j] = 0.0
        data.ctrl[j] = self.rw
        if j > 0:
            model.actuator_gainprm[j - 1, 0] = 0.0
            model.actuator_biasprm[j - 1, :3] = 0.0
            data.ctrl[j - 1] = 0.0
            model.tendon_stiffness[j - 1] = c
            model.tendon_damping[j - 1] = d
        self.b = j

    def end_payout(self) -> None:
        """Full payout: the spool stops (act stays at l0, damper on the true stretch rate) and
        the last node stays tied to Q, or its Q-spring is removed (last_node "released")."""
        j, c, d = self.b, self.p["stiffness"], self.p["damping"]
        self.data.ctrl[j] = 0.0
        self.work["rate"] = 0.0
        keep = self.p["last_node"] == "attached"
        self.model.actuator_gainprm[j, 0] = c if keep else 0.0
        self.model.actuator_biasprm[j, :3] = (0.0, -c, -d) if keep else (0.0, 0.0, 0.0)

    def step_to(self, t: float, te: float) -> None:
        """Steps of dt from t, the last one shortened to land on te; spool work summed at every
        step. Raises FloatingPointError on a blow-up."""
        model, data, dt, af = self.model, self.data, self.dt, self.data.actuator_force
        K = int(np.floor((te - t) / dt * (1 + 1e-12)))
        rem = te - t - K * dt
        for _ in range(K):
            mujoco.mj_step(model, data)
            self.work["W"] += af[self.b] * self.work["rate"] * dt
        self.steps += K
        if rem > 1e-9 * dt:
            model.opt.timestep = rem
            mujoco.mj_step(model, data)
            self.work["W"] += af[self.b] * self.work["rate"] * rem
            model.opt.timestep = dt
            self.steps += 1
        bad = data.warning[mujoco.mjtWarning.mjWARN_BADQACC].number > 0
        if bad or not np.all(np.isfinite(data.qpos)) or not np.all(np.isfinite(data.qvel)):
            raise FloatingPointError("MuJoCo bad QACC / non-finite state (unstable step?)")
        X, _ = self.node_state()
        seg = np.sqrt((np.diff(X[:self.b + 1], axis=0) ** 2).sum(1))
        limit = self.s["stretch_limit"]
        if seg.size and np.max(np.abs(seg - self.l0)) > limit * self.l0:
            est = stable_dt_explicit(self.p, _FACTOR[self.s["integrator"]], 1.0)
            raise FloatingPointError(f"unstable step: spring stretch beyond {limit}*l0 "
                                     f"(dt={dt:.3g}, estimated limit {est:.3g})")

    def observe(self, io: int) -> None:
        o = self.out
        X, V = self.node_state()
        o["psi"][io], o["omega"][io] = self.data.qpos[self.hub_q], self.data.qvel[self.hub_v]
        o["X"][io], o["V"][io], o["b"][io] = X, V, self.b
        o["W"][io] = 2.0 * self.work["W"]                   # two blades


@check_once
def check_settings(settings: dict | None, t_out: np.ndarray | None = None) -> dict:
    """The settings merged and checked before anything runs (ValueError with one line)."""
    s = merge_settings(settings, DEFAULT_SETTINGS, INTEGRATORS)
    if s["stored"] not in STORED:
        raise ValueError(f"stored must be one of {STORED}, got {s['stored']!r}")
    require_positive(s, ("dt",), auto_ok=True)
    return s


def simulate(params: dict, t_out: np.ndarray, settings: dict | None = None) -> LeafResult:
    s, t_out = check_settings(settings), check_grid(t_out)
    dt = s["dt"]
    if dt is None or dt == "auto":
        dt = stable_dt_explicit(params, _FACTOR[s["integrator"]])
    dt = float(dt)
    run = _Sail(params, s, dt, len(t_out))
    t = 0.0
    status, reason, t_fail = "ok", None, None
    wall0 = _time.perf_counter()
    for te, io, jr, end in zip(*phys.breakpoints(params, t_out), strict=True):
        if te > t:
            try:
                run.step_to(t, te)
            except FloatingPointError as exc:
                status, reason, t_fail = "diverged", str(exc), te
                break
            t = te
        if jr > 0:
            run.release(jr)
        elif end:
            run.end_payout()
        if io >= 0:
            run.observe(io)
    wall = _time.perf_counter() - wall0
    o = run.out
    ch, extra = phys.channels(params, t_out, o["psi"], o["omega"], o["X"], o["V"], o["b"],
                              spool_work=o["W"])
    if t_fail is not None:
        for k in ch:
            ch[k][t_out > t_fail] = np.nan
    extra["hub_rate_formula18"] = phys.formula18(params, t_out)
    extra["boundary_node"] = o["b"].astype(float)
    evals = run.steps * (4 if s["integrator"] == "rk4" else 1)
    return LeafResult(channels=ch, status=status, t_fail=t_fail, reason=reason,
            stats={"steps": run.steps, "rhs_evals": evals, "integrate_s": wall},
            settings={**s, "dt": dt}, extra=extra)
