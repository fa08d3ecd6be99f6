"""Two-bearing rotor with a bearing defect (scene `bearing-rotor`, seed 001): the ONE
implementation of the force laws, the spin angle and every observable. Numpy + numba only.

Frames and conventions (every solver of the scene uses these):
- fixed frame: bearings centred on the z axis at z = +l/2 (a) and z = −l/2 (b);
- body frame: shaft axis e3 = body z, journal a at body z = +l/2, b at −l/2, centre of mass at 0;
- quaternions are (w, x, y, z) and rotate body vectors into the fixed frame;
- angular velocity `omega` is given in the FIXED frame; the spin rate is ω_z = ω·e3 with
  e3 = R·(0, 0, 1) the shaft axis in the fixed frame; motor and friction moments act about e3.

Force laws (spec scene-bearing-rotor.md):
- radial bearing force at j ∈ {a, b}: F_j = −k_b (δ_j − d_j) − c_b δ̇_j, δ_j the (x, y) offset
  of the journal point from its bearing centre; axial spring −k_axial (z_a − l/2) on journal a;
- defect lift d_a = h(x)·(−ĝ), ĝ the unit projection of gravity on the bearing (x, y) plane
  (−y when gravity has no radial part, so the defect stays defined), x the wrapped angle between
  the bump (body angle defect_angle + twist) and ĝ, h(x) = H (1 − (x/w)²)² for |x| < w; d_b = 0;
- motor M_F = stall (1 − ω_z/ω_0); friction −(drag ω_z + μ r_j (|F_a| + |F_b|) tanh(ω_z/0.1)),
  |F_j| the norm of the full radial force (spring with lift + damper).

Energy balance E = T + V_g + V_b − W_motor + D, constant in time, with V_g = −m g·r_cm,
V_b = ½k_b|δ_a − d_a|² + ½k_b|δ_b|² + ½k_axial (z_a − l/2)², Ẇ_motor = M_F ω_z and
Ḋ = c_b(|δ̇_a|² + |δ̇_b|²) − M_friction ω_z + k_b (δ_a − d_a)·ḋ_a.
The last term is the work of the prescribed lift: the bump moves the spring's anchor but the
force law puts no reaction moment on the shaft, so the lift is not conservative; its work is
booked in D ("dissipated" = dampers + friction + defect lift) so the balance closes exactly
(D need not grow monotonically: the lift can feed energy in).

For solvers: every one starts from `initial_state` (defect-free static sag, unrotated, at rest,
unless the scene's initial-condition parameters say otherwise);
`body_loads` gives everything but gravity reduced to the centre of mass plus Ẇ_motor and Ḋ,
which each solver integrates along with its state; `channels` turns the common kinematic output
into the scene's channels.
"""
from __future__ import annotations

import numba as nb
import numpy as np

from ..contract import LeafModes
from .rotation import quat_matrix, quat_matrix_t  # noqa: F401  (the leaves' too)

OMEGA_SMOOTH = 0.1     # rad/s, the tanh width of the friction moment's sign (spec)

# Layout of the packed parameter array (pack()).
I_M, I_L, I_JT, I_JP = 0, 1, 2, 3
I_KB, I_CB, I_KAX = 4, 5, 6
I_GX, I_GY, I_GZ = 7, 8, 9
I_H, I_W, I_ANG = 10, 11, 12          # defect height, half width (rad), body angle
I_STALL, I_NOLOAD = 13, 14
I_DRAG, I_MU, I_RJ = 15, 16, 17
I_LX, I_LY, I_LANG = 18, 19, 20       # loaded direction ĝ (unit, x-y plane) and its angle
N_PACK = 21


def pack(params: dict) -> np.ndarray:
    """The scene's resolved parameters as a float64 array for the numba kernels."""
    g = np.asarray(params["gravity"], float)
    g_radial = np.hypot(g[0], g[1])
    ld = g[:2] / g_radial if g_radial > 0 else np.array([0.0, -1.0])
    p = np.zeros(N_PACK)
    p[I_M], p[I_L], p[I_JT], p[I_JP] = params["m"], params["l"], params["J_t"], params["J_p"]
    p[I_KB], p[I_CB], p[I_KAX] = params["k_b"], params["c_b"], params["k_axial"]
    p[I_GX], p[I_GY], p[I_GZ] = g
    p[I_H], p[I_W], p[I_ANG] = (params["defect_height"], params["defect_width"],
                                params["defect_angle"])
    p[I_STALL], p[I_NOLOAD] = params["motor_stall_torque"], params["motor_no_load_speed"]
    p[I_DRAG], p[I_MU], p[I_RJ] = params["bearing_drag"], params["mu"], params["r_j"]
    p[I_LX], p[I_LY], p[I_LANG] = ld[0], ld[1], np.arctan2(ld[1], ld[0])
    return p


