"""The benchmark bicycle (Meijaard, Papadopoulos, Ruina, Schwab 2007): lean and steer of the
Whipple bicycle about its upright straight run, as a frequency scene. The paper's 25 design
parameters (its symbols, Table 1's benchmark values) and the forward speed; every root at that
speed (`xval modes bicycle --set speed=V`), the growth rate against speed (`xval map bicycle
--x speed=0:10 --observable growth_rate --level 0`: the weave and capsize speeds)."""
import math

import numpy as np

from ..errors import BadInput
from ..physics.bicycle import matrices
from .base import MapSpec, ModesScene
from .params import Param

SOURCE = ("J. P. Meijaard, J. M. Papadopoulos, A. Ruina, A. L. Schwab, “Linearized dynamics "
          "equations for the balance and steer of a bicycle: a benchmark and review”, Proc. R. "
          "Soc. A 463 (2007) 1955–1982, doi:10.1098/rspa.2007.1857 (Appendix A, Table 2)")


def _mass(name, default, doc):
    return Param(name, default, "kg", doc, lo=0.0, hi=1e4, open_lo=True)


def _inertia(name, default, doc, signed=False):
    return Param(name, default, "kg·m²", doc, lo=-1e4 if signed else 0.0, hi=1e4,
                 open_lo=not signed)


def _length(name, default, doc, lo=-100.0, open_lo=False):
    return Param(name, default, "m", doc, lo=lo, hi=100.0, open_lo=open_lo)


# Table 1 of the paper: axes x forward, y right, z down, origin at the rear contact point
PARAMS = (
    _length("w", 1.02, "wheel base", lo=0.0, open_lo=True),
    _length("c", 0.08, "trail"),
    Param("lambda", math.pi / 10, "rad", "steer axis tilt (from the vertical, pi/2 − head "
          "angle; short of ±π/2, where the steer axis lies flat)", lo=-1.5, hi=1.5),
    Param("g", 9.81, "m/s²", "gravity", lo=0.0, hi=100.0),
    _length("r_R", 0.3, "rear wheel radius", lo=0.0, open_lo=True),
    _mass("m_R", 2.0, "rear wheel mass"),
    _inertia("I_Rxx", 0.0603, "rear wheel inertia about a diameter (= I_Rzz)"),
    _inertia("I_Ryy", 0.12, "rear wheel inertia about its axle"),
    _length("x_B", 0.3, "rear body and frame centre of mass, x"),
    _length("z_B", -0.9, "rear body and frame centre of mass, z (down positive)"),
    _mass("m_B", 85.0, "rear body and frame mass (rider included)"),
    _inertia("I_Bxx", 9.2, "rear body inertia I_xx about its centre of mass"),
    _inertia("I_Bxz", 2.4, "rear body product of inertia I_xz", signed=True),
    _inertia("I_Byy", 11.0, "rear body inertia I_yy (not in the linear equations)"),
    _inertia("I_Bzz", 2.8, "rear body inertia I_zz"),
    _length("x_H", 0.9, "front handlebar and fork assembly centre of mass, x"),
    _length("z_H", -0.7, "front handlebar and fork assembly centre of mass, z"),
    _mass("m_H", 4.0, "front handlebar and fork assembly mass"),
    _inertia("I_Hxx", 0.05892, "front assembly inertia I_xx"),
    _inertia("I_Hxz", -0.00756, "front assembly product of inertia I_xz", signed=True),
    _inertia("I_Hyy", 0.06, "front assembly inertia I_yy (not in the linear equations)"),
    _inertia("I_Hzz", 0.00708, "front assembly inertia I_zz"),
    _length("r_F", 0.35, "front wheel radius", lo=0.0, open_lo=True),
    _mass("m_F", 3.0, "front wheel mass"),
    _inertia("I_Fxx", 0.1405, "front wheel inertia about a diameter (= I_Fzz)"),
    _inertia("I_Fyy", 0.28, "front wheel inertia about its axle"),
    Param("speed", 5.0, "m/s", "forward speed v of the rear contact point", lo=-100.0,
          hi=100.0),
)


def _check(p):
    """The equations need a positive definite mass matrix (a design that has one)."""
    eig = np.linalg.eigvalsh(matrices(p)[0])
    if not (np.all(np.isfinite(eig)) and eig[0] > 0.0):
        raise BadInput("the design's mass matrix M (Appendix A) is not positive definite: "
                       f"eigenvalues {eig[0]:.3g}, {eig[1]:.3g}")


def _growth(p, m):
    """The largest real part of every root (> 0: a motion grows) — the weave below the weave
    speed, the capsize above the capsize speed."""
    return m.extra.get("max_re_per_s")


BICYCLE = ModesScene(
    name="bicycle",
    title="Benchmark bicycle: lean and steer about the upright straight run",
    source=SOURCE,
    leaves={"meijaard": "custom_models.bicycle.meijaard",
            "exudyn": "reference_models.exudyn.bicycle",
            "mujoco": "reference_models.mujoco.bicycle"},
    params=PARAMS,
    energy_channel=None,
    # No modelling difference: Exudyn's bodies, hinges and ideal rolling discs are the paper's
    # Whipple model, whose linearisation the equations are; its roots carry their own bars (its
    # step and fit: every root off the equations by ≤ 0.63 of its bar at 0–10 m/s, 0.5 m/s
    # apart; the weave 1.1e-6 relative at most at 2, 5, 8 m/s, tests/allowances.json), so the
    # allowances are 0. MuJoCo's contacts are soft (time constant 5e-4 s): its roots move
    # off linearly in it (reference_models/mujoco/bicycle.py); measured against the equations
    # at 1–10 m/s, the weave frequency by ≤ 1.1e-3 relative and ζ by ≤ 1.25e-3 (10 m/s;
    # 1.0e-3 and 1.16e-3 at 8 m/s, tests/allowances.json), its own bars far below that
    # (1e-4–3e-3): 2.5e-3 each
    tolerances={"frequency": 0.0, "damping": 0.0,
                "frequency_by_solver": {"mujoco": 2.5e-3},
                "damping_by_solver": {"mujoco": 2.5e-3}},
    check=_check,
    campaign_cases=({"name": "bicycle-5", "campaign": "benchmarks"},
                    {"name": "bicycle-0", "set": {"speed": 0.0}, "campaign": "benchmarks"}),
    map_observables={"growth_rate": (_growth, "1/s", "largest real part of the eigenvalues "
                                     "(> 0: a motion grows; its zeros are the weave and capsize "
                                     "speeds)")},
    maps=(MapSpec("stability", x="speed=0:10", observable="growth_rate", level=0.0,
                  resolution=1e-4),),
    group="benchmarks",
    notes="Modes are the oscillating roots (the weave); every root, the real capsize and "
          "castor ones included, is each run's `eigenvalues` [Re, Im] in 1/s.",
)
