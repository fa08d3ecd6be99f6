"""MuJoCo reference model of the spin-up rotor (scenes ``rotor-spinup`` and ``rotor-whirl``).

A disk on a massless shaft stands on a ball joint at the origin. The transverse spring is the
isotropic cone-angle spring of the scene: with n = R e_z the body axis and θ = ∠(n, e_z), it
applies the spatial moment −kγ, γ = θ (e_z × n)/|e_z × n|, so U = ½kθ² and nothing resists the
spin. MuJoCo has no such element (its ball-joint stiffness also resists spin), so the moment is
added to ``qfrc_passive`` by a passive-force callback. The callback runs inside every RK4 stage,
which keeps RK4 4th order (a per-step ``qfrc_applied`` would freeze the force over the stages).

The callback is, by default, a numba ``cfunc`` installed as a raw C function pointer: it reads
``qpos``/``qvel`` and writes ``qfrc_passive``/``ctrl`` through the ``mjData`` pointer it is given,
so MuJoCo never re-enters Python (about 10x faster than a Python callable). The offsets of those
``mjData`` fields are found at run time by matching the pointers of a live ``MjData`` object;
if that or numba fails, the pure-Python callable (``settings["callback"] = "python"``) is used.

The drive work A = ∫ torque·ω_z dt is an extra state integrated by MuJoCo's own integrator: an
actuator with integrator dynamics and zero gain/gear (it exerts no force) whose ``ctrl`` the
callback sets to torque·ω_z in every stage, so A is RK4-consistent (act_dot = ctrl).

The drive torque is a constant world-frame wrench in ``xfrc_applied``; gravity is MuJoCo's.

Stepping path. With the native callback and an output grid uniform to round-off (the normal
case), the whole run is one ``mujoco.rollout.rollout`` call per block of up to 2^17 steps at
one step h = span / (intervals · N): the steps run in C, the states come back for every step
and the output rows are picked from them; the torque goes in as the rollout's constant
``xfrc_applied`` control (rollout does not keep ``xfrc_applied`` of the data it is given).
Otherwise (Python callback, uneven grid) ``mj_step(m, d, n)`` runs the n steps of each output
interval in one call. Two switches cut the C step itself without changing a bit of the result
(tests/test_mujoco_rotor.py): the constraint and contact stages are disabled (the model has
neither), and a clock that returns 0 is installed as ``mjcb_time`` while the model runs —
MuJoCo 4.0 otherwise reads the system clock around every pipeline stage for ``mjData.timer``,
which nothing here reads.
Measured per RK4 step (the 10 s spin-up, 2 busy cores, CPU time): 7.8 µs → 5.0 (clock) →
4.2 µs (stages); the 10 s run 125–165 ms through the per-interval loop → 73–77 ms.

`regimes` (the map's batch path) runs many points through the same `_run` as `simulate`, each
point one rollout, the model compiled once per distinct set of model fields (l, m, R,
eccentricity, gravity: torque and k are data, not model) and reduced to its regime by
`physics.regime_summaries`, the rule the compiled custom batch applies.

Optional model variant ``settings["spring"] = "cardan"``: the Cardan spring k/2(α²+β²) of
R = Rx(α)Ry(β)Rz(φ) (a different spring at large tilt; the compare layer reports the deviation).
"""

from __future__ import annotations

import ctypes
import math
import time as _time

import mujoco
import mujoco.rollout
import numpy as np

from compare.contract import LeafModes, LeafResult, merge_settings
from compare.physics import eigen
from compare.physics import rotor as physics

DEFAULT_SETTINGS = {
    "integrator": "rk4",
    "dt": 1e-3,
    "spring": "cone",       # "cone" (the scene's −kγ) | "cardan" (named model variant)
    "callback": "native",   # "native" (numba cfunc, no GIL) | "python" (Python callable)
    "omega_max": 1e5,       # |ω| bound [rad/s]: beyond it the run is reported diverged
}
INTEGRATORS = ("rk4", "euler", "implicitfast", "implicit")
# a map point's first look (compare/leafinfo.py `cheaper`): 10× the accurate step, the output
# step. RK4 is stable to |λ dt| ≤ 2.78; on the rotor map the tilt root is ~41 rad/s and the
# spin at most 56 rad/s (torque 5, e 0.02, 10 s): |λ dt| ≤ 0.6. Measured (`xval bench
# rotor-spinup --points 400 --solver mujoco`): 0 of 400 labels differ from the all-accurate
# grid, 16 % rerun accurate; 5e-2 gives wrong cheap labels (tests/test_map_trace.py fails)
CHEAP_DT = {"rk4": 1e-2}
SPRINGS = ("cone", "cardan")
CALLBACKS = ("native", "python")

_INTEGRATOR_ENUM = {
    "rk4": mujoco.mjtIntegrator.mjINT_RK4,
    "euler": mujoco.mjtIntegrator.mjINT_EULER,
    "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST,
    "implicit": mujoco.mjtIntegrator.mjINT_IMPLICIT,
}
_RHS_PER_STEP = {"rk4": 4, "euler": 1, "implicitfast": 1, "implicit": 1}