# ---------------------------------------------------------------- rotation and spin angle
@nb.njit(cache=True)
def cross(a, b):
    """a × b for 3-vectors (np.cross is several times slower inside numba kernels)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


@nb.njit(cache=True)
def dot(a, b):
    """a·b by a loop (np.dot / @ call BLAS from numba: ~1 µs of overhead per call)."""
    acc = 0.0
    for i in range(a.shape[0]):
        acc += a[i] * b[i]
    return acc


@nb.njit(cache=True)
def transpose_times(R, v):
    """Rᵀ v for a 3×3 R."""
    return np.array([R[0, 0] * v[0] + R[1, 0] * v[1] + R[2, 0] * v[2],
                     R[0, 1] * v[0] + R[1, 1] * v[1] + R[2, 1] * v[2],
                     R[0, 2] * v[0] + R[1, 2] * v[1] + R[2, 2] * v[2]])


@nb.njit(cache=True)
def wrap(a):
    """Angle wrapped into [−π, π)."""
    return (a + np.pi) % (2.0 * np.pi) - np.pi


@nb.njit(cache=True)
def twist_of(w, z) -> float:
    """Twist about the body z axis of the swing–twist split q = q_swing ⊗ q_twist (wrapped),
    from q's w and z.

    With q_twist = (cos φ/2, 0, 0, sin φ/2) and a swing without z part, the product has
    w = c·cos φ/2 and z = c·sin φ/2, so φ = 2 atan2(z, w) for any norm and sign of q."""
    return wrap(2.0 * np.arctan2(z, w))


@nb.njit(cache=True)
def twist_angle(q) -> float:
    """twist_of a quaternion array (w, x, y, z)."""
    return twist_of(q[0], q[3])


@nb.njit(cache=True)
def twist_rate_t(w, x, y, z, ox, oy, oz):
    """dφ/dt of twist_angle for q' = ½ (0, ω) ⊗ q, ω in the fixed frame (scalars)."""
    dw = -0.5 * (ox * x + oy * y + oz * z)
    dz = 0.5 * (w * oz + ox * y - oy * x)
    return 2.0 * (w * dz - z * dw) / (w * w + z * z)


@nb.njit(cache=True)
def twist_rate(q, omega):
    """twist_rate_t of a quaternion array and a fixed-frame ω array."""
    return twist_rate_t(q[0], q[1], q[2], q[3], omega[0], omega[1], omega[2])


@nb.njit(cache=True)
def _twists(quats):
    out = np.empty(quats.shape[0])
    for i in range(quats.shape[0]):
        out[i] = twist_of(quats[i, 0], quats[i, 3])
    return out


@nb.njit(cache=True)
def _unwrap_by_rate(phi, t, rate):
    """The 2π branch of each angle nearest the trapezoidal prediction from the previous one."""
    out = np.empty_like(phi)
    out[0] = phi[0]
    for i in range(1, phi.shape[0]):
        pred = out[i - 1] + 0.5 * (rate[i] + rate[i - 1]) * (t[i] - t[i - 1])
        out[i] = phi[i] + 2.0 * np.pi * np.rint((pred - phi[i]) / (2.0 * np.pi))
    return out


def spin_angle(quats: np.ndarray, t: np.ndarray | None = None,
               spin_rate: np.ndarray | None = None) -> np.ndarray:
    """Unwrapped spin angle of a quaternion series (n, 4).

    Without rates, consecutive samples must differ by less than π (np.unwrap). With `t` and
    `spin_rate` the 2π branch is the one nearest the trapezoidal prediction, so a coarse output
    grid (many radians per sample) still unwraps correctly."""
    phi = _twists(np.ascontiguousarray(quats, float).reshape(-1, 4))
    if t is None or spin_rate is None:
        return np.unwrap(phi)
    f = np.ascontiguousarray
    return _unwrap_by_rate(phi, f(t, float), f(spin_rate, float))


