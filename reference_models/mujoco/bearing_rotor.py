"""MuJoCo model of the two-bearing rotor with a bearing defect (scene `bearing-rotor`).

The shaft is one body on a free joint (six degrees of freedom) with its frame at the centre of
mass: mass m, central inertia diag(J_t, J_t, J_p), axis body z; gravity is MuJoCo's. Everything
else — the bearing spring–dampers with the defect lift, the axial spring, the motor and the
friction moment about the shaft axis — is `compare.physics.bearing_rotor.body_loads`, evaluated
by a passive-force callback at every force evaluation (inside every RK4 stage, so RK4 stays 4th
order; a per-step `qfrc_applied` would freeze the force over the stages).

The callback is, by default, a numba `cfunc` installed as a raw C function pointer (MuJoCo never
re-enters Python). It finds the arrays of the one `MjData` being stepped through a small address
table (`_ADDR`) that `simulate` fills before stepping, so no knowledge of the `mjData` struct
layout is needed; the table is found through an external symbol, so numba caches the compiled
callback on disk (a fresh process loads it instead of compiling for ~4 s). The callback acts
only on the `MjData` named in the table: MuJoCo also calls the (process-global) passive
callback while any model compiles, e.g. in another thread. `settings["callback"] = "python"`
installs a Python callable running the same numba kernel (default 3 s run: 5.8 s against 2.5 s
native, measured under load). Simulations and compiles of this leaf hold a lock (threads of one
process, e.g. Dask workers, run them one at a time); a run whose callback another leaf replaced
or removed meanwhile ends `diverged`.

Free-joint conventions: qvel[0:3] is the world velocity of the body frame (the centre of mass),
qvel[3:6] the angular velocity in the body frame; qfrc_passive[0:3] takes the world force and
qfrc_passive[3:6] the moment in the body frame.

Stepping: with the native callback, `mujoco.rollout` runs blocks of 2^14 steps in C and the
output rows are picked from its states (checks between blocks); with the Python callback one
`mj_step(m, d, n)` call per output interval.

Motor work and dissipated work are two actuator states with integrator dynamics and zero gain
and gear (they exert nothing); the callback sets their `ctrl` to Ẇ and Ḋ in every stage, so
MuJoCo's own integrator integrates them with the mechanics (act_dot = ctrl) — the energy
balance closes at the integrator's accuracy, not at the output grid's.

Divergence: the kernel raises a flag on a non-finite state or a bound (journal farther than l/4
from its bearing, |ω| > 1e5 rad/s) and stops applying loads; MuJoCo's bad-qpos/qvel/qacc warning
counters (every 64 output steps and at the end) and the simulated time (every output step)
are checked (MuJoCo resets a diverged state silently unless autoreset is disabled, which it is
here); the energy balance is checked on the output grid. Each ends the run as `diverged` with
t_fail and the reason.
"""
from __future__ import annotations

import ctypes
import math
import threading
import time

import llvmlite.binding as llvm
import mujoco
import mujoco.rollout
import numpy as np
from llvmlite import ir
from numba import carray, cfunc, njit, types
from numba.extending import intrinsic

from compare.contract import LeafResult, merge_settings
from compare.physics import bearing_rotor as br
from reference_models import bearing_common as bc

# Accurate default (measured against RK4 at 5 µs over the default 3 s run): RK4 at 50 µs —
# journals within 2e-11 m, spin rate within 1.3e-7 rad/s, energy balance 1e-8 of the motor work;
# inside the RK4 stability limit of the bearing modes up to k_b ≈ 3e9 N/m (bearing_common).
# dt="auto": this step, or half the stability limit of the bearing modes where that is smaller
# (k_b above ~8e8 N/m).
DEFAULT_SETTINGS = {"integrator": "rk4", "dt": 5e-5, "callback": "native"}
INTEGRATORS = ("rk4", "euler", "implicitfast", "implicit")
CALLBACKS = ("native", "python")
_ENUM = {"rk4": mujoco.mjtIntegrator.mjINT_RK4, "euler": mujoco.mjtIntegrator.mjINT_EULER,
         "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST,
         "implicit": mujoco.mjtIntegrator.mjINT_IMPLICIT}
_STAGES = {"rk4": 4, "euler": 1, "implicitfast": 1, "implicit": 1}
# |h·λ| limits for dt="auto" (the callback's forces are explicit in every integrator; the
# Euler family is taken as the symplectic-Euler oscillator limit 2)
_STABILITY = {"rk4": bc.RK4_STABILITY, "euler": 2.0, "implicitfast": 2.0, "implicit": 2.0}

