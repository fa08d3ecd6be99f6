"""MuJoCo model of Bricard's mechanism (scene `bricard`).

Model: one kinematic tree of five hinges, world → rod 1 (hinge s0 at P0) → rod 2 (s1 at P1) →
… → rod 5 (s4 at P4), each body's frame at its joint with the space axes at the start, so the
hinge angles are the joint angles q0…q4 of compare.physics.bricard themselves; uniform square
prisms of side a (an explicit `inertial`: m (L² + a²)/12 about the two transverse axes, m a²/6
about their own, compare.physics.bricard.principal_inertia; at least AXIAL·m L² about their own,
which MuJoCo needs positive: thin rods, a = 0, get that).
The loop's last joint, rod 5 to the ground about x at P5, is two `connect`s on its axis (at
P5 and P5 + L/2 x̂): six equations where a hinge is five, and five where the mechanism needs
four (Grübler's zero against the one degree of freedom) — MuJoCo's soft constraints take the
redundant rows as they are (its solver regularises them), solref (solref_factor·dt, 1) and
solimp (0.9999, 0.9999, 0.001, 0.5, 2). Gravity −g ŷ. RK4.
"""
from __future__ import annotations

import mujoco
import numpy as np

from compare.contract import LeafResult, check_once
from compare.physics import bricard as phys

from .. import loop_common as lc

DEFAULT_SETTINGS = {"integrator": "rk4", "dt": 1e-4, "solref_factor": 4.0,
                    "solimp": (0.9999, 0.9999, 0.001, 0.5, 2.0)}
INTEGRATORS = ("rk4", "euler", "implicitfast", "implicit")
# the soft loop moves the motion off the rigid mechanism by an amount ∝ tc² (tc = the
# constraint's time constant, solref_factor·dt; measured in tests/engines/test_bricard_engines.py);
# the knob varies the ratio on its own (order 2)
KNOBS = {"solref_factor": 2}
# MuJoCo refuses a moving body with a zero principal inertia (mjMINVAL): each rod gets at least
# AXIAL·m L² about its own axis, 1.2e-9 of a thin rod's transverse inertia — thin rods (a = 0)
# only, the library's a = 0.1 m gives 1.7e6× more (its effect: well below the soft loop's,
# measured in tests/engines/test_bricard_engines.py)
AXIAL = 1e-10


@check_once
def check_settings(settings: dict | None, t_out: np.ndarray | None = None) -> dict:
    """The settings merged and checked before anything runs (ValueError with one line)."""
    return lc.mujoco_settings(settings, DEFAULT_SETTINGS, INTEGRATORS)


_f = lc.fmt


def _v(x):
    return " ".join(_f(c) for c in x)


def xml(params: dict, s: dict) -> str:
    m, L, g = (float(params[n]) for n in ("m", "L", "g"))
    i_t, i_a = phys.principal_inertia(phys.pack(params))
    i_a = max(i_a, AXIAL * m * L * L)
    solref, solimp = lc.soft_strings(s)
    integ = lc.MJ_INTEGRATORS[s["integrator"]]
    P = phys.POINTS * L
    tree = ""
    for k in reversed(range(5)):
        d = phys.POINTS[k + 1] - phys.POINTS[k]
        diag = [i_a if abs(c) > 0.5 else i_t for c in d]
        pos = P[k] - (P[k - 1] if k else 0.0)
        tree = (f'<body name="rod{k + 1}" pos="{_v(pos)}">'
                f'<joint name="q{k}" type="hinge" axis="{_v(phys.AXES[k])}"/>'
                f'<inertial pos="{_v(0.5 * d * L)}" mass="{_f(m)}" diaginertia="{_v(diag)}"/>'
                f'{tree}</body>')
    a1 = P[5] - P[4]
    a2 = a1 + 0.5 * L * phys.AXES[5]
    connects = "".join(f'<connect body1="rod5" body2="world" anchor="{_v(a)}" '
                       f'solref="{solref}" solimp="{solimp}"/>' for a in (a1, a2))
    return f"""
<mujoco model="bricard">
  <option timestep="{_f(s['dt'])}" integrator="{integ}" gravity="0 {_f(-g)} 0"
          jacobian="dense">
    <flag contact="disable" autoreset="disable"/>
  </option>
  <worldbody>{tree}</worldbody>
  <equality>{connects}</equality>
</mujoco>
"""


def simulate(params: dict, t_out: np.ndarray, settings: dict | None = None) -> LeafResult:
    s = check_settings(settings)
    t_out = np.asarray(t_out, float)
    m, d = lc.mujoco_model(xml(params, s))
    n = len(t_out)
    Q, QD = np.full((n, 6), np.nan), np.full((n, 6), np.nan)
    Q[0, :5], QD[0, :5] = d.qpos, d.qvel
    L = float(params["L"])
    end = phys.POINTS[5] * L
    viol = [0.0]

    def record(i):
        Q[i, :5], QD[i, :5] = d.qpos, d.qvel
        mujoco.mj_kinematics(m, d)
        b = d.body("rod5")
        tip = b.xpos + b.xmat.reshape(3, 3) @ (phys.POINTS[5] - phys.POINTS[4]) * L
        viol[0] = max(viol[0], float(np.linalg.norm(tip - end)))
    steps, status, t_fail, reason, evals, h = lc.mujoco_run(m, d, t_out, s, record)
    Q[:, 5] = 0.0
    QD[:, 5] = 0.0
    return LeafResult(channels=phys.channels(Q, QD, phys.pack(params)), status=status,
                      t_fail=t_fail, reason=reason, stats={"steps": steps, "rhs_evals": evals},
                      settings={**s, "dt": h},
                      extra={"loop_violation": np.array(viol)})