# ---------------------------------------------------------------- force laws
@nb.njit(cache=True)
def defect_lift(twist, p) -> float:
    """h(x) of the journal-a defect, x the wrapped angle from ĝ to the bump."""
    u = wrap(p[I_ANG] + twist - p[I_LANG]) / p[I_W]
    if abs(u) >= 1.0:
        return 0.0
    s = 1.0 - u * u
    return p[I_H] * s * s


@nb.njit(cache=True)
def defect_lift_slope(twist, p) -> float:
    """dh/dx at the bump's current angle (for the lift's work, ḋ_a = h'(x)·φ̇·(−ĝ))."""
    u = wrap(p[I_ANG] + twist - p[I_LANG]) / p[I_W]
    if abs(u) >= 1.0:
        return 0.0
    return -4.0 * p[I_H] * u * (1.0 - u * u) / p[I_W]


@nb.njit(cache=True)
def shaft_torques(omega_z, Fa_radial_norm, Fb_radial_norm, p):
    """(motor, friction) moments about the shaft axis e3."""
    motor = p[I_STALL] * (1.0 - omega_z / p[I_NOLOAD])
    friction = -(p[I_DRAG] * omega_z + p[I_MU] * p[I_RJ] * (Fa_radial_norm + Fb_radial_norm)
                 * np.tanh(omega_z / OMEGA_SMOOTH))
    return motor, friction


@nb.njit(cache=True)
def journals(r_cm, v_cm, R, omega, p):
    """Positions and velocities (fixed frame) of journals a (+l/2 e3) and b (−l/2 e3)."""
    arm = 0.5 * p[I_L] * R[:, 2]
    w_arm = cross(omega, arm)
    return r_cm + arm, v_cm + w_arm, r_cm - arm, v_cm - w_arm


@nb.njit(cache=True)
def loads_t(rx, ry, rz, qw, qx, qy, qz, vx, vy, vz, wx, wy, wz, p):
    """Everything but gravity acting on the shaft, reduced to the centre of mass (fixed frame),
    from the centre's position r and velocity v, the orientation q (w, x, y, z; any norm) and
    the fixed-frame ω, as scalars: (F_x, F_y, F_z, M_x, M_y, M_z, Ẇ_motor, Ḋ).

    The one implementation of the force laws (module docstring); scalar code that allocates
    nothing, because every solver evaluates it once per right-hand side (the engines through
    `body_loads`)."""
    s = 1.0 / (qw * qw + qx * qx + qy * qy + qz * qz)
    ex = 2 * s * (qx * qz + qw * qy)                 # e3 = R(q)·(0, 0, 1), the shaft axis
    ey = 2 * s * (qy * qz - qw * qx)
    ez = 1 - 2 * s * (qx * qx + qy * qy)
    half = 0.5 * p[I_L]
    ax, ay, az = half * ex, half * ey, half * ez    # arm from the centre to journal a
    ux, uy = wy * az - wz * ay, wz * ax - wx * az    # (ω × arm)_x,y: journal velocity about r
    phi = twist_of(qw, qz)
    h = defect_lift(phi, p)
    k, c, lx, ly = p[I_KB], p[I_CB], p[I_LX], p[I_LY]
    # radial spring–dampers (d_a = −h ĝ at a) and the axial spring on journal a's z
    sax, say = rx + ax + h * lx, ry + ay + h * ly    # δ_a − d_a
    vax, vay, vbx, vby = vx + ux, vy + uy, vx - ux, vy - uy
    fax, fay = -k * sax - c * vax, -k * say - c * vay
    faz = -p[I_KAX] * (rz + az - half)
    fbx, fby = -k * (rx - ax) - c * vbx, -k * (ry - ay) - c * vby
    w_z = wx * ex + wy * ey + wz * ez
    motor, friction = shaft_torques(w_z, np.sqrt(fax * fax + fay * fay),
                                    np.sqrt(fbx * fbx + fby * fby), p)
    tq = motor + friction
    # moment: arm × F_a + (−arm) × F_b (F_b has no z part) + the shaft torques about e3
    mx = ay * faz - az * fay + az * fby + tq * ex
    my = az * fax - ax * faz - az * fbx + tq * ey
    mz = ax * fay - ay * fax - (ax * fby - ay * fbx) + tq * ez
    # Ḋ: dampers + friction + the lift's work k_b (δ_a − d_a)·ḋ_a (see module docstring)
    dh = defect_lift_slope(phi, p) * twist_rate_t(qw, qx, qy, qz, wx, wy, wz)
    lift_power = -k * (sax * lx + say * ly) * dh
    damp = c * (vax * vax + vay * vay + vbx * vbx + vby * vby)
    return (fax + fbx, fay + fby, faz, mx, my, mz, motor * w_z,
            damp - friction * w_z + lift_power)