# --- userdata layout (doubles in mjData.userdata, read/written by the callback) -------------
(_U_K, _U_TORQUE, _U_COS_PI, _U_OMEGA2, _U_FLAG, _U_TFAIL, _U_VARIANT, _U_COS_CARDAN, _U_CEXT,
 _U_CINT, _U_POISON) = range(11)
_NUSERDATA = 11
# _U_POISON ≠ 0 (the batch path, whose per-step userdata control clears the flag): a flagged
# stage also makes its passive force NaN, so the state (auto-reset is off) and every later row
# are NaN (a NaN work rate would not do: MuJoCo zeroes a bad ctrl)
_PI_MARGIN = 1e-3            # stop when θ > π − this (the direction of −kγ is undefined at π)
_CARDAN_MARGIN = 1e-3        # Cardan variant: stop when |cos β| < this (β → ±90°)
_FLAG_REASONS = {
    1.0: "singular spring direction at tilt pi",
    2.0: "non-finite state",
    3.0: "angular velocity bound omega_max exceeded",
    4.0: "Cardan spring singular at beta = +-90 deg",
}


# ----------------------------------------------------------------------------------------------
# The spring kernel (plain scalar Python; compiled by numba for the native callback)
# ----------------------------------------------------------------------------------------------
def _damper_kernel(w, x, y, z, vx, vy, vz, omz, c_ext, c_int):
    """Body-frame damper moment. In body axes (ω_body = v, the shaft axis n = e_z, the fixed z
    axis b = Rᵀe_z): the external damper −c_ext (ω − (ω·n) n) opposes the axis' motion in the
    fixed frame; the internal one, −c_int (ω − ω_z b), is a damper between the rotor and a hub
    spinning with it about the fixed z axis (to first order the tilt rate seen in the rotor's
    frame)."""
    s2 = 2.0 / (w * w + x * x + y * y + z * z)
    bx, by, bz = s2 * (x * z - w * y), s2 * (y * z + w * x), 1.0 - s2 * (x * x + y * y)
    return (-c_ext * vx - c_int * (vx - omz * bx), -c_ext * vy - c_int * (vy - omz * by),
            -c_int * (vz - omz * bz))


def _spring_kernel(w, x, y, z, vx, vy, vz, k, variant, cos_pi, omega2, cos_cardan):
    """Body-frame spring moment (tbx, tby, tbz), spatial ω_z and a status flag (0 = fine)."""
    nq = w * w + x * x + y * y + z * z
    qv = vx * vx + vy * vy + vz * vz
    if not (nq > 0.0 and nq < 1e300 and qv <= omega2):
        if nq == nq and qv == qv and nq < 1e300 and qv < 1e300:
            return 0.0, 0.0, 0.0, 0.0, 3.0
        return 0.0, 0.0, 0.0, 0.0, 2.0
    s2 = 2.0 / nq
    # b = R^T e_z (third row of R): spatial ω_z = b·ω_body, cos θ = b_z
    bx = s2 * (x * z - w * y)
    by = s2 * (y * z + w * x)
    bz = 1.0 - s2 * (x * x + y * y)
    omz = bx * vx + by * vy + bz * vz
    if variant == 0.0:
        # cone spring: body moment R^T(−kγ) = −k θ/sinθ (b × e_z) = −k θ/sinθ (b_y, −b_x, 0)
        if bz < cos_pi:
            return 0.0, 0.0, 0.0, omz, 1.0
        sn = math.sqrt(bx * bx + by * by)
        if sn < 1e-4 and bz > 0.0:
            f = 1.0 + sn * sn / 6.0            # θ/sinθ, series (error < 1e-17)
        else:
            f = math.atan2(sn, bz) / sn
        c = -k * f
        return c * by, -c * bx, 0.0, omz, 0.0
    # Cardan variant: R = Rx(α)Ry(β)Rz(φ), U = k/2(α²+β²); spatial τ from Eᵀτ = (−kα, −kβ, 0),
    # E = [e_x, Rx(α)e_y, n]. n = R e_z = (R02, R12, R22).
    r00 = 1.0 - s2 * (y * y + z * z)
    r01 = s2 * (x * y - w * z)
    r02 = s2 * (x * z + w * y)
    r10 = s2 * (x * y + w * z)
    r11 = 1.0 - s2 * (x * x + z * z)
    r12 = s2 * (y * z - w * x)
    r20 = bx
    r21 = by
    r22 = bz
    sb = min(1.0, max(-1.0, r02))
    cb = math.sqrt(max(0.0, 1.0 - sb * sb))
    if cb < cos_cardan:
        return 0.0, 0.0, 0.0, omz, 4.0
    beta = math.asin(sb)
    alpha = math.atan2(-r12, r22)
    ca = math.cos(alpha)
    sa = math.sin(alpha)
    # τ = (−kα (u2×u3) − kβ (u3×u1)) / cosβ, u2 = (0, ca, sa), u3 = n, u1 = e_x
    ga = -k * alpha / cb
    gb = -k * beta / cb
    tx = ga * (ca * r22 - sa * r12)
    ty = ga * (sa * r02) + gb * r22
    tz = ga * (-ca * r02) - gb * r12
    return (r00 * tx + r10 * ty + r20 * tz,
            r01 * tx + r11 * ty + r21 * tz,
            r02 * tx + r12 * ty + r22 * tz, omz, 0.0)


