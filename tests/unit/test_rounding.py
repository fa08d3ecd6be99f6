"""A channel that is zero in exact arithmetic rounds with the lengths it is computed from: the
press loop residual | |B − A| − l2 | carries eps·l2, not eps × its own ~1e-17 m."""
import numpy as np

from compare.physics.press import CHANNELS, loop_violation
from compare.solvers import rounding_scale


class _Run:
    def __init__(self, channels):
        self.channels = channels


def test_the_loop_residual_rounds_with_the_rod_length():
    (lv,) = [c for c in CHANNELS if c == "loop_violation"]
    params = {"l1": 0.015, "l2": 0.04, "l3": 0.03}
    # an exactly closed loop, evaluated in floating point: a residual of a few eps·l2
    phi = np.linspace(-1.2, 0.4, 400)
    ax, ay = params["l1"] * np.cos(phi), params["l1"] * np.sin(phi)
    psi = np.arcsin(-ay / params["l3"] * 0.5)
    bx = ax + np.sqrt(params["l2"] ** 2 - (params["l3"] * np.sin(psi) - ay) ** 2)
    x_c = bx - params["l3"] * np.cos(psi)
    res = loop_violation(params, phi, psi, x_c)
    assert 0 < res.max() < 8 * np.finfo(float).eps * params["l2"]
    assert rounding_scale(lv, _Run({lv: res}), params) == params["l2"]
    assert rounding_scale("crank_rate", _Run({"crank_rate": np.array([-3.0, 2.0])}), {}) == 3.0