@nb.njit(cache=True)
def body_loads(r_cm, q, v_cm, omega, p):
    """`loads_t` for arrays (the engines' call): (force (3,), moment (3,), motor power Ẇ,
    dissipation power Ḋ). ω in the fixed frame."""
    L = loads_t(r_cm[0], r_cm[1], r_cm[2], q[0], q[1], q[2], q[3], v_cm[0], v_cm[1], v_cm[2],
                omega[0], omega[1], omega[2], p)
    force = np.empty(3)
    moment = np.empty(3)
    for i in range(3):
        force[i] = L[i]
        moment[i] = L[3 + i]
    return force, moment, L[6], L[7]


def powers(r_cm, q, v_cm, omega, p):
    """(Ẇ_motor, Ḋ) — the integrands of the work channels (see body_loads)."""
    return loads_t(*r_cm, *q, *v_cm, *omega, p)[6:]


# ---------------------------------------------------------------- energy
@nb.njit(cache=True)
def kinetic_energy(v_cm, omega, R, p) -> float:
    """½ m |v|² + ½ ω·(R J Rᵀ)ω, ω in the fixed frame."""
    wb = transpose_times(R, omega)
    return 0.5 * p[I_M] * dot(v_cm, v_cm) + 0.5 * (p[I_JT] * (wb[0] ** 2 + wb[1] ** 2)
                                                 + p[I_JP] * wb[2] ** 2)


@nb.njit(cache=True)
def gravity_potential(r_cm, p) -> float:
    return -p[I_M] * (p[I_GX] * r_cm[0] + p[I_GY] * r_cm[1] + p[I_GZ] * r_cm[2])


@nb.njit(cache=True)
def bearing_potential(r_a, r_b, twist, p) -> float:
    """½k_b|δ_a − d_a|² + ½k_b|δ_b|² + ½k_axial (z_a − l/2)²."""
    h = defect_lift(twist, p)
    ax, ay = r_a[0] + h * p[I_LX], r_a[1] + h * p[I_LY]
    za = r_a[2] - 0.5 * p[I_L]
    return 0.5 * p[I_KB] * (ax * ax + ay * ay + r_b[0] ** 2 + r_b[1] ** 2) \
        + 0.5 * p[I_KAX] * za * za


# ---------------------------------------------------------------- observables
@nb.njit(cache=True)
def _observables(r_cm, v_cm, quats, omega, p):
    n = r_cm.shape[0]
    out = np.empty((n, 9))   # spin_rate, twist, a_x, a_y, b_x, b_y, kinetic, V_g, V_b
    for i in range(n):
        R = quat_matrix(quats[i])
        r_a, _, r_b, _ = journals(r_cm[i], v_cm[i], R, omega[i], p)
        phi = twist_angle(quats[i])
        out[i, 0] = omega[i, 0] * R[0, 2] + omega[i, 1] * R[1, 2] + omega[i, 2] * R[2, 2]
        out[i, 1] = phi
        out[i, 2], out[i, 3], out[i, 4], out[i, 5] = r_a[0], r_a[1], r_b[0], r_b[1]
        out[i, 6] = kinetic_energy(v_cm[i], omega[i], R, p)
        out[i, 7] = gravity_potential(r_cm[i], p)
        out[i, 8] = bearing_potential(r_a, r_b, phi, p)
    return out


