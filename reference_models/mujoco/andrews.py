"""MuJoCo model of Andrews' squeezer (scene `andrews-squeezer`).

Model: three kinematic trees of hinges about z, each body's frame at its joint — world → K1
(hinge β at O) → K2 (hinge Θ at P); world → K3 (hinge γ at B); world → K5 (hinge δ at A) → K4
(hinge Φ at G); world → K7 (hinge ε at A) → K6 (hinge Ω at H) — so the hinge angles are the
test set's relative angles themselves. The bodies' masses, inertias and points come from the
shared layout (compare.physics.andrews.body_layout). The two loops are closed by three site
`connect`s at E (K2 with K3, K4 and K6; their z rows are redundant), soft constraints with
solref (solref_factor·dt, 1) and solimp (0.9999, 0.9999, 0.001, 0.5, 2); the spring is a
spatial tendon D (on K3) – C with stiffness c0 and spring length l0; the motor torque `mom` a
constant `qfrc_applied` on β. RK4.
"""
from __future__ import annotations

import mujoco
import numpy as np

from compare.contract import LeafResult, check_once
from compare.physics import andrews as phys

from .. import loop_common as lc

DEFAULT_SETTINGS = {"integrator": "rk4", "dt": 1e-6, "solref_factor": 4.0,
                    "solimp": (0.9999, 0.9999, 0.001, 0.5, 2.0)}
INTEGRATORS = ("rk4", "euler", "implicitfast", "implicit")
# The soft loops move the angles off the rigid model by ≈ 2e3–4e3 rad/s² · tc² at t = 0.03 s
# (measured at dt 2e-6: tc 8e-6 → 1.2e-7 rad, 3.2e-5 → 2.2e-6, 1.28e-4 → 5.8e-5, 5.12e-4 →
# 9.8e-4; at tc 8e-6 dt 1e-6 and 2e-6 give the same 1.1e-7 / 1.2e-7: the time constant, not the
# step, sets it). tc = solref_factor·dt follows the step, so halving dt halves tc too; the
# knob varies the ratio on its own, its error ∝ tc² (order 2, toward refsafe's floor 2·dt)
KNOBS = {"solref_factor": 2}
# the tree: (body, parent or None, joint point); qpos order = this order
TREE = (("K1", None, "O"), ("K2", "K1", "P"), ("K3", None, "B"), ("K5", None, "A"),
        ("K4", "K5", "G"), ("K7", None, "A"), ("K6", "K7", "H"))
# qpos index of each test-set angle (β, Θ, γ, Φ, δ, Ω, ε)
QPOS_OF = (0, 1, 2, 4, 3, 6, 5)


@check_once
def check_settings(settings: dict | None, t_out: np.ndarray | None = None) -> dict:
    """The settings merged and checked before anything runs (ValueError with one line)."""
    return lc.mujoco_settings(settings, DEFAULT_SETTINGS, INTEGRATORS)


_f = lc.fmt


def xml(params: dict, s: dict) -> str:
    lay = phys.body_layout(params)
    solref, solimp = lc.soft_strings(s)
    integ = lc.MJ_INTEGRATORS[s["integrator"]]

    def body(name, joint, pos, children):
        m, J, pts = lay[name]
        j = pts[joint]
        com = -j
        sites = "".join(f'<site name="{name}_{pt}" pos="{_f(x[0] - j[0])} {_f(x[1] - j[1])} 0"/>'
                        for pt, x in pts.items() if pt != joint)
        return (f'<body name="{name}" pos="{_f(pos[0])} {_f(pos[1])} 0">'
                f'<joint name="{name}" type="hinge" axis="0 0 1"/>'
                f'<inertial pos="{_f(com[0])} {_f(com[1])} 0" mass="{_f(m)}" '
                f'diaginertia="{_f(J)} {_f(J)} {_f(J)}"/>{sites}{children}</body>')

    def chain(name, parent_joint=None):
        kids = "".join(chain(c, p) for c, par, p in TREE if par == name)
        _, par, joint = next(t for t in TREE if t[0] == name)
        if par is None:
            pos = phys.fixed_point(joint, params)
        else:
            pts = lay[par][2]
            pos = pts[joint] - pts[next(t for t in TREE if t[0] == par)[2]]
        return body(name, joint, pos, kids)

    trees = "".join(chain(b) for b, par, _ in TREE if par is None)
    c = phys.fixed_point("C", params)
    connects = "".join(f'<connect site1="K2_E" site2="{k}_E" solref="{solref}" '
                       f'solimp="{solimp}"/>' for k in ("K3", "K4", "K6"))
    return f"""
<mujoco model="andrews-squeezer">
  <option timestep="{_f(s['dt'])}" integrator="{integ}" gravity="0 0 0" jacobian="dense">
    <flag contact="disable" autoreset="disable"/>
  </option>
  <worldbody>
    <site name="C" pos="{_f(c[0])} {_f(c[1])} 0"/>
    {trees}
  </worldbody>
  <equality>{connects}</equality>
  <tendon>
    <spatial name="spring" stiffness="{_f(params['c0'])}" springlength="{_f(params['l0'])}"
             damping="0">
      <site site="K3_D"/><site site="C"/>
    </spatial>
  </tendon>
</mujoco>
"""


def simulate(params: dict, t_out: np.ndarray, settings: dict | None = None) -> LeafResult:
    s = check_settings(settings)
    t_out = np.asarray(t_out, float)
    m, d = lc.mujoco_model(xml(params, s))
    q0 = phys.initial_angles(params)
    d.qpos[list(QPOS_OF)] = q0
    d.qvel[:] = 0.0
    d.qfrc_applied[0] = float(params["mom"])
    n = len(t_out)
    Q, QD = np.full((n, 7), np.nan), np.full((n, 7), np.nan)
    Q[0], QD[0] = q0, 0.0
    viol = [0.0]

    def record(i):
        Q[i], QD[i] = d.qpos[list(QPOS_OF)], d.qvel[list(QPOS_OF)]
        mujoco.mj_kinematics(m, d)
        e = d.site("K2_E").xpos
        viol[0] = max(viol[0], *(float(np.linalg.norm(e - d.site(f"{k}_E").xpos))
                                 for k in ("K3", "K4", "K6")))
    steps, status, t_fail, reason, evals, h = lc.mujoco_run(m, d, t_out, s, record)
    return LeafResult(channels=phys.channels(Q, QD, phys.pack(params)), status=status,
                      t_fail=t_fail, reason=reason, stats={"steps": steps, "rhs_evals": evals},
                      settings={**s, "dt": h},
                      extra={"loop_violation": np.array(viol)})
