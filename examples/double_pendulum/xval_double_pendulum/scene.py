"""The scene: parameters with defaults, units and ranges, the channels every solver reports
(computed here once, from each solver's angles and rates), the allowances, the extremes and a
closed form. Two point masses on massless rods, absolute angles θ1, θ2 from the downward
vertical, no damping and no drive: the energy is conserved.

    T = ½(m1+m2) l1² θ1'² + ½ m2 l2² θ2'² + m2 l1 l2 θ1' θ2' cos(θ1 − θ2)
    V = −(m1+m2) g l1 cos θ1 − m2 g l2 cos θ2
Small oscillations (m1 = m2, l1 = l2 = l): ω² = (g/l)(2 ∓ √2).
"""
import numpy as np

from compare.scenes.base import Extreme, Finding, Scene
from compare.scenes.params import Param, positive

CHANNELS = ("theta1", "theta2", "kinetic", "potential", "energy_balance")


def channels(params, th1, th2, w1, w2):
    """The channels from a solver's angles and rates (one implementation for every solver)."""
    m1, m2, l1, l2, g = (params[k] for k in ("m1", "m2", "l1", "l2", "g"))
    kin = (0.5 * (m1 + m2) * l1**2 * w1**2 + 0.5 * m2 * l2**2 * w2**2
           + m2 * l1 * l2 * w1 * w2 * np.cos(th1 - th2))
    pot = -(m1 + m2) * g * l1 * np.cos(th1) - m2 * g * l2 * np.cos(th2)
    e = kin + pot
    return {"theta1": th1, "theta2": th2, "kinetic": kin, "potential": pot,
            "energy_balance": e - e[0]}


def normal_mode_frequencies(params):
    """Small-oscillation angular frequencies [rad/s] of the linearised pendulum (any masses and
    lengths): the roots of det(K − ω² M) with M, K at rest."""
    m1, m2, l1, l2, g = (params[k] for k in ("m1", "m2", "l1", "l2", "g"))
    M = np.array([[(m1 + m2) * l1**2, m2 * l1 * l2], [m2 * l1 * l2, m2 * l2**2]])
    K = np.diag([(m1 + m2) * g * l1, m2 * g * l2])
    return np.sqrt(np.sort(np.linalg.eigvals(np.linalg.solve(M, K)).real))


def findings(params, trajectories):
    ok = [tr for tr in trajectories if tr.status == "ok"]
    w = normal_mode_frequencies(params)
    drift = {tr.solver: float(np.max(np.abs(tr.channels["energy_balance"]))) for tr in ok}
    return [Finding("normal_modes", float(w[0]), "rad/s",
                    f"small-oscillation frequencies {w[0]:.6f} and {w[1]:.6f} rad/s"),
            Finding("energy_drift", max(drift.values(), default=None), "J",
                    "largest |E(t) − E(0)|: " + ", ".join(f"{s} {v:.2e} J"
                                                        for s, v in drift.items()))]


# the solver this plug-in adds (compare.solvers.Solver's fields); exudyn and mujoco are xval's
def flip_regime(params, tr):
    """`flips` when the lower rod goes over the top (|θ2| passes π) within the run, else
    `swings`: the classic map of the double pendulum over its initial angles."""
    return "flips" if np.nanmax(np.abs(tr.channels["theta2"])) > np.pi else "swings"


SOLVERS = ({"name": "dp-lagrange", "doc": "the double pendulum's Lagrange equations on xval's "
            "shared integrators (example plug-in); numba", "engine": "numba", "compiled": True},)

SCENE = Scene(
    name="double-pendulum",
    title="Planar double pendulum (example plug-in)",
    source="examples/double_pendulum: a user's own system",
    kind="time",
    leaves={"dp-lagrange": "xval_double_pendulum.lagrange",
            "exudyn": "xval_double_pendulum.exudyn_leaf",
            "mujoco": "xval_double_pendulum.mujoco_leaf"},
    params=(positive("m1", 1.0, "kg", "upper mass"), positive("m2", 1.0, "kg", "lower mass"),
            positive("l1", 1.0, "m", "upper rod"), positive("l2", 1.0, "m", "lower rod"),
            positive("g", 9.81, "m/s²", "gravity"),
            Param("theta1_0", 0.5, "rad", "initial angle of the upper rod", lo=-np.pi, hi=np.pi),
            Param("theta2_0", 1.0, "rad", "initial angle of the lower rod", lo=-np.pi, hi=np.pi),
            positive("t_end", 5.0, "s", "horizon", hi=1e4),
            positive("output_dt", 0.01, "s", "output grid")),
    channels=CHANNELS,
    # the three solvers model one system: only their own errors separate them (the verdicts
    # weigh each solver's error estimate). Measured at the defaults (`xval run double-pendulum`):
    # every pair within 1.7e-11 of the channel's scale; the allowance 1e-9 covers the
    # 1e-12 kg·m² inertia MuJoCo needs on its point masses and round-off
    tolerances={c: ("rel+abs", 1e-9, 1e-9) for c in CHANNELS},
    key_channel="theta2",
    energy_scale_channels=("kinetic", "potential"),
    reference_solvers=("dp-lagrange", "mujoco"),
    findings=findings,
    regime=flip_regime,
    extremes=(Extreme("large swing", {"theta1_0": 2.5, "theta2_0": -2.5, "t_end": 3},
                      bound=1e-6, why="chaotic tumbling: energy must still close"),
              Extreme("tiny swing", {"theta1_0": 1e-4, "theta2_0": 1e-4, "t_end": 3},
                      check="reference", bound=1e-6,
                      why="near rest: another solver at accurate settings")),
    campaign_cases=({"name": "double-pendulum"},),
)

SCENES = (SCENE,)