def channels(params: dict, t: np.ndarray, r_cm: np.ndarray, v_cm: np.ndarray,
             quats: np.ndarray, omega: np.ndarray, motor_work: np.ndarray,
             dissipated: np.ndarray) -> dict:
    """The scene's channels from a solver's kinematic output on the grid t: centre of mass
    position/velocity (n, 3), quaternions (n, 4) w, x, y, z, angular velocity (n, 3) in the
    FIXED frame, and the integrated motor work and dissipated work (n,) (Ẇ, Ḋ from `powers`)."""
    p = pack(params)
    f = np.ascontiguousarray
    o = _observables(f(r_cm, float), f(v_cm, float), f(quats, float), f(omega, float), p)
    motor_work = np.asarray(motor_work, float)
    dissipated = np.asarray(dissipated, float)
    potential = o[:, 7] + o[:, 8]
    return {"spin_rate": o[:, 0],
            "spin_angle": spin_angle(quats, t, o[:, 0]),
            "journal_a_x": o[:, 2], "journal_a_y": o[:, 3],
            "journal_b_x": o[:, 4], "journal_b_y": o[:, 5],
            "kinetic": o[:, 6], "potential": potential,
            "motor_work": motor_work, "dissipated": dissipated,
            "energy_balance": o[:, 6] + potential - motor_work + dissipated}


@nb.njit(cache=True)
def _axes(quats):
    """Shaft axis e3 = R(q)·(0, 0, 1) per row (n, 3)."""
    out = np.empty((quats.shape[0], 3))
    for i in range(quats.shape[0]):
        R = quat_matrix_t(quats[i, 0], quats[i, 1], quats[i, 2], quats[i, 3])
        out[i, 0], out[i, 1], out[i, 2] = R[2], R[5], R[8]
    return out


def journal_positions(params: dict, r_cm: np.ndarray, quats: np.ndarray):
    """(n, 3) positions of journals a and b (for the 3D recording)."""
    half = 0.5 * float(params["l"])
    axes = _axes(np.ascontiguousarray(quats, float).reshape(-1, 4))
    return r_cm + half * axes, r_cm - half * axes


# ---------------------------------------------------------------- closed forms, start
def static_sag(params: dict) -> np.ndarray:
    """Offset (3,) of each journal (and the centre of mass) from its bearing centre at rest
    without the defect: radial m g/(2 k_b) per journal, axial m g_z / k_axial (journal a's
    spring carries the whole axial load)."""
    g = np.asarray(params["gravity"], float)
    m = params["m"]
    return np.array([m * g[0] / (2 * params["k_b"]), m * g[1] / (2 * params["k_b"]),
                     m * g[2] / params["k_axial"]])


def initial_state(params: dict):
    """The common start: (r_cm, q, v_cm, ω) — the defect-free static sag shifted by `offset0`,
    turned by `tilt0` about the fixed x axis, spinning at `spin0` about the shaft axis (all
    zero by default: at the sag, unrotated, at rest; a ring-down starts at the steady spin)."""
    tilt, spin = float(params["tilt0"]), float(params["spin0"])
    q = np.array([np.cos(0.5 * tilt), np.sin(0.5 * tilt), 0.0, 0.0])
    axis = np.array([0.0, -np.sin(tilt), np.cos(tilt)])          # R(q)·(0, 0, 1)
    return (static_sag(params) + np.asarray(params["offset0"], float), q, np.zeros(3),
            spin * axis)


def steady_spin_rate(params: dict) -> float:
    """Spin rate of the defect-free shaft where motor and friction balance (|F_a| + |F_b| =
    m |g_radial| at rest in the bearings), by bisection."""
    g = np.asarray(params["gravity"], float)
    load = params["m"] * np.hypot(g[0], g[1])

    def net(w):
        return (params["motor_stall_torque"] * (1 - w / params["motor_no_load_speed"])
                - params["bearing_drag"] * w
                - params["mu"] * params["r_j"] * load * np.tanh(w / OMEGA_SMOOTH))

    lo, hi = 0.0, abs(params["motor_no_load_speed"])
    if net(lo) * net(hi) > 0:
        return 0.0 if net(lo) <= 0 else hi
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if net(lo) * net(mid) > 0 else (lo, mid)
    return 0.5 * (lo + hi)


