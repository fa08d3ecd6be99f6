"""The passive-force callback that applies the kernel's moments inside every integrator stage.

Inside every RK4 stage, so RK4 stays 4th order (a per-step `qfrc_applied` would freeze the force
over the stages). By default it is a numba `cfunc` installed as a raw C function pointer: it
reads `qpos`/`qvel` and writes `qfrc_passive`/`ctrl` through the `mjData` pointer it is given,
so MuJoCo never re-enters Python (about 10x faster than a Python callable). The offsets of those
`mjData` fields are found at run time by matching the pointers of a live `MjData` object; if
that or numba fails, the pure-Python callable (`settings["callback"] = "python"`) is used.
While a model runs, a clock that returns 0 is installed as `mjcb_time`: MuJoCo 4.0 otherwise
reads the system clock around every pipeline stage for `mjData.timer`, which nothing here reads.
"""
import ctypes
import math

import mujoco
import numpy as np

from .kernel import (
    NUSERDATA,
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
    damper_kernel,
    spring_kernel,
)


def python_callback(m, d):
    """Pure-Python passive callback (reference/fallback for the native one)."""
    ud = d.userdata
    if ud[U_FLAG] != 0.0:
        return
    w, x, y, z = d.qpos.tolist()
    vx, vy, vz = d.qvel.tolist()
    u = ud.tolist()
    tbx, tby, tbz, omz, flag = spring_kernel(w, x, y, z, vx, vy, vz, u[U_K], u[U_VARIANT],
                                             u[U_COS_PI], u[U_OMEGA2], u[U_COS_CARDAN])
    if flag != 0.0:
        ud[U_FLAG] = flag
        ud[U_TFAIL] = d.time
        if u[U_POISON] != 0.0:
            d.qfrc_passive[0] = math.nan
        return
    if u[U_CEXT] != 0.0 or u[U_CINT] != 0.0:
        dx, dy, dz = damper_kernel(w, x, y, z, vx, vy, vz, omz, u[U_CEXT], u[U_CINT])
        tbx, tby, tbz = tbx + dx, tby + dy, tbz + dz
    qf = d.qfrc_passive
    qf[0] += tbx
    qf[1] += tby
    qf[2] += tbz
    d.ctrl[0] = u[U_TORQUE] * omz


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


def native_callback():
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

        damper = njit(cache=True)(damper_kernel)
        kernel = njit(cache=True)(spring_kernel)   # cached in __pycache__

        @cfunc(types.void(types.voidptr, types.voidptr), nopython=True)
        def _cb(m, d):
            words = carray(d, (nwords,), np.int64)
            ud = carray(_as_f64ptr(words[o_ud]), (NUSERDATA,))
            if ud[U_FLAG] != 0.0:
                return
            q = carray(_as_f64ptr(words[o_qpos]), (4,))
            v = carray(_as_f64ptr(words[o_qvel]), (3,))
            tbx, tby, tbz, omz, flag = kernel(q[0], q[1], q[2], q[3], v[0], v[1], v[2],
                                              ud[U_K], ud[U_VARIANT], ud[U_COS_PI],
                                              ud[U_OMEGA2], ud[U_COS_CARDAN])
            if flag != 0.0:
                ud[U_FLAG] = flag
                ud[U_TFAIL] = carray(d, (nwords,), np.float64)[o_time]
                if ud[U_POISON] != 0.0:
                    carray(_as_f64ptr(words[o_qfrc]), (3,))[0] = np.nan
                return
            if ud[U_CEXT] != 0.0 or ud[U_CINT] != 0.0:
                dx, dy, dz = damper(q[0], q[1], q[2], q[3], v[0], v[1], v[2], omz, ud[U_CEXT],
                                    ud[U_CINT])
                tbx, tby, tbz = tbx + dx, tby + dy, tbz + dz
            qf = carray(_as_f64ptr(words[o_qfrc]), (3,))
            qf[0] += tbx
            qf[1] += tby
            qf[2] += tbz
            carray(_as_f64ptr(words[o_ctrl]), (1,))[0] = ud[U_TORQUE] * omz

        @cfunc(types.float64())
        def _clock():
            return 0.0

        _NATIVE["cb"], _NATIVE["clock"] = _cb, _clock
    except Exception as exc:  # numba missing, layout not found, ...: fall back to Python
        _NATIVE["error"] = f"{type(exc).__name__}: {exc}"
    return _NATIVE["cb"]


def fallback_reason():
    """Why the native callback could not be built (None where it was)."""
    return _NATIVE["error"]


class Callback:
    """Context manager: install the passive callback, a quiet warning handler and (native) the
    zero clock; restore all three."""

    def __init__(self, kind):
        self.kind = kind
        self.warnings: list[str] = []

    def __enter__(self):
        if self.kind == "native":
            cb = native_callback()
            if cb is None:
                self.kind = "python"
        self._prev_warning = mujoco.get_mju_user_warning()
        self._prev_clock = mujoco.get_mjcb_time()
        mujoco.set_mju_user_warning(self.warnings.append)   # no stdout, no MUJOCO_LOG.TXT
        mujoco.set_mjcb_passive(_NATIVE["cb"].ctypes if self.kind == "native"
                                else python_callback)
        if self.kind == "native" and _NATIVE["clock"] is not None:
            mujoco.set_mjcb_time(_NATIVE["clock"].ctypes)
        return self

    def __exit__(self, *exc):
        mujoco.set_mjcb_passive(None)
        mujoco.set_mjcb_time(self._prev_clock)
        mujoco.set_mju_user_warning(self._prev_warning)
        return False
