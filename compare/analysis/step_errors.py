"""A fixed step's error estimate as a function of its members (the run and its reruns at other
steps), so that one estimator serves a run and the difference of two runs of one scheme.

`solvers._halving_error` keeps each run's members' offsets y_member − y (`Trajectory.members`,
rows 2·dt and dt/2) and which estimator held per channel. Two runs of one scheme (one leaf,
integrator and step) share the scheme's truncation error where their models coincide: in its
asymptotic range each run's error is C·dt^p, so their difference's is the change of a − b
times the same factor ≤ 2. `pair_error` uses it where both runs' halving is asymptotic and a − b
passes the same test — its changes shrink from 2·dt → dt to dt → dt/2 — and the sum of the two
runs' estimates elsewhere. Measured on sail-deploy's two thread-spool models (t_end 0.5 s, the
defaults and four calibration sets): tip angle 1.2e-6 rad apart, each run's halving estimate
4.1e-6 rad, their difference's 1.7e-10 rad against its change to a step that resolves the
thread's spring (dt/512) of 1.1e-10; 1.3–1.5 × that change at the five sets.

Where a run does not converge on halving (its changes wander in a band or shrink slowly: a
mode the step does not resolve, the thread's spring at ~1e5 rad/s) the difference's members
share that under-resolution and say nothing of the resolved difference: the deployed lengths'
difference wandered in bands of 3.7e-15–4.8e-14 m across 2·dt … dt/4 while its change to
dt/512 was 2.0e-13–2.4e-12 m at the same five sets (tests/verdicts/test_pair_error.py). There the
pair keeps the sum. Only one leaf: two codes running a scheme of one name need not share what
the step means (MuJoCo ties its constraints' time constant to it)."""
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


def shares_scheme(a: Trajectory, b: Trajectory, channel: str) -> bool:
    """The step's part of the error of a − b can be read from its own members: the two runs are
    of one scheme, each run's halving of `channel` is asymptotic, and so is the difference's
    (`shrinks`)."""
    if a.scheme is None or a.scheme != b.scheme or channel not in a.members \
            or channel not in b.members:
        return False
    if a.estimators.get(channel) != "halving" or b.estimators.get(channel) != "halving":
        return False
    d = np.asarray(a.members[channel]) - np.asarray(b.members[channel])
    return shrinks(d[0], d[1])


def pair_error(a: Trajectory, b: Trajectory, channel: str) -> np.ndarray:
    """The error of a − b on t: the sum of the two runs' estimates, with the step's part read
    from the difference's own halving where they share a scheme (`shares_scheme`) — never more
    than the sum. Rounding and every other knob's error stay summed."""
    ea, eb = a.errors[channel], b.errors[channel]
    if not shares_scheme(a, b, channel):
        return ea + eb
    da, db = a.members[channel][1], b.members[channel][1]
    own = 2 * (np.abs(da) + np.abs(db))
    return ea + eb - own + np.minimum(2 * np.abs(da - db), own)
