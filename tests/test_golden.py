"""Regression against small golden results (verification.md, "Regression").

These are *not* independent oracles — the physics tests are. They pin what each solver produced
when the golden file was written, with the package versions, so that a change that moves a
solver's output beyond environment noise fails here and has to be explained. Rewrite them on
purpose with `python -m pytest tests/test_golden.py --update-golden`; the JSON diff is the
review.
"""
import importlib.metadata
import json
from pathlib import Path

import numpy as np
import pytest

from compare import solvers
from compare.scenes import get_scene

GOLDEN = Path(__file__).parent / "golden"
RTOL, ATOL = 1e-7, 1e-8          # well above run-to-run noise, far below any model change
CASES = [
    ("rotor-spinup", {"t_end": "2"}, ["euler-vector", "quaternion", "exudyn", "mujoco"]),
    ("press", {}, ["lagrange-partial", "lagrange-exact", "exudyn", "mujoco"]),
    ("press-cycle", {}, ["lagrange-exact", "mujoco"]),
    ("sail-deploy", {"t_end": "2"}, ["thread-spool", "thread-spool-conservative", "exudyn"]),
    ("rotor-whirl", {"spin": "41.3"}, ["euler-vector", "exudyn", "mujoco"]),
]


def _versions():
    return {p: importlib.metadata.version(p) for p in ("numpy", "scipy", "numba", "exudyn",
                                                       "mujoco")}


def _produce(scene_name, overrides, solver_name):
    sc = get_scene(scene_name)
    s = solvers.get_solver(solver_name)
    p = sc.resolve(overrides)
    if sc.kind == "modes":
        m = solvers.modes(sc, s, p)
        assert m.status == "ok", m.reason
        return dict(zip(m.labels, map(float, m.frequencies_hz)))
    tr = solvers.simulate(sc, s, p, solvers.settings_for(s, sc.name))
    assert tr.status == "ok", tr.reason
    return tr.final()


@pytest.mark.parametrize("scene_name, overrides, solver_name",
                         [(sc, o, s) for sc, o, ss in CASES for s in ss],
                         ids=lambda x: x if isinstance(x, str) else "")
def test_golden(request, scene_name, overrides, solver_name):
    path = GOLDEN / f"{scene_name}--{solver_name}.json"
    got = _produce(scene_name, overrides, solver_name)
    if request.config.getoption("--update-golden"):
        path.write_text(json.dumps({"scene": scene_name, "set": overrides, "solver": solver_name,
                                    "versions": _versions(), "rtol": RTOL, "atol": ATOL,
                                    "final": got}, indent=1, sort_keys=True) + "\n")
        return
    ref = json.loads(path.read_text())
    assert ref["set"] == overrides
    for k, v in ref["final"].items():
        assert np.isclose(got[k], v, rtol=ref["rtol"], atol=ref["atol"]), \
            f"{solver_name} {k}: {got[k]!r} moved from golden {v!r} (written with {ref['versions']})"
