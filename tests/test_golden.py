"""Regression against golden results over whole trajectories (verification.md, "Regression").

These are *not* independent oracles — the physics tests are. They pin what each solver produced
when the golden file was written, with the package versions, so that a change that moves a
solver's output beyond environment noise fails here and has to be explained. Each golden holds
every channel down-sampled to 64 points plus the final values (frequency scenes: every mode).

Tolerances sit above environment noise, measured when the golden is written: the run is
repeated with every float parameter scaled by 1 + 1e-12 (the size of the input changes a
different libm, BLAS or compiler makes), and each channel's tolerance is 100× the largest
deviation that causes over the run, floored at 1e-12 of the channel's scale. Rewrite them on
purpose with `python -m pytest tests/test_golden.py --update-golden`; the JSON diff is the
review, and a failure names the package versions that changed since.
"""
import importlib.metadata
import json
from pathlib import Path

import numpy as np
import pytest

from compare import solvers
from compare.scenes import SCENES, get_scene

GOLDEN = Path(__file__).parent / "golden"
N_SAMPLES = 64
PERTURB = 1e-12
SAFETY = 100.0
# short, fast cases per scene; every solver that serves the scene has a golden
OVERRIDES = {"rotor-spinup": {"t_end": "2"}, "rotor-whirl": {"spin": "41.3"},
             "press": {}, "press-cycle": {},
             # a softer thread so the explicit engines' stable step stays affordable
             "sail-deploy": {"t_end": "2", "stiffness": "1e5"},
             "bearing-rotor": {"t_end": "0.5"}}
CASES = [(sc, s) for sc in SCENES for s in SCENES[sc].leaves]


def _versions():
    return {p: importlib.metadata.version(p) for p in ("numpy", "scipy", "numba", "exudyn",
                                                       "mujoco")}


def _produce(scene_name, solver_name, scale_params=1.0):
    """{channel: array} — time scenes: 64 samples and the final value; modes: frequencies."""
    sc = get_scene(scene_name)
    s = solvers.get_solver(solver_name)
    p = sc.resolve(OVERRIDES.get(scene_name, {}))
    if scale_params != 1.0:
        p = {k: (v * scale_params if isinstance(v, float) and k not in ("t_end", "output_dt")
                 else v) for k, v in p.items()}
    if sc.kind == "modes":
        m = solvers.modes(sc, s, p)
        assert m.status == "ok", m.reason
        return {lb: np.array([f]) for lb, f in zip(m.labels, m.frequencies_hz)}
    tr = solvers.simulate(sc, s, p, solvers.settings_for(s, sc.name))
    assert tr.status == "ok", tr.reason
    idx = np.unique(np.linspace(0, len(tr.t) - 1, N_SAMPLES).round().astype(int))
    return {c: np.append(v[idx], v[-1]) for c, v in tr.channels.items()}


def check(golden: dict, got: dict) -> list[str]:
    """Every stored sample within its channel's tolerance; the failures in words."""
    bad = []
    for ch, ref in golden["channels"].items():
        ref, tol = np.asarray(ref, float), golden["tolerance"][ch]
        if ch not in got or len(got[ch]) != len(ref):
            bad.append(f"{ch}: missing or resampled")
            continue
        d = np.abs(np.asarray(got[ch]) - ref)
        if np.any(~(d <= tol)):
            i = int(np.nanargmax(np.where(np.isfinite(d), d, np.inf)))
            bad.append(f"{ch}: sample {i} moved by {d[i]:.3g} > {tol:.3g} "
                       f"({got[ch][i]!r} vs golden {ref[i]!r})")
    return bad


@pytest.mark.parametrize("scene_name, solver_name", CASES, ids=lambda x: x)
def test_golden(request, scene_name, solver_name):
    path = GOLDEN / f"{scene_name}--{solver_name}.json"
    got = _produce(scene_name, solver_name)
    if request.config.getoption("--update-golden"):
        moved = _produce(scene_name, solver_name, 1.0 + PERTURB)
        tol = {c: max(SAFETY * float(np.max(np.abs(moved[c] - v))),
                      1e-12 * float(np.max(np.abs(v)))) for c, v in got.items()}
        path.write_text(json.dumps({
            "scene": scene_name, "set": OVERRIDES.get(scene_name, {}), "solver": solver_name,
            "versions": _versions(), "noise_perturbation": PERTURB, "safety": SAFETY,
            "tolerance": tol, "channels": {c: v.tolist() for c, v in got.items()}},
            indent=1, sort_keys=True) + "\n")
        return
    golden = json.loads(path.read_text())
    assert golden["set"] == OVERRIDES.get(scene_name, {})
    bad = check(golden, got)
    changed = {k: f"{v} → {_versions()[k]}" for k, v in golden["versions"].items()
               if _versions()[k] != v}
    assert not bad, (f"{solver_name} on {scene_name} moved from its golden: "
                     + "; ".join(bad) + (f" — package versions changed: {changed}"
                                         if changed else " (same package versions)"))


def test_a_mid_trajectory_change_of_1e_6_fails_the_check():
    golden = json.loads((GOLDEN / "rotor-spinup--quaternion.json").read_text())
    got = {c: np.array(v) for c, v in golden["channels"].items()}
    assert check(golden, got) == []
    mid = len(got["omega_norm"]) // 2
    got["omega_norm"][mid] *= 1 + 1e-6
    assert check(golden, got) and "sample" in check(golden, got)[0]
