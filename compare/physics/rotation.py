"""Rotation math shared by the models of every solver (numba-compiled, plain arrays).

Euler-vector tensors follow the paper (seed 000) and Zhilin's notation:
    L(θ) = E cos θ + (1 − cos θ) θ⊗θ/θ² + (sin θ/θ) θ×E        rotation tensor
    Z(θ) = E sin θ/θ + (1 − sin θ/θ) θ⊗θ/θ² + ((1 − cos θ)/θ²) θ×E,   ω = Z(θ)·θ̇
written here in the equivalent Rodrigues form E + a θ× + b (θ×)², with series near θ = 0 so no
0/0 is ever formed. Quaternions are (w, x, y, z) and rotate body vectors into the fixed frame.
"""
import math

import numba as nb
import numpy as np

from .trig import atan2, sincos, tuple_math

_SMALL = 1e-4   # below this |θ| the coefficient series are exact to round-off


@nb.njit(cache=True)
def skew(v):
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


@tuple_math
def _coefficients(t):
    """a = sin t/t, b = (1 − cos t)/t², c = (1 − a)/t², d = (1 − a/(2b))/t²."""
    t2 = t * t
    if t < _SMALL:
        return (1.0 - t2 / 6.0, 0.5 - t2 / 24.0, 1.0 / 6.0 - t2 / 120.0, 1.0 / 12.0 + t2 / 720.0)
    sn, cs = sincos(t)
    a = sn / t
    b = (1.0 - cs) / t2
    return a, b, (1.0 - a) / t2, (1.0 - a / (2.0 * b)) / t2


@nb.njit(cache=True)
def _rodrigues(t, c1, c2):
    """E + c1·θ× + c2·(θ×)², built in place using (θ×)² = θ⊗θ − |θ|²E (one allocation)."""
    t2 = t @ t
    out = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            out[i, j] = c2 * t[i] * t[j]
        out[i, i] += 1.0 - c2 * t2
    out[0, 1] -= c1 * t[2]
    out[1, 0] += c1 * t[2]
    out[0, 2] += c1 * t[1]
    out[2, 0] -= c1 * t[1]
    out[1, 2] -= c1 * t[0]
    out[2, 1] += c1 * t[0]
    return out


@nb.njit(cache=True)
def axis_rotation(s, a):
    """Rotation by a about the unit axis s: (1 − cos a) s⊗s + cos a E + sin a s× (Rodrigues)."""
    c, sn = math.cos(a), math.sin(a)
    R = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            R[i, j] = (1 - c) * s[i] * s[j] + (c if i == j else 0.0)
    R[0, 1] -= sn * s[2]
    R[0, 2] += sn * s[1]
    R[1, 0] += sn * s[2]
    R[1, 2] -= sn * s[0]
    R[2, 0] -= sn * s[1]
    R[2, 1] += sn * s[0]
    return R


@nb.njit(cache=True)
def rotation_tensor(theta):
    """L(θ) of an Euler (rotation) vector θ."""
    a, b, _, _ = _coefficients(np.sqrt(theta @ theta))
    return _rodrigues(theta, a, b)


@nb.njit(cache=True)
def zhilin(theta):
    """Z(θ) with ω = Z(θ)·θ̇ (ω in the fixed frame)."""
    _, b, c, _ = _coefficients(np.sqrt(theta @ theta))
    return _rodrigues(theta, b, c)


@nb.njit(cache=True)
def zhilin_inverse(theta):
    """Z⁻¹(θ) = E − ½θ× + (1 − (θ/2)cot(θ/2))/θ² (θ×)²; singular at |θ| = 2π."""
    _, _, _, d = _coefficients(np.sqrt(theta @ theta))
    return _rodrigues(theta, -0.5, d)


@nb.njit(cache=True)
def rotation_z(phi):
    s, c = sincos(phi)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