def _python_callback(m, d):
    """Pure-Python passive callback (reference/fallback for the native one)."""
    ud = d.userdata
    if ud[_U_FLAG] != 0.0:
        return
    w, x, y, z = d.qpos.tolist()
    vx, vy, vz = d.qvel.tolist()
    u = ud.tolist()
    tbx, tby, tbz, omz, flag = _spring_kernel(w, x, y, z, vx, vy, vz, u[_U_K], u[_U_VARIANT],
                                              u[_U_COS_PI], u[_U_OMEGA2], u[_U_COS_CARDAN])
    if flag != 0.0:
        ud[_U_FLAG] = flag
        ud[_U_TFAIL] = d.time
        if u[_U_POISON] != 0.0:
            d.qfrc_passive[0] = math.nan
        return
    if u[_U_CEXT] != 0.0 or u[_U_CINT] != 0.0:
        dx, dy, dz = _damper_kernel(w, x, y, z, vx, vy, vz, omz, u[_U_CEXT], u[_U_CINT])
        tbx, tby, tbz = tbx + dx, tby + dy, tbz + dz
    qf = d.qfrc_passive
    qf[0] += tbx
    qf[1] += tby
    qf[2] += tbz
    d.ctrl[0] = u[_U_TORQUE] * omz


# ----------------------------------------------------------------------------------------------
# Native callback: numba cfunc reading mjData through its pointer
# ----------------------------------------------------------------------------------------------
_NATIVE = {"cb": None, "clock": None, "error": None}


def _mjdata_offsets():
    """Byte offsets of time, qpos, qvel, ctrl, qfrc_passive, userdata inside struct mjData.

    Found by matching the buffer addresses of a live MjData against the pointer fields of the
    struct (a zero-size array aliases the next array, so the last match is the real field)."""
    spec = mujoco.MjSpec()
    spec.nuserdata = 2
    b = spec.worldbody.add_body(name="b")
    b.add_joint(type=mujoco.mjtJoint.mjJNT_BALL, name="j")
    b.mass, b.inertia, b.explicitinertial = 1.0, [1.0, 1.0, 1.0], True
    a = spec.add_actuator(trntype=mujoco.mjtTrn.mjTRN_JOINT, target="j")
    a.dyntype = mujoco.mjtDyn.mjDYN_INTEGRATOR
    m = spec.compile()
    d = mujoco.MjData(m)
    marker = 7.123456789e-3
    d.time = marker
    names = ("qpos", "qvel", "ctrl", "qfrc_passive", "userdata")
    want = {int(getattr(d, n).ctypes.data): n for n in names}
    found: dict[str, list[int]] = {}
    base = int(d._address)
    for blk in range(0, 1 << 22, 4096):        # the struct is ~160 kB; stop once all are found
        words = np.frombuffer((ctypes.c_uint64 * 512).from_address(base + blk), dtype=np.uint64)
        if "time" not in found:
            hit = np.nonzero(words.view(np.float64) == marker)[0]
            if hit.size:
                found["time"] = [blk + 8 * int(hit[0])]
        for i in np.nonzero(np.isin(words, np.array(list(want), dtype=np.uint64)))[0]:
            found.setdefault(want[int(words[i])], []).append(blk + 8 * int(i))
        if "time" in found and "qfrc_passive" in found and "userdata" in found:
            break
    if not all(n in found for n in names + ("time",)):
        raise RuntimeError("could not locate mjData fields")
    off = {n: max(v) for n, v in found.items()}
    off["time"] = found["time"][0]
    if not off["time"] < off["qpos"] < off["qvel"] < off["ctrl"]:
        raise RuntimeError("unexpected mjData layout")
    return off