# userdata: [flag, journal bound (m), omega bound (rad/s), packed scene parameters...]
_U_FLAG, _U_RBOUND, _U_WBOUND, _U_P = 0, 1, 2, 3
_FLAG_REASONS = {1.0: "non-finite state", 2.0: "journal left its bearing by more than l/4",
                 3.0: "angular velocity bound exceeded"}


@njit(cache=True)
def _passive(qpos, qvel, qfrc, ctrl, ud):
    """Add the bearing/motor/friction wrench to qfrc_passive and set ctrl = (Ẇ, Ḋ)."""
    if ud[_U_FLAG] != 0.0:
        qfrc[0] = np.nan      # poison the state: the stop shows in the stored rows at once
        return
    s = 0.0
    for i in range(7):
        s += qpos[i]
    for i in range(6):
        s += qvel[i]
    if not math.isfinite(s):
        ud[_U_FLAG] = 1.0
        return
    q = qpos[3:7].copy()
    R = br.quat_matrix(q)
    omega = R @ qvel[3:6]
    r = qpos[0:3].copy()
    half = 0.5 * ud[_U_P + br.I_L]
    if (r[0] * r[0] + r[1] * r[1]) ** 0.5 + half * (R[0, 2] ** 2 + R[1, 2] ** 2) ** 0.5 \
            > ud[_U_RBOUND]:
        ud[_U_FLAG] = 2.0
        return
    if omega @ omega > ud[_U_WBOUND] ** 2:
        ud[_U_FLAG] = 3.0
        return
    force, moment, p_motor, p_diss = br.body_loads(r, q, qvel[0:3].copy(), omega, ud[_U_P:])
    mb = R.T @ moment
    for i in range(3):
        qfrc[i] += force[i]
        qfrc[3 + i] += mb[i]
    ctrl[0] = p_motor
    ctrl[1] = p_diss


def _python_callback(m, d):
    if d._address == _ADDR[6]:        # only the MjData being stepped (see _ADDR)
        _passive(d.qpos, d.qvel, d.qfrc_passive, d.ctrl, d.userdata)


# --------------------------------------------------------------------- native callback
# The cfunc reaches the arrays of the MjData being stepped through _ADDR; it finds _ADDR through
# an external symbol resolved when the machine code is loaded (llvmlite add_symbol), not through
# an address baked into the code, so numba can cache the compiled callback on disk. The callback
# acts only on the MjData whose address is _ADDR[6]: MuJoCo calls the (process-global) passive
# callback for any model, e.g. while another thread compiles one (mj_setConst), and writing
# that call's forces into the stepped arrays would corrupt a running simulation silently.
# _ADDR: qpos, qvel, qfrc_passive, ctrl, userdata, len(userdata), address of the stepped mjData
_ADDR = np.zeros(7, dtype=np.int64)
_ADDR_SYMBOL = "xval_bearing_rotor_mjdata_table"
_ADDR_CELL = ctypes.c_int64(_ADDR.ctypes.data)     # the array is never rebound
_NATIVE = {"cb": None, "error": None}
_LOCK = threading.Lock()              # one simulation per process at a time (global callback)


@intrinsic
def _table(typingctx):
    def codegen(context, builder, signature, args):
        gv = builder.module.globals.get(_ADDR_SYMBOL)
        if gv is None:
            gv = ir.GlobalVariable(builder.module, ir.IntType(64), name=_ADDR_SYMBOL)
            gv.linkage = "external"
        return builder.load(gv)
    return types.int64(), codegen


@intrinsic
def _ptr(typingctx, addr):
    def codegen(context, builder, signature, args):
        return builder.inttoptr(args[0], context.get_value_type(types.CPointer(types.float64)))
    return types.CPointer(types.float64)(addr), codegen


@intrinsic
def _address(typingctx, ptr):
    def codegen(context, builder, signature, args):
        return builder.ptrtoint(args[0], ir.IntType(64))
    return types.int64(ptr), codegen


@intrinsic
def _iptr(typingctx, addr):
    def codegen(context, builder, signature, args):
        return builder.inttoptr(args[0], context.get_value_type(types.CPointer(types.int64)))
    return types.CPointer(types.int64)(addr), codegen