# ---------------------------------------------------------------- linearisation about the spin
# Small motions about the steady spin Ω = steady_spin_rate (the defect-free shaft at its static
# sag; the defect is a periodic forcing, not part of the linear system), in the fixed frame:
# centre offset (x, y, z) from the sag, tilt (θx, θy) (rotation vector of the shaft axis,
# e3 ≈ (θy, −θx, 1)), spin-angle perturbation θz. The state of every solver's first-order
# linearisation is ordered (x, y, z, θx, θy, θz, then six velocities of any kind); whirl is
# counted about +z, the motor's sense (Ω ≥ 0 at the balance).
WHIRL_TYPES = ("cylindrical", "conical", "axial")
DEGENERATE = 1e-8       # relative gap below which two roots of one type are one repeated root


def modal_closed_form(params: dict) -> dict:
    """The damped modes about the steady spin in closed form: label -> (λ, whirl), λ the
    complex root (1/s) with Im λ = the damped frequency ≥ 0; plus "spin" -> (λ, "—"), the real
    root of the spin rate. Derivation (journals at ±(l/2)e3 in isotropic bearings k_b, c_b):

    - cylindrical (x, y): m ẍ + 2c_b ẋ + 2k_b x = 0, so ω_n = √(2k_b/m), ζ = 2c_b/(2√(2k_b m)),
      ω_d = ω_n√(1 − ζ²), forward and backward alike (no gyroscopic term on translation);
    - axial: m z̈ + k_axial z = 0 (no axial damper): ω = √(k_axial/m), ζ = 0;
    - conical: the journals move by ±(l/2)(θy, −θx), so the bearings give a tilt stiffness
      k_θ = k_b l²/2 and damping c_θ = c_b l²/2; with H ≈ J_t(θ̇x, θ̇y, 0) + J_p Ω e3,
      J_t θ̈x + J_p Ω θ̇y + c_θ θ̇x + k_θ θx = 0, J_t θ̈y − J_p Ω θ̇x + c_θ θ̇y + k_θ θy = 0,
      i.e. for φ = θx + iθy ∝ e^{st}: J_t s² + (c_θ − i J_p Ω) s + k_θ = 0. Its root with
      Im s > 0 whirls forward (with the spin), the other backward (ω_d = |Im s|,
      ζ = −Re s/|s|); at Ω = 0 both are ω = √(k_b l²/(2J_t)) damped by ζ = c_θ/(2√(k_θ J_t));
    - spin: J_p δΩ̇ = −(M_stall/ω_0 + c_drag + μ r_j m|g_xy| sech²(Ω/0.1)/0.1) δΩ (motor and
      friction slopes; the friction's dependence on the bearing loads feeds the lateral motion
      into the spin, but nothing feeds back: block-triangular, the roots above stand)."""
    m, l, jt, jp = params["m"], params["l"], params["J_t"], params["J_p"]
    kb, cb = params["k_b"], params["c_b"]
    spin = steady_spin_rate(params)
    zc, wn = cb / np.sqrt(2 * kb * m), np.sqrt(2 * kb / m)
    cyl = complex(-zc * wn, wn * np.sqrt(1 - zc * zc)) if zc < 1 else complex(-zc * wn, 0.0)
    s = np.roots([jt, 0.5 * cb * l * l - 1j * jp * spin, 0.5 * kb * l * l])
    fwd, bwd = sorted(s, key=lambda r: -r.imag)
    g = np.asarray(params["gravity"], float)
    slope = (params["motor_stall_torque"] / params["motor_no_load_speed"]
             + params["bearing_drag"] + params["mu"] * params["r_j"] * m * np.hypot(g[0], g[1])
             * (1.0 - np.tanh(spin / OMEGA_SMOOTH) ** 2) / OMEGA_SMOOTH)
    return {"cylindrical backward": (cyl, "backward"), "cylindrical forward": (cyl, "forward"),
            "axial": (complex(0.0, np.sqrt(params["k_axial"] / m)), "—"),
            "conical backward": (complex(bwd.real, -bwd.imag), "backward"),
            "conical forward": (complex(fwd), "forward"),
            "spin": (complex(-slope / jp, 0.0), "—")}


def _circular(v, kind, half):
    """(forward, backward) amplitudes of a mode's orbit: the whirling point's complex offset
    u = x + iy = ½(x̂ + iŷ)e^{iωt} + ½(x̂* + iŷ*)e^{−iωt} for Re(v e^{iωt})."""
    x, y = (v[0], v[1]) if kind == "cylindrical" else (half * v[4], -half * v[3])
    return abs(x + 1j * y), abs(x - 1j * y)