def _native_callback():
    """The compiled cfunc (built once per process), or None with _NATIVE['error'] set."""
    if _NATIVE["cb"] is not None or _NATIVE["error"] is not None:
        return _NATIVE["cb"]
    try:
        from numba import carray, cfunc, njit, types
        from numba.extending import intrinsic

        off = _mjdata_offsets()
        o_time, o_qpos, o_qvel = off["time"] // 8, off["qpos"] // 8, off["qvel"] // 8
        o_ctrl, o_qfrc, o_ud = off["ctrl"] // 8, off["qfrc_passive"] // 8, off["userdata"] // 8
        nwords = max(off.values()) // 8 + 1

        @intrinsic
        def _as_f64ptr(typingctx, addr):
            sig = types.CPointer(types.float64)(addr)

            def codegen(context, builder, signature, args):
                return builder.inttoptr(args[0],
                                        context.get_value_type(types.CPointer(types.float64)))
            return sig, codegen

        damper = njit(cache=True)(_damper_kernel)
        kernel = njit(cache=True)(_spring_kernel)   # cached in __pycache__

        @cfunc(types.void(types.voidptr, types.voidptr), nopython=True)
        def _cb(m, d):
            words = carray(d, (nwords,), np.int64)
            ud = carray(_as_f64ptr(words[o_ud]), (_NUSERDATA,))
            if ud[_U_FLAG] != 0.0:
                return
            q = carray(_as_f64ptr(words[o_qpos]), (4,))
            v = carray(_as_f64ptr(words[o_qvel]), (3,))
            tbx, tby, tbz, omz, flag = kernel(q[0], q[1], q[2], q[3], v[0], v[1], v[2],
                                              ud[_U_K], ud[_U_VARIANT], ud[_U_COS_PI],
                                              ud[_U_OMEGA2], ud[_U_COS_CARDAN])
            if flag != 0.0:
                ud[_U_FLAG] = flag
                ud[_U_TFAIL] = carray(d, (nwords,), np.float64)[o_time]
                if ud[_U_POISON] != 0.0:
                    carray(_as_f64ptr(words[o_qfrc]), (3,))[0] = np.nan
                return
            if ud[_U_CEXT] != 0.0 or ud[_U_CINT] != 0.0:
                dx, dy, dz = damper(q[0], q[1], q[2], q[3], v[0], v[1], v[2], omz, ud[_U_CEXT],
                                    ud[_U_CINT])
                tbx, tby, tbz = tbx + dx, tby + dy, tbz + dz
            qf = carray(_as_f64ptr(words[o_qfrc]), (3,))
            qf[0] += tbx
            qf[1] += tby
            qf[2] += tbz
            carray(_as_f64ptr(words[o_ctrl]), (1,))[0] = ud[_U_TORQUE] * omz

        @cfunc(types.float64())
        def _clock():
            return 0.0

        _NATIVE["cb"], _NATIVE["clock"] = _cb, _clock
    except Exception as exc:  # numba missing, layout not found, ...: fall back to Python
        _NATIVE["error"] = f"{type(exc).__name__}: {exc}"
    return _NATIVE["cb"]


class _Callback:
    """Context manager: install the passive callback, a quiet warning handler and (native) the
    zero clock; restore all three."""

    def __init__(self, kind):
        self.kind = kind
        self.warnings: list[str] = []

    def __enter__(self):
        if self.kind == "native":
            cb = _native_callback()
            if cb is None:
                self.kind = "python"
        self._prev_warning = mujoco.get_mju_user_warning()
        self._prev_clock = mujoco.get_mjcb_time()
        mujoco.set_mju_user_warning(self.warnings.append)   # no stdout, no MUJOCO_LOG.TXT
        mujoco.set_mjcb_passive(_NATIVE["cb"].ctypes if self.kind == "native"
                                else _python_callback)
        if self.kind == "native" and _NATIVE["clock"] is not None:
            mujoco.set_mjcb_time(_NATIVE["clock"].ctypes)
        return self

    def __exit__(self, *exc):
        mujoco.set_mjcb_passive(None)
        mujoco.set_mjcb_time(self._prev_clock)
        mujoco.set_mju_user_warning(self._prev_warning)
        return False


# ----------------------------------------------------------------------------------------------
# Model
# ----------------------------------------------------------------------------------------------
def check_settings(settings, t_out=None):
    """Settings merged and checked before anything runs."""
    s = merge_settings(settings, DEFAULT_SETTINGS, INTEGRATORS)
    if not (isinstance(s["dt"], (int, float)) and math.isfinite(s["dt"]) and s["dt"] > 0):
        raise ValueError(f"dt must be a positive number, got {s['dt']!r}")
    if s["spring"] not in SPRINGS:
        raise ValueError(f"spring must be one of {SPRINGS}, got {s['spring']!r}")
    if s["callback"] not in CALLBACKS:
        raise ValueError(f"callback must be one of {CALLBACKS}, got {s['callback']!r}")
    if not (float(s["omega_max"]) > 0):
        raise ValueError(f"omega_max must be positive, got {s['omega_max']!r}")
    s["dt"] = float(s["dt"])
    return s


MODEL_FIELDS = ("l", "m", "R", "eccentricity", "gravity")   # compiled into the model
_NO_STAGES = int(mujoco.mjtDisableBit.mjDSBL_AUTORESET) | \
    int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT) | int(mujoco.mjtDisableBit.mjDSBL_CONTACT)


def _compile(params, settings, integrator):
    """The ball-joint rotor as an MjModel: everything but torque and k (set in the data)."""
    l, mass, rad = (float(params[n]) for n in ("l", "m", "R"))
    ecc = float(params["eccentricity"])
    g = np.asarray(params["gravity"], dtype=float).reshape(3)
    spec = mujoco.MjSpec()
    spec.modelname = "rotor"
    spec.nuserdata = _NUSERDATA
    spec.option.timestep = settings["dt"]
    spec.option.integrator = _INTEGRATOR_ENUM[integrator]
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


