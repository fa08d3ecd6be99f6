"""Rotation math shared by every custom model (numba-compiled, plain arrays).

Euler-vector tensors follow the paper (seed 000) and Zhilin's notation:
    L(θ) = E cos θ + (1 − cos θ) θ⊗θ/θ² + (sin θ/θ) θ×E        rotation tensor
    Z(θ) = E sin θ/θ + (1 − sin θ/θ) θ⊗θ/θ² + ((1 − cos θ)/θ²) θ×E,   ω = Z(θ)·θ̇
written here in the equivalent Rodrigues form E + a θ× + b (θ×)², with series near θ = 0 so no
0/0 is ever formed. Quaternions are (w, x, y, z) and rotate body vectors into the fixed frame.
"""
import numpy as np
import numba as nb

_SMALL = 1e-4   # below this |θ| the coefficient series are exact to round-off


@nb.njit(cache=True)
def skew(v):
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


@nb.njit(cache=True)
def _coefficients(t):
    """a = sin t/t, b = (1 − cos t)/t², c = (1 − a)/t², d = (1 − a/(2b))/t²."""
    t2 = t * t
    if t < _SMALL:
        return (1.0 - t2 / 6.0, 0.5 - t2 / 24.0, 1.0 / 6.0 - t2 / 120.0, 1.0 / 12.0 + t2 / 720.0)
    a = np.sin(t) / t
    b = (1.0 - np.cos(t)) / t2
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
    c, s = np.cos(phi), np.sin(phi)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


@nb.njit(cache=True)
def quat_to_matrix(q):
    """Rotation matrix of a (not necessarily unit) quaternion, normalised on the fly."""
    w, x, y, z = q / np.sqrt(q @ q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


@nb.njit(cache=True)
def quat_times_vector(q, v):
    """q ⊗ (0, v): the kinematic product of q' = ½ q ⊗ (0, ω_body)."""
    w, x, y, z = q
    return np.array([-x * v[0] - y * v[1] - z * v[2],
                     w * v[0] + y * v[2] - z * v[1],
                     w * v[1] + z * v[0] - x * v[2],
                     w * v[2] + x * v[1] - y * v[0]])


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
    s = np.sqrt(n[0] * n[0] + n[1] * n[1])
    th = np.arctan2(s, n[2])
    f = 1.0 + th * th / 6.0 if th < _SMALL else th / s
    return np.array([-n[1] * f, n[0] * f, 0.0])
