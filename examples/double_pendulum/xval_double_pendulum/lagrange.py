"""`dp-lagrange`: the Lagrange equations in (θ1, θ2) with an allocation-free numba right-hand
side on xval's shared integrators (custom_models.integrators.dense)."""
import numba as nb
import numpy as np

from compare.contract import LeafResult, merge_settings
from custom_models.integrators import FAIL_REASONS, FIXED_TABLEAUS, no_guard
from custom_models.integrators.dense import DENSE_TABLEAUS, solve

from .scene import channels

INTEGRATORS = tuple(DENSE_TABLEAUS) + tuple(FIXED_TABLEAUS)
ADAPTIVE = tuple(DENSE_TABLEAUS)
DEFAULT_SETTINGS = {"integrator": "dop853", "rtol": 1e-11, "dt": None}


@nb.njit(cache=True)
def rhs_into(t, y, p, dy):
    m1, m2, l1, l2, g = p[0], p[1], p[2], p[3], p[4]
    th1, th2, w1, w2 = y[0], y[1], y[2], y[3]
    c, s = np.cos(th1 - th2), np.sin(th1 - th2)
    a11, a12, a22 = (m1 + m2) * l1 * l1, m2 * l1 * l2 * c, m2 * l2 * l2
    f1 = -m2 * l1 * l2 * w2 * w2 * s - (m1 + m2) * g * l1 * np.sin(th1)
    f2 = m2 * l1 * l2 * w1 * w1 * s - m2 * g * l2 * np.sin(th2)
    det = a11 * a22 - a12 * a12
    dy[0], dy[1] = w1, w2
    dy[2] = (a22 * f1 - a12 * f2) / det
    dy[3] = (a11 * f2 - a12 * f1) / det


def simulate(params, t_out, settings=None):
    s = merge_settings(settings, DEFAULT_SETTINGS, INTEGRATORS)
    p = np.array([params[k] for k in ("m1", "m2", "l1", "l2", "g")])
    y0 = np.array([params["theta1_0"], params["theta2_0"], 0.0, 0.0])
    Y, stats, t_fail, code, used = solve(rhs_into, no_guard, y0, p, t_out, s["integrator"],
                                         dt=s["dt"] or 1e-3, rtol=s["rtol"])
    return LeafResult(channels=channels(params, *Y.T), stats=stats, settings=used,
                      status="ok" if code == 0 else "diverged",
                      t_fail=None if code == 0 else float(t_fail),
                      reason=None if code == 0 else FAIL_REASONS.get(code))
