"""The tree's loads and work rates as compiled kernels, one call per stage for every rotor of a
tree.

Exudyn calls Python once per stage for the loads and once for the work rate; with plain Python
bodies those calls were the cost (10 s spin-up, RK67 at 2 ms: 570–620 ms of CPU on 2 busy
cores, of which the tree's own C++ is 61–79 ms, measured without any user function). Compiled
(numba) and taking every rotor of a tree at once: alone 286 ms; several rotors as branches of
one tree (`regimes`, the map's batch path) share each call — 111 ms a rotor at 8 per tree.
`EXUDYN_MODULE=fast` (Exudyn without range checks, chosen at import for the whole process) took
8 per tree from 120 to 101 ms (its numbers not compared); it is left to the user (an indexing
fault would then crash instead of raising).
Tried and not taken:
(a) the loads and the work rate as Exudyn symbolic user functions (C++ expression trees; the
work as the velocity of an extra ODE2 coordinate in an `ObjectGenericODE2` spanning the
tree's coordinates, the checks moved to a per-step post-step function): same numbers to all
digits but 478 ms against 392 ms at dt = 0.002 — the expression trees are interpreted;
(b) the fast module for one rotor alone: no difference in the noise; (c) the
tree's built-in joint springs (`jointPControlVector`) are C++ but are the Cardan spring
½k(α²+β²), a different model (|ω(10 s)| moves by 0.3 rad/s, see the notes); (d) one
`ObjectGenericODE2` carrying the loads of many single-rotor trees: its mass matrix cannot be
inverted per body, and the sparse solver it then needs costs more than it saves (155 ms a
rotor at 128).
"""
import math

import numba as nb

from .chart import CHART_LOCK, COS_TILT_LIMIT

OK, NONFINITE, TILT, LOCK = 0, 1, 2, 3
STOP_KINDS = {NONFINITE: "nonfinite", TILT: "tilt", LOCK: "chart"}


@nb.njit(cache=True)
def loads(q, qd, A, k, c_ext, c_int, torque, checks, out):
    """Generalised forces Jᵀτ, τ = −kγ + torque·e_z and the dampers c_ext, c_int, of every
    rotor i of a tree (coordinates 3i…3i+2, chart A[i]) into `out`; with `checks`, the first
    rotor whose stage state is non-finite, at tilt π or near its chart's lock stops it:
    returns (kind, i), else (0, -1). `work_rates` repeats the axes' z row on purpose: a work
    rate needs that row alone, once per stage."""
    for i in range(k.shape[0]):
        j = 3 * i
        a = A[i]
        ca, sa = math.cos(q[j]), math.sin(q[j])
        cb, sb = math.cos(q[j + 1]), math.sin(q[j + 1])
        # joint axes in the chart frame: e_x, Rx e_y, Rx Ry e_z = n; then rotated by A0
        j1x = a[0, 1] * ca + a[0, 2] * sa
        j1y = a[1, 1] * ca + a[1, 2] * sa
        j1z = a[2, 1] * ca + a[2, 2] * sa
        u0, u1, u2 = sb, -sa * cb, ca * cb
        nx = a[0, 0] * u0 + a[0, 1] * u1 + a[0, 2] * u2
        ny = a[1, 0] * u0 + a[1, 1] * u1 + a[1, 2] * u2
        nz = a[2, 0] * u0 + a[2, 1] * u1 + a[2, 2] * u2
        if checks:
            if not (math.isfinite(q[j] + q[j + 1] + q[j + 2])
                    and math.isfinite(qd[j] + qd[j + 1] + qd[j + 2])):
                return NONFINITE, i
            if nz < COS_TILT_LIMIT:
                return TILT, i
            if abs(cb) < CHART_LOCK:                    # hard guard inside a stage
                return LOCK, i
        s = math.sqrt(nx * nx + ny * ny)
        th = math.atan2(s, nz)
        f = th / s if s > 1e-6 else 1.0 + th * th / 6.0    # θ/sinθ, no 0/0 at θ = 0
        # τ = −k·θ/sinθ·(e_z × n) + torque·e_z
        tx = k[i] * f * ny
        ty = -k[i] * f * nx
        tz = torque[i]
        if c_ext[i] != 0.0 or c_int[i] != 0.0:
            # ω = J q̇; external damper: −c_ext (ω − (ω·n) n) = −c_ext n × ṅ, against the axis'
            # motion in the fixed frame; internal: a damper between the rotor and a hub spinning
            # with it about the fixed z axis, −c_int (ω_x, ω_y, 0) (to first order the tilt
            # rate seen in the rotor's frame, θ̇ − iΩθ)
            wx = a[0, 0] * qd[j] + j1x * qd[j + 1] + nx * qd[j + 2]
            wy = a[1, 0] * qd[j] + j1y * qd[j + 1] + ny * qd[j + 2]
            wz = a[2, 0] * qd[j] + j1z * qd[j + 1] + nz * qd[j + 2]
            wn = wx * nx + wy * ny + wz * nz
            tx -= c_ext[i] * (wx - wn * nx) + c_int[i] * wx
            ty -= c_ext[i] * (wy - wn * ny) + c_int[i] * wy
            tz -= c_ext[i] * (wz - wn * nz)
        out[j] = tx * a[0, 0] + ty * a[1, 0] + tz * a[2, 0]
        out[j + 1] = tx * j1x + ty * j1y + tz * j1z
        out[j + 2] = tx * nx + ty * ny + tz * nz
    return OK, -1


@nb.njit(cache=True)
def work_rates(q, qd, A, torque, out):
    """torque·ω_z of every rotor of a tree: ω_z = (J q̇)_z at the stage state."""
    for i in range(torque.shape[0]):
        j = 3 * i
        a = A[i]
        ca, sa = math.cos(q[j]), math.sin(q[j])
        cb, sb = math.cos(q[j + 1]), math.sin(q[j + 1])
        j1z = a[2, 1] * ca + a[2, 2] * sa
        nz = a[2, 0] * sb - a[2, 1] * sa * cb + a[2, 2] * ca * cb
        out[i] = torque[i] * (a[2, 0] * qd[j] + j1z * qd[j + 1] + nz * qd[j + 2])
