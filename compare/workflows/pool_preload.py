"""What every local pool worker needs, imported once by the forkserver the workers are forked
from (`executors._context`): the job runners, the engines, matplotlib on its file backend, and
numba with its target context set up — numba's first compile or cache load in a process does
that, ~0.5 s of CPU in each worker otherwise (measured: a forked worker importing the two rotor
leaves, 0.6–0.8 s → 0.14–0.17 s). The solvers' leaves themselves are not imported here: on an
empty numba cache their import compiles (~37 CPU-s for all), which here would run on one core
before any worker starts, where the workers compile what their jobs need side by side.
Not rerun: its import starts threads, which a fork would not copy."""
import matplotlib

matplotlib.use("Agg")                  # workers write files; pyplot then never picks a GUI

import exudyn  # noqa: E402,F401
import matplotlib.pyplot  # noqa: E402,F401
import mujoco  # noqa: E402,F401
import numba  # noqa: E402

from . import campaign, maps  # noqa: E402,F401


@numba.njit
def numba_ready(x):
    return x


numba_ready(0)