def _native_callback():
    """The cfunc (compiled once, cached on disk), or None with _NATIVE['error'] set."""
    if _NATIVE["cb"] is not None or _NATIVE["error"] is not None:
        return _NATIVE["cb"]
    try:
        llvm.add_symbol(_ADDR_SYMBOL, ctypes.addressof(_ADDR_CELL))

        @cfunc(types.void(types.voidptr, types.voidptr), nopython=True, cache=True)
        def _cb(m, d):
            a = carray(_iptr(_table()), (7,))
            if _address(d) != a[6]:
                return
            _passive(carray(_ptr(a[0]), (7,)), carray(_ptr(a[1]), (6,)),
                     carray(_ptr(a[2]), (6,)), carray(_ptr(a[3]), (2,)),
                     carray(_ptr(a[4]), (a[5],)))

        _NATIVE["cb"] = _cb
    except Exception as exc:  # noqa: BLE001 - numba missing or failing: use the Python callable
        _NATIVE["error"] = f"{type(exc).__name__}: {exc}"
    return _NATIVE["cb"]


class _Callback:
    """Install the passive callback (and a quiet warning handler) for one MjData; restore."""

    def __init__(self, kind: str, d):
        self.kind, self.d = kind, d
        self.warnings: list[str] = []

    def __enter__(self):
        cb = _native_callback() if self.kind == "native" else None
        if cb is None:
            self.kind = "python"
        d = self.d
        _ADDR[:] = (d.qpos.ctypes.data, d.qvel.ctypes.data, d.qfrc_passive.ctypes.data,
                    d.ctrl.ctypes.data, d.userdata.ctypes.data, len(d.userdata), d._address)
        self._prev = mujoco.get_mju_user_warning()
        mujoco.set_mju_user_warning(self.warnings.append)    # no stdout, no MUJOCO_LOG.TXT
        mujoco.set_mjcb_passive(cb.ctypes if cb is not None else _python_callback)
        return self

    def intact(self) -> bool:
        """Whether our callback is still the installed one (another leaf in another thread may
        have replaced or removed it: the run would then go on without its forces)."""
        g = mujoco.get_mjcb_passive()
        if self.kind == "python":
            return g is _python_callback
        return g is not None and ctypes.cast(g, ctypes.c_void_p).value == _NATIVE["cb"].address

    def __exit__(self, *exc):
        mujoco.set_mjcb_passive(None)
        mujoco.set_mju_user_warning(self._prev)
        _ADDR[:] = 0
        return False


# --------------------------------------------------------------------- model
def _build(params: dict, integrator: str, h: float):
    """The free shaft and the two work integrators; (model, data) at the common start."""
    p = br.pack(params)
    spec = mujoco.MjSpec()
    spec.modelname = "bearing_rotor"
    spec.nuserdata = _U_P + len(p)
    spec.option.timestep = h
    spec.option.integrator = _ENUM[integrator]
    spec.option.gravity = [float(x) for x in params["gravity"]]
    body = spec.worldbody.add_body(name="shaft")
    body.add_freejoint(name="free")
    body.mass = float(params["m"])
    body.inertia = [float(params["J_t"]), float(params["J_t"]), float(params["J_p"])]
    body.explicitinertial = True
    for name in ("motor_work", "dissipated"):
        act = spec.add_actuator(trntype=mujoco.mjtTrn.mjTRN_JOINT, target="free", name=name)
        act.dyntype = mujoco.mjtDyn.mjDYN_INTEGRATOR
        act.gainprm = [0.0] * len(act.gainprm)
        act.biasprm = [0.0] * len(act.biasprm)
        act.gear = [0.0] * 6
        act.ctrllimited = mujoco.mjtLimited.mjLIMITED_FALSE
        act.actlimited = mujoco.mjtLimited.mjLIMITED_FALSE
    m = spec.compile()
    m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_AUTORESET)
    d = mujoco.MjData(m)
    d.userdata[_U_FLAG] = 0.0
    d.userdata[_U_RBOUND] = bc.JOURNAL_BOUND * float(params["l"])
    d.userdata[_U_WBOUND] = bc.OMEGA_BOUND
    d.userdata[_U_P:] = p
    r0, q0, v0, w0 = br.initial_state(params)
    d.qpos[:] = np.concatenate([r0, q0])
    d.qvel[:] = np.concatenate([v0, br.quat_matrix(q0).T @ w0])
    d.act[:] = 0.0
    return m, d


def _check(d, cbk, rows, times, t_expect):
    """(index of the first bad row, reason) of freshly stepped rows (qpos|qvel|act), or None."""
    finite = np.isfinite(rows).all(axis=1)
    if d.userdata[_U_FLAG] != 0.0:
        j = int(np.argmin(finite)) if not finite.all() else len(rows) - 1
        return j, _FLAG_REASONS[float(d.userdata[_U_FLAG])]
    if not finite.all():
        return int(np.argmin(finite)), "non-finite state"
    late = np.abs(times - t_expect) > 1e-9 * np.maximum(1.0, t_expect)
    if late.any():
        j = int(np.argmax(late))
        return j, f"time did not advance as expected (MuJoCo reset?) t = {times[j]:.6g} s"
    if not cbk.intact():
        return 0, "the passive callback was replaced (another MuJoCo model in this process)"
    return None


