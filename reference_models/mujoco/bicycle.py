"""MuJoCo model of the benchmark bicycle (`bicycle`): the rear frame on a free joint, hinges at
the hubs and along the steer axis, the paper's inertias in MuJoCo's z-up axes, and each wheel a
thin ellipsoid (semi-axes r, 1e-4 m, r: a knife edge whose contact point stays on the
mid-plane — a thin cylinder touches with both rim edges and adds a spurious lean stiffness,
its roots measured off by 1.7–11 /s) touching the ground plane through MuJoCo's contacts.

Those contacts are soft: each is a spring-damper constraint with time constant `timeconst`
(solref, damping ratio 1) and a friction cone (μ = `friction`, elliptic, `impratio`), so the
wheels sink and creep where the paper's roll without slip. The roots move off the paper's
with the time constant, linearly: weave at 5 m/s off by 0.0204, 0.0105, 0.0056, 0.0030 /s at
2e-3, 1e-3, 5e-4, 2.5e-4 s (MuJoCo's default 0.02 s would put it near 0.2 /s, 4 %); noslip
iterations (20–50) and impratio 100 change it by < 5 %. The default 5e-4 s is the stiffest
the step 1e-4 s resolves (MuJoCo holds the time constant ≥ 2 steps); the scene's allowance
for MuJoCo is set from that deviation, measured.

The roots are fitted as Exudyn's (reference_models/bicycle_common.py): rolling upright at the
speed, 0.5 s to let the contacts settle, the roll torque pulse, lean and steer every
`output_dt`, a matrix pencil of four poles; the bars the change at twice the step and on half
the record (they do not contain the contact's deviation, which the allowance carries).
"""
from __future__ import annotations

import time

import mujoco
import numpy as np

from compare.contract import LeafModes, merge_settings, require_positive

from .. import bicycle_common as common

MODES_SETTINGS = {"dt": 1e-4, "timeconst": 5e-4, "friction": 2.0, "impratio": 10.0,
                  "record_s": 3.0, "output_dt": 0.01, "settle_s": 0.5}
WHEEL_WIDTH = 1e-4              # m: the ellipsoid's semi-axis along the axle


def _numbers(a) -> str:
    return " ".join(repr(float(x)) for x in np.ravel(a))


def _full(I) -> str:
    return _numbers([I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]])


def model_xml(p: dict, s: dict) -> str:
    axis, on_axis = common.steer_axis(p)
    rR, rF, w = p["r_R"], p["r_F"], p["w"]
    at_b = np.array([p["x_B"], 0.0, -p["z_B"]])
    inertia = common.tensor

    def wheel(r):
        return (f'<geom type="ellipsoid" size="{_numbers([r, WHEEL_WIDTH, r])}" mass="0" '
                f'contype="1" conaffinity="0"/>')
    return f"""<mujoco>
<option timestep="{s['dt']!r}" integrator="RK4" gravity="0 0 {-p['g']!r}" cone="elliptic"
        impratio="{s['impratio']!r}"/>
<default><geom solref="{s['timeconst']!r} 1" friction="{s['friction']!r} 0 0" condim="3"/>
</default>
<worldbody><geom type="plane" size="0 0 1" contype="0" conaffinity="1"/>
<body name="frame" pos="{_numbers(at_b)}"><freejoint/>
 <inertial pos="0 0 0" mass="{p['m_B']!r}"
           fullinertia="{_full(inertia(p['I_Bxx'], p['I_Byy'], p['I_Bzz'], p['I_Bxz']))}"/>
 <body name="rear" pos="{_numbers(np.array([0.0, 0.0, rR]) - at_b)}">
  <joint name="rear" type="hinge" axis="0 1 0"/>
  <inertial pos="0 0 0" mass="{p['m_R']!r}"
            fullinertia="{_full(inertia(p['I_Rxx'], p['I_Ryy'], p['I_Rxx'], 0.0))}"/>
  {wheel(rR)}</body>
 <body name="fork" pos="{_numbers(on_axis - at_b)}">
  <joint name="steer" type="hinge" axis="{_numbers(axis)}"/>
  <inertial pos="{_numbers(np.array([p['x_H'], 0.0, -p['z_H']]) - on_axis)}" mass="{p['m_H']!r}"
            fullinertia="{_full(inertia(p['I_Hxx'], p['I_Hyy'], p['I_Hzz'], p['I_Hxz']))}"/>
  <body name="front" pos="{_numbers(np.array([w, 0.0, rF]) - on_axis)}">
   <joint name="front" type="hinge" axis="0 1 0"/>
   <inertial pos="0 0 0" mass="{p['m_F']!r}"
             fullinertia="{_full(inertia(p['I_Fxx'], p['I_Fyy'], p['I_Fxx'], 0.0))}"/>
   {wheel(rF)}</body>
 </body>
</body></worldbody></mujoco>"""


def free_response(p: dict, v: float, dt: float, s: dict):
    """(t, lean, steer, wall_s) after the pulse: the rear frame's roll and the steer hinge
    (rad), every output_dt from the pulse's end."""
    m = mujoco.MjModel.from_xml_string(model_xml(p, {**s, "dt": dt}))
    d = mujoco.MjData(m)
    d.qvel[0] = v                                   # qvel: free joint (6), rear, steer, front
    d.qvel[6], d.qvel[8] = v / p["r_R"], v / p["r_F"]
    frame = m.body("frame").id
    torque, t_pulse = common.PULSE
    t0 = time.perf_counter()
    mujoco.mj_step(m, d, nstep=int(round(s["settle_s"] / dt)))
    d.xfrc_applied[frame, 3] = torque
    mujoco.mj_step(m, d, nstep=int(round(t_pulse / dt)))
    d.xfrc_applied[frame, 3] = 0.0
    every = int(round(s["output_dt"] / dt))
    out = []
    for _ in range(int(round(s["record_s"] / s["output_dt"])) + 1):
        lean = float(np.arcsin(d.xmat[frame][7]))   # R = Rz Rx Ry: R[2, 1] = sin φ
        if abs(lean) >= common.LEAN_CUT:
            break
        out.append((d.time, lean, d.qpos[8]))
        mujoco.mj_step(m, d, nstep=every)
    if d.warning[mujoco.mjtWarning.mjWARN_BADQACC].number > 0:
        raise RuntimeError("MuJoCo diverged (bad qacc) and reset the state")
    t, lean, steer = np.array(out).T
    return t, lean, steer, time.perf_counter() - t0


def modes(params: dict, settings: dict) -> LeafModes:
    s = merge_settings(settings, MODES_SETTINGS, ())
    require_positive(s, tuple(MODES_SETTINGS))
    if s["timeconst"] < 4 * s["dt"]:
        raise ValueError(f"timeconst {s['timeconst']:g} s must be ≥ 4 steps ({4 * s['dt']:g} s):"
                         " the run at twice the step must resolve it too")
    return common.fitted_modes(
        lambda p, v, dt: free_response(p, v, dt, s), params, s,
        f"soft contacts (time constant {s['timeconst']:g} s): the wheels sink and creep; "
        "roots fitted from a free response")