@nb.njit(cache=True)
def quat_times_vector(q, v):
    """q ⊗ (0, v): the kinematic product of q' = ½ q ⊗ (0, ω_body)."""
    return np.array(quat_times_vector_t(q[0], q[1], q[2], q[3], v[0], v[1], v[2]))


@nb.njit(cache=True)
def quat_times_vector_t(w, x, y, z, v0, v1, v2):
    """`quat_times_vector` as a 4-tuple."""
    return (-x * v0 - y * v1 - z * v2, w * v0 + y * v2 - z * v1, w * v1 + z * v0 - x * v2,
            w * v2 + x * v1 - y * v0)


@nb.njit(cache=True)
def matrix_to_quat(R):
    """Unit quaternion (w ≥ 0) of a rotation matrix (Shepperd's branch choice)."""
    tr = R[0, 0] + R[1, 1] + R[2, 2]
    if tr > max(R[0, 0], R[1, 1], R[2, 2]):
        w = 0.5 * np.sqrt(1.0 + tr)
        q = np.array([w, (R[2, 1] - R[1, 2]) / (4 * w), (R[0, 2] - R[2, 0]) / (4 * w),
                      (R[1, 0] - R[0, 1]) / (4 * w)])
    elif R[0, 0] >= R[1, 1] and R[0, 0] >= R[2, 2]:
        x = 0.5 * np.sqrt(1.0 + R[0, 0] - R[1, 1] - R[2, 2])
        q = np.array([(R[2, 1] - R[1, 2]) / (4 * x), x, (R[0, 1] + R[1, 0]) / (4 * x),
                      (R[0, 2] + R[2, 0]) / (4 * x)])
    elif R[1, 1] >= R[2, 2]:
        y = 0.5 * np.sqrt(1.0 + R[1, 1] - R[0, 0] - R[2, 2])
        q = np.array([(R[0, 2] - R[2, 0]) / (4 * y), (R[0, 1] + R[1, 0]) / (4 * y), y,
                      (R[1, 2] + R[2, 1]) / (4 * y)])
    else:
        z = 0.5 * np.sqrt(1.0 + R[2, 2] - R[0, 0] - R[1, 1])
        q = np.array([(R[1, 0] - R[0, 1]) / (4 * z), (R[0, 2] + R[2, 0]) / (4 * z),
                      (R[1, 2] + R[2, 1]) / (4 * z), z])
    return q if q[0] >= 0 else -q


@nb.njit(cache=True)
def transverse_vector(n):
    """Euler vector γ ⊥ e_z of the transverse turn carrying e_z to the unit axis n.

    γ = θ (e_z × n)/|e_z × n| with θ = atan2(|e_z × n|, n_z); θ/sin θ by series near 0."""
    g0, g1 = transverse_t(n[0], n[1], n[2])
    return np.array([g0, g1, 0.0])


# --- Scalar (allocation-free) forms for right-hand sides called millions of times ------------
# A 3×3 matrix is a row-major 9-tuple, a vector a 3-tuple: numba keeps both in registers, so a
# right-hand side built from these allocates nothing (an np.empty(3) costs more than the maths).

@tuple_math
def rodrigues_t(t0, t1, t2, c1, c2):
    """E + c1·θ× + c2·(θ×)² as a 9-tuple, (θ×)² = θ⊗θ − |θ|²E."""
    d = 1.0 - c2 * (t0 * t0 + t1 * t1 + t2 * t2)
    return (d + c2 * t0 * t0, c2 * t0 * t1 - c1 * t2, c2 * t0 * t2 + c1 * t1,
            c2 * t1 * t0 + c1 * t2, d + c2 * t1 * t1, c2 * t1 * t2 - c1 * t0,
            c2 * t2 * t0 - c1 * t1, c2 * t2 * t1 + c1 * t0, d + c2 * t2 * t2)


