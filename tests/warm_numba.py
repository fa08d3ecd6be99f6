"""Compile the numba kernels once, before the test workers start (`conftest.py` calls `warm_all`
in the xdist controller). Kernels are cached on disk (`cache=True`, in __pycache__ next to their
sources); on a fresh clone both workers, and every `xval` subprocess and campaign worker a test
started before a kernel was cached, compiled it again. Cold, one process per scene family took
42, 15, 23, 27 and 23 s of CPU (rotor, bearing, press, sail, mstmm; 2 cores under a load of 4),
warm 2–3 s each: skipped where every cached source has an index newer than itself.

`python -m tests.warm_numba INDEX` warms the scene family INDEX (scenes of one module)."""
import subprocess
import sys
from pathlib import Path

import compare  # noqa: F401  before numpy: one BLAS thread, as `xval` runs

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("compare", "custom_models", "reference_models")


def families():
    """Scene name lists, one per scene module (its scenes share their compiled kernels)."""
    from compare.scenes import ORIGIN, SCENES
    from compare.workflows.digest import _scene_module
    out: dict = {}
    for name, sc in SCENES.items():
        if name not in ORIGIN:                      # built-in scenes only, no plug-ins
            out.setdefault(_scene_module(sc), []).append(name)
    return list(out.values())


def warm(scene_names):
    """Each solver of each time scene once, at the scene's defaults, on a two-point grid (the
    compile call `simulate` makes; the engines' rotor models have numba callbacks too); each
    compiled solver of a frequency scene its modes."""
    from compare import solvers
    from compare.scenes import get_scene
    for name in scene_names:
        sc = get_scene(name)
        p = sc.resolve({})
        for leaf in sc.leaves:
            s = solvers.get_solver(leaf)
            if sc.is_modes and s.compiled:
                solvers.modes(sc, s, p)
            elif sc.is_time:
                s.leaf(sc).simulate(p, sc.output_grid(p)[:2], solvers.settings_for(s, sc.name))


def cold():
    """A source with cached kernels whose index is missing or older than the source."""
    for pkg in PACKAGES:
        for src in (ROOT / pkg).rglob("*.py"):
            if "cache=True" in src.read_text():
                index = list((src.parent / "__pycache__").glob(f"{src.stem}.*.nbi"))
                if not index or min(f.stat().st_mtime for f in index) < src.stat().st_mtime:
                    return True
    return False


def warm_all():
    """Every family in its own process, all at once (the CPUs share them; no kernel twice)."""
    if not cold():
        return
    n = len(families())
    procs = [subprocess.Popen([sys.executable, "-m", "tests.warm_numba", str(i)], cwd=ROOT,
                              stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
             for i in range(n)]
    for p in procs:                 # a failure here shows up again, with context, in a test
        p.communicate()


if __name__ == "__main__":
    warm(families()[int(sys.argv[1])])
