"""MuJoCo leaf: two hinges about −y in the x–z plane (angle θ from the downward vertical),
point masses as inertials with a negligible inertia (1e-12 kg·m² against m l² = 1), contacts
off, MuJoCo's RK4 at a fixed step; `mj_step(nstep=…)` between output samples."""
import time

import mujoco
import numpy as np

from compare.contract import LeafResult, merge_settings

from .scene import channels

INTEGRATORS = ("rk4",)
DEFAULT_SETTINGS = {"integrator": "rk4", "dt": 1e-4}


def _xml(p, dt):
    return f"""<mujoco>
  <option timestep="{dt!r}" integrator="RK4" gravity="0 0 {-p['g']!r}">
    <flag contact="disable"/>
  </option>
  <worldbody>
    <body name="upper">
      <joint name="j1" type="hinge" axis="0 -1 0"/>
      <inertial pos="0 0 {-p['l1']!r}" mass="{p['m1']!r}" diaginertia="1e-12 1e-12 1e-12"/>
      <body name="lower" pos="0 0 {-p['l1']!r}">
        <joint name="j2" type="hinge" axis="0 -1 0"/>
        <inertial pos="0 0 {-p['l2']!r}" mass="{p['m2']!r}" diaginertia="1e-12 1e-12 1e-12"/>
      </body>
    </body>
  </worldbody>
</mujoco>"""


def check_settings(settings, t_out=None):
    s = merge_settings(settings, DEFAULT_SETTINGS, INTEGRATORS)
    if not (isinstance(s["dt"], (int, float)) and s["dt"] > 0):
        raise ValueError(f"dt must be a positive number, got {s['dt']!r}")
    if t_out is not None and len(t_out) > 1:
        n = (t_out[1] - t_out[0]) / s["dt"]
        if abs(n - round(n)) > 1e-6 or round(n) < 1:
            raise ValueError(f"dt {s['dt']:g} must divide the output step {t_out[1] - t_out[0]:g}")
    return s


def simulate(params, t_out, settings=None):
    s = check_settings(settings, t_out)
    m = mujoco.MjModel.from_xml_string(_xml(params, float(s["dt"])))
    d = mujoco.MjData(m)
    d.qpos[:] = [params["theta1_0"], params["theta2_0"] - params["theta1_0"]]
    Y = np.full((len(t_out), 4), np.nan)
    Y[0] = [*d.qpos, *d.qvel]
    n = int(round((t_out[1] - t_out[0]) / s["dt"])) if len(t_out) > 1 else 0
    status, t_fail, reason = "ok", None, None
    t0 = time.perf_counter()
    for i in range(1, len(t_out)):
        mujoco.mj_step(m, d, nstep=n)
        Y[i] = [*d.qpos, *d.qvel]
        if not np.all(np.isfinite(Y[i])):
            Y[i:] = np.nan
            status, t_fail, reason = "diverged", float(t_out[i]), "non-finite state"
            break
    wall = time.perf_counter() - t0
    th1, th2 = Y[:, 0], Y[:, 0] + Y[:, 1]                 # relative hinge → absolute angle
    w1, w2 = Y[:, 2], Y[:, 2] + Y[:, 3]
    return LeafResult(channels=channels(params, th1, th2, w1, w2),
                      stats={"steps": n * (len(t_out) - 1), "rhs_evals": -1,
                             "integrate_s": wall},
                      settings=s, status=status, t_fail=t_fail, reason=reason)