@tuple_math
def rotation_t(t0, t1, t2):
    """L(θ) as a 9-tuple (see `rotation_tensor`)."""
    a, b, _, _ = _coefficients(np.sqrt(t0 * t0 + t1 * t1 + t2 * t2))
    return rodrigues_t(t0, t1, t2, a, b)


@tuple_math
def rotation_zhilin_inverse_t(t0, t1, t2):
    """L(θ) and Z⁻¹(θ) (see `zhilin_inverse`) as 9-tuples from one evaluation of their
    coefficients (one sin, one cos: the Euler-vector right-hand side needs both each call)."""
    a, b, _, d = _coefficients(np.sqrt(t0 * t0 + t1 * t1 + t2 * t2))
    return rodrigues_t(t0, t1, t2, a, b), rodrigues_t(t0, t1, t2, -0.5, d)


@tuple_math
def quat_matrix_t(w, x, y, z):
    """Rotation matrix of a (not necessarily unit) quaternion as a 9-tuple."""
    s = 2.0 / (w * w + x * x + y * y + z * z)
    return (1.0 - s * (y * y + z * z), s * (x * y - w * z), s * (x * z + w * y),
            s * (x * y + w * z), 1.0 - s * (x * x + z * z), s * (y * z - w * x),
            s * (x * z - w * y), s * (y * z + w * x), 1.0 - s * (x * x + y * y))


@nb.njit(cache=True)
def quat_matrix(q):
    """`quat_matrix_t` as a (3, 3) array, filled in place (a nested np.array literal costs
    ~1 µs inside numba kernels)."""
    t = quat_matrix_t(q[0], q[1], q[2], q[3])
    R = np.empty((3, 3))
    for k in range(9):
        R[k // 3, k % 3] = t[k]
    return R


@tuple_math
def mat_vec_t(M, a, b, c):
    return (M[0] * a + M[1] * b + M[2] * c, M[3] * a + M[4] * b + M[5] * c,
            M[6] * a + M[7] * b + M[8] * c)


@tuple_math
def mat_tvec_t(M, a, b, c):
    """Mᵀ·v."""
    return (M[0] * a + M[3] * b + M[6] * c, M[1] * a + M[4] * b + M[7] * c,
            M[2] * a + M[5] * b + M[8] * c)


@tuple_math
def cross_t(a0, a1, a2, b0, b1, b2):
    return a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0


@tuple_math
def transverse_t(nx, ny, nz):
    """(γ_x, γ_y) of `transverse_vector` (γ_z = 0) for the unit axis n."""
    s = np.sqrt(nx * nx + ny * ny)
    th = atan2(s, nz)
    f = 1.0 + th * th / 6.0 if th < _SMALL else th / s
    return -ny * f, nx * f


@nb.njit(cache=True)
def all_finite(a):
    """np.all(np.isfinite(a)) as a loop: numba compiles the array expression, with its result
    assigned into a row slice, in ~4 s a kernel (0.7 s as loops)."""
    for v in a.flat:
        if not np.isfinite(v):
            return False
    return True


@nb.njit(cache=True)
def matrices_to_quats(Rs):
    """(n, 3, 3) rotation matrices → (n, 4) unit quaternions (w ≥ 0); NaN rows stay NaN."""
    out = np.full((Rs.shape[0], 4), np.nan)
    for i in range(Rs.shape[0]):
        if all_finite(Rs[i]):
            q = matrix_to_quat(Rs[i])
            for k in range(4):
                out[i, k] = q[k]
    return out


@nb.njit(cache=True)
def quats_to_matrices(Q):
    """(n, 4) quaternions (not necessarily unit) → (n, 3, 3) rotation matrices; NaN stays NaN."""
    out = np.empty((Q.shape[0], 3, 3))
    for i in range(Q.shape[0]):
        R = quat_matrix_t(Q[i, 0], Q[i, 1], Q[i, 2], Q[i, 3])
        for k in range(9):
            out[i, k // 3, k % 3] = R[k]
    return out
