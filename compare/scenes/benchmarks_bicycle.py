"""The benchmark bicycle (Meijaard, Papadopoulos, Ruina, Schwab 2007): lean and steer of the
Whipple bicycle about its upright straight run, as a frequency scene. The paper's 25 design
parameters (its symbols, Table 1's benchmark values) and the forward speed; every root at that
speed (`xval modes bicycle --set speed=V`), the growth rate against speed (`xval map bicycle
--x speed=0:10 --observable growth_rate --level 0`: the weave and capsize speeds)."""
import math

import numpy as np

from ..errors import BadInput
from ..physics.bicycle import damping_shift, eigenvalues, matrices
from .base import Calibration, MapSpec, ModesScene
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


BODIES = (("rear wheel", "I_Rxx", "I_Ryy", "I_Rxx", None),
          ("rear body", "I_Bxx", "I_Byy", "I_Bzz", "I_Bxz"),
          ("front assembly", "I_Hxx", "I_Hyy", "I_Hzz", "I_Hxz"),
          ("front wheel", "I_Fxx", "I_Fyy", "I_Fxx", None))


def principal_moments(p, xx, yy, zz, xz):
    """A body's principal moments of inertia (its tensor in the x–z plane, y a principal
    axis), ascending."""
    t = np.array([[p[xx], 0.0, p[xz] if xz else 0.0], [0.0, p[yy], 0.0],
                  [p[xz] if xz else 0.0, 0.0, p[zz]]], float)
    return np.linalg.eigvalsh(t)


def _check(p):
    """Every body a rigid body: its principal moments satisfy the triangle inequality
    (A + B ≥ C: a mass distribution has one; a thin wheel is at equality, I_yy = 2 I_xx), and
    the equations a positive definite mass matrix (a design that has one)."""
    for body, *names in BODIES:
        a, b, c = principal_moments(p, *names)
        if c > a + b + 8 * np.finfo(float).eps * (a + b + c):
            given = ", ".join(f"{n}={p[n]:g}" for n in dict.fromkeys(filter(None, names)))
            raise BadInput(f"the {body}'s inertia is not a rigid body's ({given}): its "
                           f"principal moments {a:.4g}, {b:.4g}, {c:.4g} kg·m² break the "
                           f"triangle inequality A + B >= C")
    eig = np.linalg.eigvalsh(matrices(p)[0])
    if not (np.all(np.isfinite(eig)) and eig[0] > 0.0):
        raise BadInput("the design's mass matrix M (Appendix A) is not positive definite: "
                       f"eigenvalues {eig[0]:.3g}, {eig[1]:.3g}")


def _halves(names, up):
    """Each name's default/2 … default (up: default … 2·default)."""
    d = {p.name: p.default for p in PARAMS}
    return {n: (d[n], 2 * d[n]) if up else (d[n] / 2, d[n]) for n in names}


# `xval calibrate`'s region: the default box (each float ×1/2 … ×2) cut where the bodies stay
# rigid. The wheels are thin discs (I_yy 6e-4 and 1e-3 kg·m² under 2 I_xx), the rear body and
# fork flat in x–z (I_yy ≈ I_xx + I_zz): drawn independently over ×1/2 … ×2, 0.7 % of the box
# is rigid (`_check`; each wheel alone half of it). Each wheel's diameter moment is drawn
# from the default up and its axle moment from the default down (every draw rigid), and the
# I_yy of rear body and fork from the default down (I_yy ≤ I_xx + I_zz); the refused rest is
# drawn again (5 % of draws are kept). meijaard solves the paper's equations to round-off: it
# is the truth of Exudyn's fit, the same Whipple model; MuJoCo's soft contacts are another
# model (its shift is an allowance), so it has no truth and is left out of coverage.
CALIBRATION = Calibration(
    region={**_halves(("I_Rxx", "I_Fxx"), up=True),
            **_halves(("I_Ryy", "I_Fyy", "I_Byy", "I_Hyy"), up=False)},
    log=("I_Rxx", "I_Fxx", "I_Ryy", "I_Fyy", "I_Byy", "I_Hyy"),
    truth={"exudyn": "meijaard"})


# MuJoCo's soft contacts: each constraint force follows the motion with its time constant tc
# (5e-4 s, reference_models/mujoco/bicycle.py), a lag that moves a root λ by δλ ∝ tc·λ² to
# first order (linear in tc there: 0.0204, 0.0105, 0.0056, 0.0030 /s at 2e-3 … 2.5e-4 s).
# Measured |δλ| / (tc |λ|²) of the weave, MuJoCo against the equations: 0.55 at the defaults,
# 0.23–1.15 over 12 calibration designs (seed 11, 2.5–9 m/s; tests/verdicts/
# test_allowance_models.py), so |δλ| ≤ 2 tc |λ|²; the frequency moves by at most that, ζ by
# the arg's change within it (`damping_shift`).
MUJOCO_TC = 5e-4
CONTACT_LAG = 2.0


def _contact_shifts(p):
    """(relative frequency, ζ) allowances of MuJoCo's soft contacts at `p`: over the
    oscillating roots of the equations, the largest of |δλ|/Im λ and of ζ's change within
    |δλ| ≤ CONTACT_LAG · tc · |λ|²."""
    lam = eigenvalues(p, float(p["speed"]))
    lam = lam[lam.imag > 1e-9 * np.abs(lam)]
    if not len(lam):
        return 0.0, 0.0
    r = CONTACT_LAG * MUJOCO_TC * np.abs(lam) ** 2
    return float(np.max(r / lam.imag)), float(np.max(damping_shift(lam, r)))


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
    # allowances are 0. MuJoCo's contacts are soft: its roots move by the contact lag
    # (`_contact_shifts`; a constant 2.5e-3 on ζ was 3.7e3 × a near-real weave's 6.7e-7)
    tolerances={"frequency": 0.0, "damping": 0.0,
                "frequency_by_solver": {"mujoco": lambda p: _contact_shifts(p)[0]},
                "damping_by_solver": {"mujoco": lambda p: _contact_shifts(p)[1]}},
    check=_check,
    calibration=CALIBRATION,
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
