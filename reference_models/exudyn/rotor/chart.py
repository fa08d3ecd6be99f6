"""Cardan charts of the gimbal: R = A0 · Rx(q0) · Ry(q1) · Rz(q2), ω = J(q)·q̇ with the columns
A0·e_x, A0·Rx·e_y, R·e_z.

The chain locks where n = R·e_z = ±A0·e_x. A run starts in A0 = identity (lock at tilt 90°
towards x); when |cos q1| falls below CHART_SWITCH after a step it goes on in a chart whose lock
axis is ≥ 45° away from n and from the cone n sweeps when whirling about e_z (`new_chart`), so
every tilt short of π is reachable. At tilt π the spring direction itself is undefined: the run
stops at TILT_LIMIT."""
import math

import numba as nb
import numpy as np

TILT_LIMIT = math.pi - 1e-3        # stop here: −kγ has no defined direction at tilt π
COS_TILT_LIMIT = math.cos(TILT_LIMIT)
CHART_SWITCH = 0.6                 # |cos q1| below this after a step -> change of Cardan chart
CHART_LOCK = 0.2                   # ... and in any stage state (hard guard near the lock)


def _rx(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1.0, 0, 0], [0, c, -s], [0, s, c]])


def _ry(b):
    c, s = math.cos(b), math.sin(b)
    return np.array([[c, 0, s], [0, 1.0, 0], [-s, 0, c]])


@nb.njit(cache=True)
def _motion_rows(A0, q, qd, R, w):
    """Rows of R = A0·Rx(q0)·Ry(q1)·Rz(q2) and ω = J q̇, J = [A0 e_x, A0 Rx e_y, R e_z]."""
    for r in range(q.shape[0]):
        ca, sa = math.cos(q[r, 0]), math.sin(q[r, 0])
        cb, sb = math.cos(q[r, 1]), math.sin(q[r, 1])
        cc, sc = math.cos(q[r, 2]), math.sin(q[r, 2])
        for i in range(3):
            x1 = ca * A0[i, 1] + sa * A0[i, 2]          # (A0 Rx) e_y
            x2 = -sa * A0[i, 1] + ca * A0[i, 2]         # (A0 Rx) e_z
            y0 = cb * A0[i, 0] - sb * x2                # (A0 Rx Ry) e_x
            y2 = sb * A0[i, 0] + cb * x2                # (A0 Rx Ry) e_z = R e_z
            R[r, i, 0] = cc * y0 + sc * x1
            R[r, i, 1] = -sc * y0 + cc * x1
            R[r, i, 2] = y2
            w[r, i] = A0[i, 0] * qd[r, 0] + x1 * qd[r, 1] + y2 * qd[r, 2]


def chart_motion(A0, q, qd):
    """Body rotations R (n, 3, 3) and spatial angular velocities ω (n, 3) from rows of Cardan
    coordinates q, rates qd (n, 3) in chart A0."""
    q, qd = np.atleast_2d(q).astype(float), np.atleast_2d(qd).astype(float)
    R, w = np.empty((len(q), 3, 3)), np.empty((len(q), 3))
    _motion_rows(np.ascontiguousarray(A0, float), q, qd, R, w)
    return R, w


def chart_coordinates(A0, R, w):
    """Inverse of `chart_motion` (Cardan XYZ angles of A0ᵀR and the rates that give ω)."""
    M = A0.T @ R
    b = math.asin(max(-1.0, min(1.0, M[0, 2])))
    a = math.atan2(-M[1, 2], M[2, 2])
    c = math.atan2(-M[0, 1], M[0, 0])
    q = np.array([a, b, c])
    Rx = A0 @ _rx(a)
    Rxy = Rx @ _ry(b)
    J = np.column_stack([A0[:, 0], Rx[:, 1], Rxy[:, 2]])
    return q, np.linalg.solve(J, w)


def new_chart(R):
    """Chart for the current body axis n, with its lock axes ±A0·e_x at least 45° from n and
    from the cone n sweeps when it whirls about e_z at the current tilt θ:
    - 45° < θ < 135°: lock axis e_z (distance θ and π − θ from the whirl cone);
    - otherwise: lock axis horizontal and ⊥ n (distance 90° − |90° − θ| ≥ 45° from the cone)."""
    n = R[:, 2]
    tilt = math.atan2(math.hypot(n[0], n[1]), n[2])
    if math.pi / 4 < tilt < 3 * math.pi / 4:
        a = np.array([0.0, 0.0, 1.0])
    else:
        a = np.cross([0.0, 0.0, 1.0], n)
        if np.linalg.norm(a) < 1e-9:
            a = np.array([1.0, 0.0, 0.0])
    a = a / np.linalg.norm(a)
    b = np.cross(a, [1.0, 0.0, 0.0]) if abs(a[0]) < 0.9 else np.cross(a, [0.0, 1.0, 0.0])
    b /= np.linalg.norm(b)
    return np.column_stack([a, b, np.cross(a, b)])


def start(params):
    """The initial rows (R, ω, work) and the rotor's Cardan coordinates in the first chart."""
    R0 = _rx(float(params["tilt0"]))
    w0 = float(params["spin0"]) * R0[:, 2]
    return R0, w0, chart_coordinates(np.eye(3), R0, w0)


def quaternions(R):
    """(n,4) unit quaternions w,x,y,z of rotation matrices (n,3,3), sign kept continuous."""
    n = R.shape[0]
    Q = np.empty((n, 4))
    tr = R[:, 0, 0] + R[:, 1, 1] + R[:, 2, 2]
    cand = np.stack([tr, R[:, 0, 0], R[:, 1, 1], R[:, 2, 2]], axis=1)
    which = np.argmax(cand, axis=1)
    for i in range(n):
        r = R[i]
        j = which[i]
        if j == 0:
            s = 2.0 * math.sqrt(max(1.0 + tr[i], 0.0))
            Q[i] = [0.25 * s, (r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s,
                    (r[1, 0] - r[0, 1]) / s]
        elif j == 1:
            s = 2.0 * math.sqrt(max(1.0 + r[0, 0] - r[1, 1] - r[2, 2], 0.0))
            Q[i] = [(r[2, 1] - r[1, 2]) / s, 0.25 * s, (r[0, 1] + r[1, 0]) / s,
                    (r[0, 2] + r[2, 0]) / s]
        elif j == 2:
            s = 2.0 * math.sqrt(max(1.0 + r[1, 1] - r[0, 0] - r[2, 2], 0.0))
            Q[i] = [(r[0, 2] - r[2, 0]) / s, (r[0, 1] + r[1, 0]) / s, 0.25 * s,
                    (r[1, 2] + r[2, 1]) / s]
        else:
            s = 2.0 * math.sqrt(max(1.0 + r[2, 2] - r[0, 0] - r[1, 1], 0.0))
            Q[i] = [(r[1, 0] - r[0, 1]) / s, (r[0, 2] + r[2, 0]) / s, (r[1, 2] + r[2, 1]) / s,
                    0.25 * s]
        if i > 0 and Q[i] @ Q[i - 1] < 0:
            Q[i] = -Q[i]
    return Q
