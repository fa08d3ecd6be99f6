"""What every local pool worker needs, imported once by the forkserver the workers are forked
from (`executors._context`): the job runners, the engines, matplotlib on its file backend, and
every built-in solver's leaf — a compiled leaf's import loads its kernels from numba's cache
(or compiles them), and numba's first load in a process sets up its target context: 0.6–0.8 s
of CPU in each worker otherwise (measured: a forked worker importing the two rotor leaves).
Not rerun: its import starts threads, which a fork would not copy."""
import matplotlib

matplotlib.use("Agg")                  # workers write files; pyplot then never picks a GUI

import exudyn  # noqa: E402,F401
import matplotlib.pyplot  # noqa: E402,F401
import mujoco  # noqa: E402,F401

from ..leafinfo import leaf_info  # noqa: E402
from ..scenes import SCENES  # noqa: E402
from . import campaign, maps  # noqa: E402,F401

for _scene in SCENES.values():
    for _module in _scene.leaves.values():
        try:
            leaf_info(_module)
        except Exception:  # noqa: BLE001 - a plug-in's broken leaf: its own jobs report it
            pass