def linear_modes(A: np.ndarray, params: dict) -> tuple[list[dict], np.ndarray]:
    """The oscillatory modes of ẋ = A x (the state ordered as above), each a dict: label,
    λ (Im λ > 0), whirl ("forward", "backward", "mixed" as ROSS names them; "—" for the axial
    mode), in ascending damped frequency; and the nonzero real roots (the spin rate's). A
    mode's kind is the largest journal motion of its shape: centre (x, y), tilt
    (l/2)(θx, θy), or z. Two roots of one kind within DEGENERATE of each other are a repeated
    root (an isotropic rotor's translation at any spin, its tilt at rest): their eigenspace
    holds one forward and one backward circular whirl, reported as that pair at their mean."""
    lam, V = np.linalg.eig(np.asarray(A, float))
    tiny = 1e-9 * float(np.max(np.abs(lam)))
    half = 0.5 * params["l"]
    shapes = []                                   # (kind, λ, positions of the shape)
    for i in np.nonzero(lam.imag > tiny)[0]:
        v = V[:6, i]
        motion = (np.hypot(abs(v[0]), abs(v[1])), half * np.hypot(abs(v[3]), abs(v[4])),
                  abs(v[2]))
        shapes.append((WHIRL_TYPES[int(np.argmax(motion))], complex(lam[i]), v))
    out = []
    for kind in WHIRL_TYPES:
        mine = sorted((m for m in shapes if m[0] == kind), key=lambda m: m[1].imag)
        if kind == "axial":
            out += [{"label": "axial" if len(mine) == 1 else f"axial {j + 1}", "lam": m[1],
                     "whirl": "—"} for j, m in enumerate(mine)]
            continue
        j = 0
        while j < len(mine):
            (_, a, v), b = mine[j], mine[j + 1][1] if j + 1 < len(mine) else None
            if b is not None and abs(b - a) <= DEGENERATE * abs(a):
                out += [{"label": f"{kind} {w.lower()}", "lam": 0.5 * (a + b), "whirl": w}
                        for w in ("backward", "forward")]
                j += 2
                continue
            f, bw = _circular(v, kind, half)
            whirl = ("mixed" if abs(f - bw) <= 0.01 * (f + bw) else
                     "forward" if f > bw else "backward")
            out.append({"label": f"{kind} {whirl.lower()}", "lam": a, "whirl": whirl})
            j += 1
    out.sort(key=lambda m: (m["lam"].imag, m["whirl"] != "backward"))
    real = lam.real[(np.abs(lam.imag) <= tiny) & (np.abs(lam) > tiny)]
    return out, np.sort(real)


def modes_result(A: np.ndarray, A_check: np.ndarray, params: dict, settings: dict,
                 how: str) -> LeafModes:
    """A solver's `LeafModes` from its linearisation A and a second one, A_check, at half its
    finite-difference step: damped frequencies (Hz), ζ, labels, whirl, and as each mode's error
    estimate |Δ| between the two (extra "frequency_error_hz", "damping_error"); the real roots
    (the spin rate's) in extra "real_roots_per_s". `how` says how A was made."""
    modes, real = linear_modes(A, params)
    other = {m["label"]: m["lam"] for m in linear_modes(A_check, params)[0]}

    def zeta(lam):
        return -lam.real / abs(lam)

    def error(fn, m):
        return abs(fn(m["lam"]) - fn(other[m["label"]])) if m["label"] in other else np.inf
    return LeafModes(
        frequencies_hz=np.array([m["lam"].imag for m in modes]) / (2 * np.pi),
        labels=[m["label"] for m in modes], damping=np.array([zeta(m["lam"]) for m in modes]),
        whirl=[m["whirl"] for m in modes], settings={**settings, "linearisation": how},
        notes=[f"about the steady spin {steady_spin_rate(params):.10g} rad/s (motor/friction "
               "balance), defect-free static sag"],
        extra={"frequency_error_hz": np.array([error(lambda x: x.imag / (2 * np.pi), m)
                                               for m in modes]),
               "damping_error": np.array([error(zeta, m) for m in modes]),
               "real_roots_per_s": real})