def _build(params, settings, integrator, torque, model=None):
    """(model, data, body id) with the point's torque and k in the data; `model`: one compiled
    from the same MODEL_FIELDS, settings and integrator (else compiled here)."""
    m = _compile(params, settings, integrator) if model is None else model
    d = mujoco.MjData(m)
    bid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "rotor")
    _load(d, bid, params, settings, torque)
    return m, d, bid


def _load(d, bid, params, settings, torque):
    """The point's numbers into the data: the drive wrench, the callback's userdata, and the
    initial state R0 = Rx(tilt0), spin0 about the body axis, no work."""
    d.xfrc_applied[bid, 3:6] = (0.0, 0.0, float(torque))
    ud = d.userdata
    ud[_U_K] = float(params["k"])
    ud[_U_TORQUE] = float(torque)
    ud[_U_COS_PI] = math.cos(math.pi - _PI_MARGIN)
    ud[_U_OMEGA2] = float(settings["omega_max"]) ** 2
    ud[_U_FLAG] = ud[_U_TFAIL] = ud[_U_POISON] = 0.0
    ud[_U_VARIANT] = 0.0 if settings["spring"] == "cone" else 1.0
    ud[_U_COS_CARDAN] = _CARDAN_MARGIN
    ud[_U_CEXT] = float(params.get("c_ext", 0.0))
    ud[_U_CINT] = float(params.get("c_int", 0.0))
    tilt0, spin0 = float(params.get("tilt0", 0.0)), float(params.get("spin0", 0.0))
    d.time = 0.0
    d.qpos[:] = (math.cos(tilt0 / 2), math.sin(tilt0 / 2), 0.0, 0.0)
    d.qvel[:] = (0.0, 0.0, spin0)
    d.act[0] = 0.0


_ROLLOUT_BLOCK = 1 << 17             # steps per rollout call (bounds the state buffer)
_FULL = mujoco.mjtState.mjSTATE_FULLPHYSICS
_XFRC = mujoco.mjtState.mjSTATE_XFRC_APPLIED


