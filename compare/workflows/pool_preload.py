"""What every local pool worker needs, imported once by the forkserver the workers are forked
from (`executors._context`): the job runners, the engines, matplotlib on its file backend.
Not rerun: its import starts threads, which a fork would not copy."""
import matplotlib

matplotlib.use("Agg")                  # workers write files; pyplot then never picks a GUI

import exudyn  # noqa: E402,F401
import matplotlib.pyplot  # noqa: E402,F401
import mujoco  # noqa: E402,F401

from . import campaign, maps  # noqa: E402,F401
