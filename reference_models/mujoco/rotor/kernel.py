"""The spring and damper moments, plain scalar Python that numba compiles for the native
callback; the shared `quat_matrix_t` gives the rotation.

The transverse spring is the isotropic cone-angle spring of the scene: with n = R e_z the body
axis and θ = ∠(n, e_z), it applies the spatial moment −kγ, γ = θ (e_z × n)/|e_z × n|, so
U = ½kθ² and nothing resists the spin. MuJoCo has no such element (its ball-joint stiffness also
resists spin), so the moment is added to `qfrc_passive` by a passive-force callback. Optional
model variant `settings["spring"] = "cardan"`: the Cardan spring k/2(α²+β²) of
R = Rx(α)Ry(β)Rz(φ) (a different spring at large tilt; the compare layer reports the deviation).
"""
import math

from compare.physics.rotation import quat_matrix_t

# the userdata layout (doubles in mjData.userdata, read and written by the callback)
(U_K, U_TORQUE, U_COS_PI, U_OMEGA2, U_FLAG, U_TFAIL, U_VARIANT, U_COS_CARDAN, U_CEXT,
 U_CINT, U_POISON) = range(11)
NUSERDATA = 11
# U_POISON ≠ 0 (the batch path, whose per-step userdata control clears the flag): a flagged
# stage also makes its passive force NaN, so the state (auto-reset is off) and every later row
# are NaN (a NaN work rate would not do: MuJoCo zeroes a bad ctrl)
PI_MARGIN = 1e-3             # stop when θ > π − this (the direction of −kγ is undefined at π)
CARDAN_MARGIN = 1e-3         # Cardan variant: stop when |cos β| < this (β → ±90°)
FLAG_REASONS = {
    1.0: "singular spring direction at tilt pi",
    2.0: "non-finite state",
    3.0: "angular velocity bound omega_max exceeded",
    4.0: "Cardan spring singular at beta = +-90 deg",
}


def damper_kernel(w, x, y, z, vx, vy, vz, omz, c_ext, c_int):
    """Body-frame damper moment. In body axes (ω_body = v, the shaft axis n = e_z, the fixed z
    axis b = Rᵀe_z): the external damper −c_ext (ω − (ω·n) n) opposes the axis' motion in the
    fixed frame; the internal one, −c_int (ω − ω_z b), is a damper between the rotor and a hub
    spinning with it about the fixed z axis (to first order the tilt rate seen in the rotor's
    frame)."""
    R = quat_matrix_t(w, x, y, z)
    bx, by, bz = R[6], R[7], R[8]
    return (-c_ext * vx - c_int * (vx - omz * bx), -c_ext * vy - c_int * (vy - omz * by),
            -c_int * (vz - omz * bz))


def spring_kernel(w, x, y, z, vx, vy, vz, k, variant, cos_pi, omega2, cos_cardan):
    """Body-frame spring moment (tbx, tby, tbz), spatial ω_z and a status flag (0 = fine)."""
    nq = w * w + x * x + y * y + z * z
    qv = vx * vx + vy * vy + vz * vz
    if not (nq > 0.0 and nq < 1e300 and qv <= omega2):
        if nq == nq and qv == qv and nq < 1e300 and qv < 1e300:
            return 0.0, 0.0, 0.0, 0.0, 3.0
        return 0.0, 0.0, 0.0, 0.0, 2.0
    # b = R^T e_z (third row of R): spatial ω_z = b·ω_body, cos θ = b_z
    r00, r01, r02, r10, r11, r12, bx, by, bz = quat_matrix_t(w, x, y, z)
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
    sb = min(1.0, max(-1.0, r02))
    cb = math.sqrt(max(0.0, 1.0 - sb * sb))
    if cb < cos_cardan:
        return 0.0, 0.0, 0.0, omz, 4.0
    beta = math.asin(sb)
    alpha = math.atan2(-r12, bz)
    ca = math.cos(alpha)
    sa = math.sin(alpha)
    # τ = (−kα (u2×u3) − kβ (u3×u1)) / cosβ, u2 = (0, ca, sa), u3 = n, u1 = e_x
    ga = -k * alpha / cb
    gb = -k * beta / cb
    tx = ga * (ca * bz - sa * r12)
    ty = ga * (sa * r02) + gb * bz
    tz = ga * (-ca * r02) - gb * r12
    return (r00 * tx + r10 * ty + bx * tz,
            r01 * tx + r11 * ty + by * tz,
            r02 * tx + r12 * ty + bz * tz, omz, 0.0)