def _rollout(m, d, n_per, n_out):
    """Run n_out − 1 output intervals of n_per steps each through mujoco.rollout; returns the
    (time, qpos, qvel, act) rows at the output times that were reached (stops at the first
    block with a callback flag or a non-finite state) and the number of steps taken."""
    nstate = mujoco.mj_stateSize(m, _FULL)
    x = np.empty(nstate)
    mujoco.mj_getState(m, d, x, _FULL)
    ctrl = np.empty(mujoco.mj_stateSize(m, _XFRC))
    mujoco.mj_getState(m, d, ctrl, _XFRC)
    ctrl = ctrl.reshape(1, 1, -1)
    per_block = max(1, _ROLLOUT_BLOCK // n_per) * n_per
    total = (n_out - 1) * n_per
    rows, done = [], 0
    while done < total:
        nstep = min(per_block, total - done)
        st, _ = mujoco.rollout.rollout(m, d, x, ctrl, control_spec=_XFRC.value, nstep=nstep)
        st = st[0]
        rows.append(st[n_per - 1::n_per])
        done += nstep
        x = st[-1].copy()
        if d.userdata[_U_FLAG] != 0.0 or not np.all(np.isfinite(x)):
            break
    return (np.concatenate(rows) if rows else np.empty((0, nstate))), done


def _bad_warnings(d):
    return sum(int(d.warning[int(w)].number) for w in (mujoco.mjtWarning.mjWARN_BADQPOS,
                                                        mujoco.mjtWarning.mjWARN_BADQVEL,
                                                        mujoco.mjtWarning.mjWARN_BADQACC))


# ----------------------------------------------------------------------------------------------
# Channels (vectorised, from stored states)
# ----------------------------------------------------------------------------------------------
def _channels(params, spring, quat, vel, work):
    """The shared rotor channels; only the Cardan variant brings its own spring potential."""
    R = physics.rotations_from_quaternions(quat)
    u_spring = None
    if spring == "cardan":
        n = R[:, :, 2]
        beta = np.arcsin(np.clip(n[:, 0], -1, 1))
        alpha = np.arctan2(-n[:, 1], n[:, 2])
        u_spring = 0.5 * float(params["k"]) * (alpha**2 + beta**2)
    return physics.channels(params, R, np.einsum("nij,nj->ni", R, vel), work, u_spring)


# ----------------------------------------------------------------------------------------------
# simulate
# ----------------------------------------------------------------------------------------------
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
        if ud[_U_FLAG] != 0.0:
            bad = _FLAG_REASONS.get(float(ud[_U_FLAG]), "callback flag")
            t_fail = float(ud[_U_TFAIL])
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
    return _run(params, t_out, s)


def _uniform_steps(t_out, dt):
    """(steps per output interval, step) where the grid is uniform but for round-off (np.diff
    of a linspace) and no coarser than dt: the whole run is one step size, so one rollout.
    None otherwise."""
    intervals = np.diff(t_out)
    if not intervals.size or dt > intervals.min() * (1 + 1e-9) or \
            np.ptp(intervals) > 1e-9 * intervals.mean():
        return None
    n = max(1, int(math.ceil(intervals[0] / dt - 1e-9)))
    return n, float((t_out[-1] - t_out[0]) / (n * intervals.size))


def _run(params, t_out, s, model=None):
    """`simulate` on checked settings and grid; `model`: a compiled one to reuse (`_build`)."""
    m, d, bid = _build(params, s, s["integrator"], float(params["torque"]), model)

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
        one_step = _uniform_steps(t_out, dt)
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
    wall0 = _time.perf_counter()
    with _Callback(s["callback"]) as cbk:
        if cbk.kind == "native" and uniform:
            m.opt.timestep = chunks[0][1]
            rows, steps = _rollout(m, d, chunks[0][0], nrec)
            nq = 1 + m.nq
            fin = np.all(np.isfinite(rows), axis=1)
            good = int(np.argmin(fin)) if not fin.all() else len(rows)
            if ud[_U_FLAG] != 0.0:
                t_fail = float(ud[_U_TFAIL])
                reason = _FLAG_REASONS.get(float(ud[_U_FLAG]), "callback flag")
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
    wall = _time.perf_counter() - wall0

    ch = _channels(params, s["spring"], quat, vel, work)
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
        used["callback_fallback_reason"] = _NATIVE["error"]
    return LeafResult(
        channels={name: np.ascontiguousarray(v, dtype=np.float64) for name, v in ch.items()},
        status=status, t_fail=t_fail, reason=reason,
        stats={"steps": int(steps), "rhs_evals": int(steps * _RHS_PER_STEP[s["integrator"]]),
               "integrate_s": wall},
        settings=used, extra={"orientation": orient})


def regimes(params_list, t_out, settings, channel, levels, window):
    """The map's batch path, reduced to the regime on |ω| (`physics.regime_summaries`; None for
    another channel). `levels`: (n, 2) per point. With the native callback on a uniform grid
    (the normal case) the points sharing MODEL_FIELDS run as one `mujoco.rollout` call
    (`_rolled_together`); else each point is `_run` on its group's model."""
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
        m = _compile(params_list[idx[0]], s, s["integrator"])
        group = [params_list[i] for i in idx]
        done = _rolled_together(m, group, t_out, s)
        for i, r in zip(idx, done or [_run(p, t_out, s, m) for p in group]):
            runs[i] = r
    levels = np.asarray(levels, float)
    return physics.regime_summaries(t_out, runs, levels[:, 0], levels[:, 1], window)


_BATCH_ROWS = 1 << 18          # states per rollout call (rolls × steps): ≈ 20 MB for the rotor
_USER = mujoco.mjtState.mjSTATE_USERDATA


def _rolled_together(m, group, t_out, s):
    """Every point of `group` (one model) in one `mujoco.rollout` call per ≤ _BATCH_ROWS
    states: each roll's initial state, drive wrench and userdata are its own (the wrench and
    the userdata as the rollout's constant control), the steps those of `_run`. A flagged stage
    makes the roll's state NaN (`_U_POISON`): such a run comes back `diverged` and the caller
    runs it alone, which says why. None where `_run` would not take one rollout (Python
    callback, a step longer than the output step, an uneven grid)."""
    one_step = _uniform_steps(t_out, s["dt"])
    if one_step is None or s["callback"] != "native" or _native_callback() is None:
        return None
    n_per, m.opt.timestep = one_step
    d = mujoco.MjData(m)
    bid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "rotor")
    spec = _XFRC.value | _USER.value
    x0 = np.empty((len(group), mujoco.mj_stateSize(m, _FULL)))
    ctrl = np.empty((len(group), 1, mujoco.mj_stateSize(m, spec)))
    for x, c, p in zip(x0, ctrl, group):
        _load(d, bid, p, s, float(p["torque"]))
        d.userdata[_U_POISON] = 1.0
        mujoco.mj_getState(m, d, x, _FULL)
        mujoco.mj_getState(m, d, c[0], spec)
    nstep = n_per * (len(t_out) - 1)
    per_call = max(1, _BATCH_ROWS // nstep)
    nq, runs = 1 + m.nq, []
    with _Callback("native"):
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
                runs.append(LeafResult(channels=_channels(p, s["spring"], quat, vel, work)))
    return runs


# ----------------------------------------------------------------------------------------------
# Linearised whirl (rotor-whirl)
# ----------------------------------------------------------------------------------------------
_FD_H = 1e-3        # Euler step used for transitionFD; the extraction below is h-independent
_FD_EPS = 1e-6
FD_VARY = 10.0      # the FD step × this: the linearisation's own error


def _whirl_setup(params, settings):
    s = check_settings({**(settings or {}), "integrator": "euler", "dt": _FD_H})
    m, d, _ = _build(params, s, "euler", torque=0.0)   # no drive torque in the linearisation
    return s, m, d


def _continuous_A(m, d, spin, eps=_FD_EPS):
    """The continuous-time state matrix (δ, v: body-frame tangent rotation and angular
    velocity) about steady spin Ω e_z at tilt 0."""
    ud = d.userdata.copy()
    mujoco.mj_resetData(m, d)        # (this also zeroes userdata: restore it)
    d.userdata[:] = ud
    d.qpos[:] = (1.0, 0.0, 0.0, 0.0)
    d.qvel[:] = (0.0, 0.0, spin)
    d.act[0] = 0.0
    d.userdata[_U_FLAG] = 0.0
    nv = m.nv
    ns = 2 * nv + m.na
    A = np.zeros((ns, ns))
    mujoco.mjd_transitionFD(m, d, eps, True, A, None, None, None)
    h = m.opt.timestep
    # Euler: v' = v + h·a(q, v) exactly, so Aq = A21/h and Av = (A22 − I)/h are exact. The
    # kinematic blocks are taken analytically: ball tangent coordinates are body-frame,
    # q = q_ref(t) ⊗ exp(δ), so δ' = −[ω×]δ + δω (the discrete map has exp(−h[ω×]) there,
    # which (A11 − I)/h would only approximate to O(hΩ)).
    A21 = A[nv:2 * nv, :nv]
    A22 = A[nv:2 * nv, nv:2 * nv]
    Aq = A21 / h
    Av = (A22 - np.eye(nv)) / h
    om = np.array(d.qvel, dtype=float)
    wx = np.array([[0, -om[2], om[1]], [om[2], 0, -om[0]], [-om[1], om[0], 0]])
    return np.block([[-wx, np.eye(nv)], [Aq, Av]])


def _whirl_at(m, d, spin):
    """Continuous-time eigen-analysis at steady spin; returns [(signed inertial rad/s, Re λ)]
    (the body-frame tangent coordinates shift the frequency by Ω, not the real part)."""
    lam, vec = np.linalg.eig(_continuous_A(m, d, spin))
    out = []
    for j in np.argsort(-np.abs(lam.imag)):
        lj = lam[j]
        if lj.imag <= 1e-9 * max(1.0, abs(lj)):
            continue
        v = vec[:, j]
        tilt_part = np.linalg.norm(v[0:2])
        if tilt_part < 1e-6 * np.linalg.norm(v[:3]):
            continue
        # body-frame rotation sense of δ(t) = Re(v e^{λt}) in the (x, y) tangent plane
        sense_b = -(v[0].real * v[1].imag - v[1].real * v[0].imag)
        mu = lj.imag
        signed_body = mu if sense_b > 0 else -mu
        if abs(sense_b) < 1e-9 * (abs(v[0]) ** 2 + abs(v[1]) ** 2):
            signed_body = mu    # linear (non-circular) mode: no sense
        out.append((signed_body + spin, lj.real, sense_b, lj))
    return out


def _classify(pairs, spin):
    """Pick the two whirl modes; return (backward, forward) as (freq_rad_s, Re λ, λ of A)."""
    if len(pairs) < 2:
        raise RuntimeError(f"expected two whirl modes, found {len(pairs)}")
    pairs = pairs[:2]
    if abs(spin) < 1e-12:
        a, b = sorted(((abs(p[0]), p[1], p[3]) for p in pairs), key=lambda t: t[:2])
        return a, b
    fw = [p for p in pairs if np.sign(p[0]) == np.sign(spin)]
    bw = [p for p in pairs if np.sign(p[0]) != np.sign(spin)]
    if len(fw) != 1 or len(bw) != 1:   # fall back to the closed-form ordering: backward lower
        a, b = sorted(((abs(p[0]), p[1], p[3]) for p in pairs), key=lambda t: t[:2])
        return a, b
    return (abs(bw[0][0]), bw[0][1], bw[0][3]), (abs(fw[0][0]), fw[0][1], fw[0][3])


def modes(params: dict, settings: dict) -> dict:
    """Linearised whirl frequencies at steady spin params['spin'] (rad/s) about the upright axis.

    Linearisation: mjd_transitionFD under Euler (no drive torque), continuous-time blocks
    recovered exactly, ball-joint body-frame tangent frequencies converted to the inertial frame
    (+Ω), backward/forward labelled from the eigenvector's rotation sense. With c_ext = 0 the
    internal-damping threshold whirl is synchronous (ω = Ω): still in the body-frame
    coordinates, its root is real there and not found within ~1e-9 of that speed."""
    spin = float(params["spin"])
    s, m, d = _whirl_setup(params, settings)
    with _Callback(s["callback"]) as cbk:
        pairs = _whirl_at(m, d, spin)
        (wb, sb, lam_b), (wf, sf, lam_f) = _classify(pairs, spin)
        # ζ's and the frequencies' errors: eigen round-off plus the change when the FD step is
        # varied, mode by mode. The body-frame root moves by |δλ|, and so does the inertial
        # frequency |Im λ ± Ω|: backward whirl's (Ω + ω_b)/ω_b magnifies it, relative
        A, A_varied = (_continuous_A(m, d, spin, e) for e in (_FD_EPS, FD_VARY * _FD_EPS))
        z_err = eigen.root_zeta_errors(A, [lam_b, lam_f], A_varied,
                                       reported=[sb + 1j * wb, sf + 1j * wf])
        f_err = eigen.root_errors(A, [lam_b, lam_f], A_varied) / (2 * math.pi)
        kind = cbk.kind
    used = {"integrator": "euler", "dt": _FD_H, "fd_eps": _FD_EPS, "spring": s["spring"],
            "callback": kind, "linearisation": "mjd_transitionFD, ball joint, inertial frame"}
    notes = (["approximate: steady spin is no equilibrium of an eccentric rotor"]
             if spin != 0 and params["eccentricity"] != 0 else [])
    return LeafModes(frequencies_hz=np.array([wb, wf]) / (2 * math.pi),
                       labels=["backward whirl", "forward whirl"], whirl=["backward", "forward"],
                       damping=-np.array([sb, sf]) / np.hypot([sb, sf], [wb, wf]),
                       settings=used, notes=notes,
                       extra={"max_re_per_s": float(max(sb, sf)),
                              "damping_error": z_err, "frequency_error_hz": f_err})


def whirl_sweep(params: dict, spins, settings: dict | None = None):
    """Campbell sweep: (backward_rad_s, forward_rad_s) arrays over ``spins``, one compiled model."""
    spins = np.asarray(spins, dtype=float)
    s, m, d = _whirl_setup(params, settings)
    bw = np.empty(spins.size)
    fw = np.empty(spins.size)
    with _Callback(s["callback"]):
        for i, om in enumerate(spins):
            (b, *_), (f, *_) = _classify(_whirl_at(m, d, float(om)), float(om))
            bw[i], fw[i] = b, f
    return bw, fw


# ----------------------------------------------------------------------------------------------
# Unbalance response (rotor-whirl)
# ----------------------------------------------------------------------------------------------
_HE = 1e-7          # eccentricity step of the input derivative, per unit l
_TRANSVERSE = [0, 1, 3, 4]      # δ_x, δ_y, v_x, v_y: the spin rows do not couple at tilt 0


def _qacc(params, settings, spin):
    """MuJoCo's acceleration (mj_forward) at tilt 0 spinning at Ω about e_z."""
    _, m, d = _whirl_setup(params, settings)
    d.qpos[:] = (1.0, 0.0, 0.0, 0.0)
    d.qvel[:] = (0.0, 0.0, spin)
    mujoco.mj_forward(m, d)
    return np.array(d.qacc, dtype=float)


def _unbalance_amplitudes(params, spins, settings, eps):
    """Forward tilt amplitudes a (θ = a e^{iΩt}). In the ball joint's body-frame coordinates
    the unbalance is fixed (it turns with the body): the steady response is the constant δ
    with A δ + b e = 0 on the transverse rows, A = `_continuous_A` (mjd_transitionFD), b =
    d q̈/de by central differences (±_HE l) of mj_forward. Back in the fixed frame the tilt is
    θ = e^{iΩt}(δ_x + iδ_y) (the axis R e_z ≈ R_z(Ωt)(e_z + δ × e_z)), so a = δ_x + iδ_y."""
    base = dict(params, eccentricity=0.0)
    he = _HE * params["l"]
    s, m, d = _whirl_setup(base, settings)
    out = []
    with _Callback(s["callback"]):
        for spin in spins:
            A = _continuous_A(m, d, spin, eps)[np.ix_(_TRANSVERSE, _TRANSVERSE)]
            b = (_qacc({**base, "eccentricity": he}, settings, spin)
                 - _qacc({**base, "eccentricity": -he}, settings, spin)) / (2 * he)
            rhs = -np.concatenate([[0.0, 0.0], b[:2]]) * params["eccentricity"]
            delta = np.linalg.solve(A, rhs)
            out.append((delta[0] + 1j * delta[1], np.linalg.cond(A)))
    a, cond = np.array(out).T
    return a, cond.real


def unbalance_response(params, spins, settings=None):
    """(a, error) per spin (`_unbalance_amplitudes`); the error is the change of the result
    when mjd_transitionFD's step is doubled (4/3 of it: its truncation) plus the linear
    solve's round-off, cond(A)·ε·|a| (the bar without it, 5.9e-15 relative at 82 rad/s, fell
    short of the 7.6e-15 seen against the closed form; cond(A) ≈ 1e2…1e4)."""
    a, cond = _unbalance_amplitudes(params, spins, settings, _FD_EPS)
    a2, _ = _unbalance_amplitudes(params, spins, settings, 2 * _FD_EPS)
    return a, 4 / 3 * np.abs(a - a2) + (cond + 8) * np.finfo(float).eps * np.abs(a)
