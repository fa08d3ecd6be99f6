"""The engine model: the ball-joint rotor compiled from the resolved parameters once
(`compile_model`: every field but torque and k) and the data of one point (`build`, `load`);
every path — time, batch, modes, response — goes through them.

A disk on a massless shaft stands on a ball joint at the origin; gravity is MuJoCo's, the drive
torque a constant world-frame wrench in `xfrc_applied`, the spring the callback's. The drive
work A = ∫ torque·ω_z dt is an extra state integrated by MuJoCo's own integrator: an actuator
with integrator dynamics and zero gain/gear (it exerts no force) whose `ctrl` the callback sets
to torque·ω_z in every stage, so A is RK4-consistent (act_dot = ctrl). The constraint and
contact stages are disabled (the model has neither): they cost time and change no bit
(tests/engines/test_mujoco_rotor.py).
"""
import math

import mujoco
import numpy as np

from .kernel import (
    CARDAN_MARGIN,
    NUSERDATA,
    PI_MARGIN,
    U_CEXT,
    U_CINT,
    U_COS_CARDAN,
    U_COS_PI,
    U_FLAG,
    U_K,
    U_OMEGA2,
    U_POISON,
    U_TFAIL,
    U_TORQUE,
    U_VARIANT,
)
from .settings import INTEGRATOR_ENUM

MODEL_FIELDS = ("l", "m", "R", "eccentricity", "gravity")   # compiled into the model
_NO_STAGES = int(mujoco.mjtDisableBit.mjDSBL_AUTORESET) | \
    int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT) | int(mujoco.mjtDisableBit.mjDSBL_CONTACT)


def compile_model(params, settings, integrator):
    """The ball-joint rotor as an MjModel: everything but torque and k (set in the data)."""
    l, mass, rad = (float(params[n]) for n in ("l", "m", "R"))
    ecc = float(params["eccentricity"])
    g = np.asarray(params["gravity"], dtype=float).reshape(3)
    spec = mujoco.MjSpec()
    spec.modelname = "rotor"
    spec.nuserdata = NUSERDATA
    spec.option.timestep = settings["dt"]
    spec.option.integrator = INTEGRATOR_ENUM[integrator]
    spec.option.gravity = g.tolist()
    body = spec.worldbody.add_body(name="rotor")
    body.add_joint(type=mujoco.mjtJoint.mjJNT_BALL, name="pivot")
    body.mass = mass
    body.ipos = [0.0, ecc, l]
    body.inertia = [mass * rad**2 / 4, mass * rad**2 / 4, mass * rad**2 / 2]
    body.explicitinertial = True
    # work integrator: act_dot = ctrl = torque·ω_z (set by the callback); no force (gain, gear 0)
    act = spec.add_actuator(trntype=mujoco.mjtTrn.mjTRN_JOINT, target="pivot", name="work")
    act.dyntype = mujoco.mjtDyn.mjDYN_INTEGRATOR
    act.gainprm = np.zeros_like(np.asarray(act.gainprm)).tolist()
    act.biasprm = np.zeros_like(np.asarray(act.biasprm)).tolist()
    act.gear = [0.0] * 6
    act.ctrllimited = mujoco.mjtLimited.mjLIMITED_FALSE
    act.actlimited = mujoco.mjtLimited.mjLIMITED_FALSE
    m = spec.compile()
    m.opt.disableflags |= _NO_STAGES      # no contacts, no constraints: stages that do nothing
    return m


def build(params, settings, integrator, torque, model=None):
    """(model, data, body id) with the point's torque and k in the data; `model`: one compiled
    from the same MODEL_FIELDS, settings and integrator (else compiled here)."""
    m = compile_model(params, settings, integrator) if model is None else model
    d = mujoco.MjData(m)
    bid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "rotor")
    load(d, bid, params, settings, torque)
    return m, d, bid


def load(d, bid, params, settings, torque):
    """The point's numbers into the data: the drive wrench, the callback's userdata, and the
    initial state R0 = Rx(tilt0), spin0 about the body axis, no work."""
    d.xfrc_applied[bid, 3:6] = (0.0, 0.0, float(torque))
    ud = d.userdata
    ud[U_K] = float(params["k"])
    ud[U_TORQUE] = float(torque)
    ud[U_COS_PI] = math.cos(math.pi - PI_MARGIN)
    ud[U_OMEGA2] = float(settings["omega_max"]) ** 2
    ud[U_FLAG] = ud[U_TFAIL] = ud[U_POISON] = 0.0
    ud[U_VARIANT] = 0.0 if settings["spring"] == "cone" else 1.0
    ud[U_COS_CARDAN] = CARDAN_MARGIN
    ud[U_CEXT] = float(params.get("c_ext", 0.0))
    ud[U_CINT] = float(params.get("c_int", 0.0))
    tilt0, spin0 = float(params.get("tilt0", 0.0)), float(params.get("spin0", 0.0))
    d.time = 0.0
    d.qpos[:] = (math.cos(tilt0 / 2), math.sin(tilt0 / 2), 0.0, 0.0)
    d.qvel[:] = (0.0, 0.0, spin0)
    d.act[0] = 0.0
