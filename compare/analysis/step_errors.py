"""A fixed step's error estimate as a function of its members (the run and its reruns at other
steps), so that one estimator serves a run and the difference of two runs of one scheme.

`solvers._halving_error` keeps each run's members' offsets y_member − y (`Trajectory.members`,
rows 2·dt, dt/2, and dt/4 where it ran) and which estimator held per channel. Two runs of one
scheme (one leaf, integrator and step) share the scheme's truncation error where their models
coincide: in its asymptotic range each run's error is C·dt^p, so their difference's is the
change of a − b times the same factor ≤ 2. `pair_error` uses it where a − b passes the
halving's own asymptotic test — its changes shrink from 2·dt → dt to dt → dt/2 — and the sum of
the two runs' estimates elsewhere. Measured on sail-deploy's two thread-spool models (t_end
0.5 s): tip angle 1.2e-6 rad apart, each run's halving estimate 4.1e-6 rad, their difference's
1.7e-10 rad against its change to dt/16 of 1.1e-10. Where the difference does not converge
but both runs wander in a band, the band of the difference holds its step's part, as a run's
band holds its own (`difference_estimator`); the runs' rounding stays in each. Only one leaf:
two codes running a scheme of one name need not share what the step means (MuJoCo ties its
constraints' time constant to it)."""
import numpy as np

from .trajectory import Trajectory


def band(*runs) -> np.ndarray:
    """2 × the running maximum of the runs' spread: the width of the band runs wander in where
    their changes do not converge (any two members, the truth included, differ by up to it)."""
    return 2 * np.maximum.accumulate(np.ptp(runs, axis=0))


def shrinks(d0, d1) -> bool:
    """The halving's asymptotic test: the change from dt to dt/2 (`d1`, over t) is at most half
    the change from 2·dt to dt (`d0`) wherever that stands out (a zero crossing of the error
    leaves both small: below a tenth of d0's largest, the tenth counts)."""
    d0, d1 = np.abs(d0), np.abs(d1)
    return not np.any(d1 > 0.5 * np.maximum(d0, 0.1 * np.max(d0)))


def member_error(kind: str, offsets) -> np.ndarray:
    """The step's part of a run's estimate from its members' offsets (rows 2·dt, dt/2, dt/4):
    "halving", an order-p method's error 2^p/(2^p − 1) ≤ 2 × |y − y_half|; "band", the band the
    run, dt/2 and dt/4 wander in (a geometric tail's ratio is the run's own: none here)."""
    if kind == "halving":
        return 2 * np.abs(offsets[1])
    return band(np.zeros_like(offsets[1]), *offsets[1:])


def difference_estimator(a: Trajectory, b: Trajectory, channel: str) -> str | None:
    """How the step's part of the error of a − b is read from its own members, where the two
    runs' step errors of `channel` come from members of one scheme: "halving" where the
    difference's changes shrink as the step does (`shrinks`), "band" where they do not but
    both runs wandered in a band and so ran dt/4 too (the band a − b wanders in across its
    members: sail-deploy's deployed lengths, each in a band of 4.5e-10 m, differ by
    1.2e-13 m and that difference changes by 1.9e-16, 6.9e-16, 2.6e-15 m from 2·dt → dt to
    dt/2 → dt/4), else None: the sum."""
    if a.scheme is None or a.scheme != b.scheme or channel not in a.members \
            or channel not in b.members:
        return None
    kinds = {a.estimators.get(channel), b.estimators.get(channel)}
    if not kinds <= {"halving", "band"}:
        return None
    ma, mb = np.asarray(a.members[channel]), np.asarray(b.members[channel])
    d = ma[:2] - mb[:2]
    if shrinks(d[0], d[1]):
        return "halving"
    return "band" if kinds == {"band"} and len(ma) == len(mb) == 3 else None


def shares_scheme(a: Trajectory, b: Trajectory, channel: str) -> bool:
    """The two runs' difference of `channel` has a step error of its own
    (`difference_estimator`)."""
    return difference_estimator(a, b, channel) is not None


def pair_error(a: Trajectory, b: Trajectory, channel: str) -> np.ndarray:
    """The error of a − b on t: the sum of the two runs' estimates, with the step's part read
    from the difference's own members where they share a scheme (`difference_estimator`) —
    never more than the sum. Rounding and every other knob's error stay summed."""
    ea, eb = a.errors[channel], b.errors[channel]
    kind = difference_estimator(a, b, channel)
    if kind is None:
        return ea + eb
    ma, mb = a.members[channel], b.members[channel]
    own = (member_error(a.estimators[channel], ma)
           + member_error(b.estimators[channel], mb))
    return ea + eb - own + np.minimum(member_error(kind, np.asarray(ma) - np.asarray(mb)), own)