def _by_output_step(m, d, t_out, n_sub, cbk):
    """mj_step over each output interval (the Python-callback path)."""
    n = len(t_out)
    rows = np.full((n, 15), np.nan)            # qpos (7) | qvel (6) | act (2)
    rows[0] = np.concatenate([d.qpos, d.qvel, d.act])
    steps = 0
    for i in range(1, n):
        mujoco.mj_step(m, d, n_sub)
        steps += n_sub
        rows[i] = np.concatenate([d.qpos, d.qvel, d.act])
        bad = _check(d, cbk, rows[i:i + 1], np.array([d.time]), t_out[i:i + 1])
        if bad is None and i % 64 == 0 and _bad_warnings(d):
            bad = 0, "MuJoCo reported a bad (NaN/huge) qpos/qvel/qacc"
        if bad is not None:
            return rows[:, :7], rows[:, 7:13], rows[:, 13:], steps, i, bad[1]
    return rows[:, :7], rows[:, 7:13], rows[:, 13:], steps, None, None


_ROLLOUT_BLOCK = 1 << 14                     # steps per rollout call (checks between calls)
_FULL = mujoco.mjtState.mjSTATE_FULLPHYSICS  # time | qpos | qvel | act


def _by_rollout(m, d, t_out, n_sub, cbk):
    """mujoco.rollout over blocks of output intervals: the steps run in C, the output rows are
    picked from the per-step states; identical channels to `_by_output_step`, ~10 % less CPU
    on the default run (1.12–1.36 s against 1.25–1.40 s, 4 runs each, busy machine)."""
    n = len(t_out)
    rows = np.full((n, 15), np.nan)
    x = np.empty(mujoco.mj_stateSize(m, _FULL))
    mujoco.mj_getState(m, d, x, _FULL)
    rows[0] = x[1:16]
    per_block = max(1, _ROLLOUT_BLOCK // n_sub)
    i, steps = 1, 0
    while i < n:
        k = min(per_block, n - i)
        st, _ = mujoco.rollout.rollout(m, d, x, nstep=k * n_sub)
        picked = st[0][n_sub - 1::n_sub]
        rows[i:i + k] = picked[:, 1:16]
        steps += k * n_sub
        bad = _check(d, cbk, rows[i:i + k], picked[:, 0], t_out[i:i + k])
        if bad is not None:
            return rows[:, :7], rows[:, 7:13], rows[:, 13:], steps, i + bad[0], bad[1]
        x = st[0][-1].copy()
        i += k
    return rows[:, :7], rows[:, 7:13], rows[:, 13:], steps, None, None


_BAD = tuple(int(w) for w in (mujoco.mjtWarning.mjWARN_BADQPOS, mujoco.mjtWarning.mjWARN_BADQVEL,
                                mujoco.mjtWarning.mjWARN_BADQACC))


def _bad_warnings(d) -> int:
    w = d.warning
    return sum(int(w[i].number) for i in _BAD)


def simulate(params: dict, t_out: np.ndarray, settings: dict) -> LeafResult:
    """Spin-up on the output grid t_out (uniform, from 0) at fixed step ≤ dt dividing output_dt."""
    s = merge_settings(settings, DEFAULT_SETTINGS, INTEGRATORS)
    if s["callback"] not in CALLBACKS:
        raise ValueError(f"callback must be one of {CALLBACKS}, got {s['callback']!r}")
    if s["dt"] == "auto":    # the accurate default, or half the stability limit where smaller
        dt = min(DEFAULT_SETTINGS["dt"], 0.5 * _STABILITY[s["integrator"]]
                 / bc.stiffest_rate(params))
    else:
        try:
            dt = float(s["dt"])
        except (TypeError, ValueError):
            raise ValueError(f"dt must be a positive number or 'auto', got {s['dt']!r}") from None
        if not (math.isfinite(dt) and dt > 0):
            raise ValueError(f"dt must be a positive number or 'auto', got {s['dt']!r}")
    # the lock also covers the compile: MuJoCo calls the global passive callback while compiling
    with _LOCK:
        return _simulate(params, np.asarray(t_out, float), s, dt)


def _simulate(params: dict, t_out: np.ndarray, s: dict, dt: float) -> LeafResult:
    n_sub, h = bc.step_plan(t_out, dt)
    m, d = _build(params, s["integrator"], h)
    wall0 = time.perf_counter()
    with _Callback(s["callback"], d) as cbk:
        stepper = _by_rollout if cbk.kind == "native" else _by_output_step
        qpos, qvel, act, steps, i_bad, bad = stepper(m, d, t_out, n_sub, cbk)
        if bad is None and _bad_warnings(d):
            i_bad, bad = len(t_out) - 1, "MuJoCo reported a bad (NaN/huge) qpos/qvel/qacc"
        kind = cbk.kind
    status, t_fail, reason = "ok", None, None
    if bad is not None:
        status, t_fail, reason = "diverged", float(t_out[i_bad]), bad + bc.stability_note(params, h)
        qpos[i_bad:] = qvel[i_bad:] = act[i_bad:] = np.nan
    wall = time.perf_counter() - wall0
    used = {**s, "dt": h, "callback": kind}
    if abs(h - dt) > 1e-12 * dt:
        used["dt_requested"] = dt
    if kind != s["callback"]:
        used["callback_fallback_reason"] = _NATIVE["error"]
    stats = {"steps": steps, "rhs_evals": steps * _STAGES[s["integrator"]], "integrate_s": wall}
    quat = qpos[:, 3:7]
    rot = np.array([br.quat_matrix(q) if np.all(np.isfinite(q)) else np.full((3, 3), np.nan)
                    for q in quat])
    omega = np.einsum("nij,nj->ni", rot, qvel[:, 3:6])       # body → fixed frame
    return bc.result(params, t_out, qpos[:, 0:3], qvel[:, 0:3], quat, omega, act[:, 0],
                     act[:, 1], status, t_fail, reason, stats, used, h)


# ------------------------------------------------------------------ linearisation (xval modes)
# mjd_transitionFD under Euler: v' = v + h·a(q, v) with the callback's forces explicit, so
# ∂a/∂q = A21/h and ∂a/∂v = (A22 − I)/h exactly, for any h; h = 1e-2 keeps the spin root's
# round-off at 6e-8 (2.5e-7 at 1e-3). Centred differences at eps 1e-6 leave every whirl root
# within 1.3e-11 of the closed form (1e-4: the conical ones 2.1e-9 off, truncation).
FD_H, FD_EPS = 1e-2, 1e-6


def _linearised(params: dict, eps: float) -> np.ndarray:
    """A (12 × 12) about the steady spin in fixed-frame perturbations. The free joint's
    rotation tangent δ and velocity ω_b are body-frame; at q = 1 they equal the fixed-frame θ
    and δω, but the body turns at Ω e_z, so θ̇ = δω_b (δ̇ = −[Ω×]δ + δω_b, plus the turn of the
    frame) and d(R δω_b)/dt = ∂a/∂(q, v) + [Ω×] δω: the fixed-frame system is
    [[0, I], [∂a/∂q, ∂a/∂v + diag(0, [Ω×])]] (time-invariant: the shaft is axisymmetric)."""
    spin = br.steady_spin_rate(params)
    with _LOCK:
        m, d = _build({**params, "defect_height": 0.0}, "euler", FD_H)
        d.qpos[:3] = br.static_sag(params)
        d.qvel[:] = 0.0
        d.qvel[5] = spin
        A = np.zeros((2 * m.nv + m.na, 2 * m.nv + m.na))
        with _Callback("native", d) as cbk:
            mujoco.mjd_transitionFD(m, d, eps, True, A, None, None, None)
            if d.userdata[_U_FLAG] != 0.0 or not cbk.intact():
                raise RuntimeError("the passive callback failed during the linearisation")
    nv = m.nv
    turn = np.zeros((nv, nv))
    turn[3, 4], turn[4, 3] = -spin, spin
    return np.block([[np.zeros((nv, nv)), np.eye(nv)],
                     [A[nv:2 * nv, :nv] / FD_H, (A[nv:2 * nv, nv:2 * nv] - np.eye(nv)) / FD_H
                      + turn]])


def modes(params: dict, settings: dict | None = None):
    """Damped modes about the steady spin from MuJoCo's transition derivatives; error
    estimate: the linearisation at half the differentiation step."""
    return br.modes_result(_linearised(params, FD_EPS), _linearised(params, 0.5 * FD_EPS),
                           params, {"integrator": "euler", "dt": FD_H, "fd_eps": FD_EPS},
                           "mujoco mjd_transitionFD (centred) → continuous Jacobians, "
                           "body-frame rotation turned into the fixed frame")
