"""Regression against golden results over whole trajectories (verification.md, "Regression").

These are *not* independent oracles — the physics tests are. They pin what each solver produced
when the golden file was written, with the package versions, so that a change that moves a
solver's output beyond environment noise fails here and has to be explained. Each golden holds
every channel down-sampled to 64 points plus the final values (frequency scenes: every mode).

Tolerances sit above environment noise, measured when the golden is written: the run is
repeated with every continuous physical parameter (`Param.continuous_physical`: never a count,
a choice, a threshold, the horizon or the output grid) moved by ±1e-12 of itself, alternating
signs (the size of the input changes a different libm, BLAS or compiler makes), and each
channel's tolerance is 100× the largest deviation that causes over the run, floored at 1e-12 of
the channel's scale. A conserved quantity (the scene's energy balance and invariants) is stored
as its drift from t = 0, so its golden pins the conservation, not an offset the noise moves.
`test_a_one_percent_error_fails_the_golden` proves each golden's power: one physical parameter
of the scene 1 % off fails every solver's golden. Rewrite them on purpose with
`python -m pytest tests/verdicts/test_golden.py --update-golden`; the JSON diff is the review, and a
failure names the package versions that changed since.
"""
import importlib.metadata
import json
from pathlib import Path

import numpy as np
import pytest

from compare import solvers
from compare.scenes import SCENES, get_scene

GOLDEN = Path(__file__).parents[1] / "golden"
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
# the aircraft engines pinned on chains of 20 segments (with their N/2 and N/4 ones): the code of
# the default 40 at a sixth of the cost (a 40-segment golden and its 1 % twin took ~20 s)
SETTINGS = {(sc, s): {"n_segments": 20} for sc in ("helicopter-clamped", "helicopter-hover")
            for s in ("exudyn", "mujoco")}


def _versions():
    return {p: importlib.metadata.version(p) for p in ("numpy", "scipy", "numba", "exudyn",
                                                       "mujoco")}


def noisy(sc, p: dict, rel: float) -> dict:
    """`p` with every continuous physical parameter moved by ±`rel` of itself (alternating
    signs, so no dimensionless group is left exactly unchanged)."""
    names = [q.name for q in sc.params if q.continuous_physical]
    return {**p, **{k: p[k] * (1.0 + (rel if i % 2 == 0 else -rel)) for i, k in enumerate(names)}}


def _produce(scene_name, solver_name, perturb=None):
    """({channel: array}, {channel: scale}) — time scenes: 64 samples and the final value,
    conserved quantities as their drift (scale: the quantity's own); modes: frequencies.
    `perturb(scene, params) -> params` changes the input."""
    sc = get_scene(scene_name)
    s = solvers.get_solver(solver_name)
    p = sc.resolve(OVERRIDES.get(scene_name, {}))
    if perturb is not None:
        p = perturb(sc, p)
    if sc.kind == "modes":
        m = solvers.modes(sc, s, p, SETTINGS.get((scene_name, solver_name)))
        assert m.status == "ok", m.reason
        got = {lb: np.array([f]) for lb, f in zip(m.labels, m.frequencies_hz)}
        return got, {c: abs(float(v[0])) for c, v in got.items()}
    tr = solvers.simulate(sc, s, p, solvers.settings_for(s, sc.name))
    assert tr.status == "ok", tr.reason
    idx = np.unique(np.linspace(0, len(tr.t) - 1, N_SAMPLES).round().astype(int))
    drift = conserved(sc)
    got = {c: np.append(v[idx], v[-1]) - (v[0] if c in drift else 0.0)
           for c, v in tr.channels.items()}
    return got, {c: float(np.max(np.abs(v))) for c, v in tr.channels.items()}


def conserved(sc) -> set:
    return ({sc.energy_channel} if sc.energy_channel else set()) | set(sc.invariant_channels)


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
    got, scale = _produce(scene_name, solver_name)
    if request.config.getoption("--update-golden"):
        moved, _ = _produce(scene_name, solver_name, lambda sc, p: noisy(sc, p, PERTURB))
        tol = {c: max(SAFETY * float(np.max(np.abs(moved[c] - v))), 1e-12 * scale[c])
               for c, v in got.items()}
        path.write_text(json.dumps({
            "scene": scene_name, "set": OVERRIDES.get(scene_name, {}), "solver": solver_name,
            **({"settings": SETTINGS[scene_name, solver_name]}
               if (scene_name, solver_name) in SETTINGS else {}),
            "versions": _versions(), "noise_perturbation": PERTURB, "safety": SAFETY,
            "drift": sorted(conserved(get_scene(scene_name)) & set(got)),
            "tolerance": tol, "channels": {c: v.tolist() for c, v in got.items()}},
            indent=1, sort_keys=True) + "\n")
        return
    golden = json.loads(path.read_text())
    assert golden["set"] == OVERRIDES.get(scene_name, {})
    assert golden.get("settings") == SETTINGS.get((scene_name, solver_name))
    assert golden["drift"] == sorted(conserved(get_scene(scene_name)) & set(got))
    bad = check(golden, got)
    changed = {k: f"{v} → {_versions()[k]}" for k, v in golden["versions"].items()
               if _versions()[k] != v}
    assert not bad, (f"{solver_name} on {scene_name} moved from its golden: "
                     + "; ".join(bad) + (f" — package versions changed: {changed}"
                                         if changed else " (same package versions)"))


# one parameter per scene that every solver reads, 1 % off in the solver under test only
POWER = {"rotor-spinup": "m", "rotor-whirl": "k", "press": "J1", "press-cycle": "J1",
         "sail-deploy": "J_hub", "bearing-rotor": "J_p", "rotating-beam": "rho",
         "spinning-shaft": "m", "helicopter-clamped": "blade_rho",
         "helicopter-hover": "fuselage_rho"}
POWER["bicycle"] = "m_B"             # the rear body's (rider's) mass: in M, K0 and C1
POWER["andrews-squeezer"] = "m2"     # the rod K2: in M(q) and the velocity terms f
OVERRIDES["bricard"] = {"t_end": "2"}
POWER["bricard"] = "m"     # every rod's mass: the motion is the same, the energies 1 % off
OVERRIDES["n-four-bar"] = {"t_end": "2"}     # past φ = 0 (0.72 s) and φ = −π (1.24 s)
POWER["n-four-bar"] = "g"  # gravity: the mass scales out of the motion, g does not


@pytest.mark.parametrize("scene_name, solver_name", CASES, ids=lambda x: x)
def test_a_one_percent_error_fails_the_golden(scene_name, solver_name):
    """The golden's power: a 1 % error in one physical parameter reaching this solver (as a
    slip in its model would) is seen, whatever the tolerances came out as."""
    name = POWER[scene_name]
    got, _ = _produce(scene_name, solver_name, lambda sc, p: {**p, name: p[name] * 1.01})
    golden = json.loads((GOLDEN / f"{scene_name}--{solver_name}.json").read_text())
    assert check(golden, got), f"{name} × 1.01 in {solver_name} passes its golden"


def test_a_mid_trajectory_change_of_1e_6_fails_the_check():
    golden = json.loads((GOLDEN / "rotor-spinup--quaternion.json").read_text())
    got = {c: np.array(v) for c, v in golden["channels"].items()}
    assert check(golden, got) == []
    mid = len(got["omega_norm"]) // 2
    got["omega_norm"][mid] *= 1 + 1e-6
    assert check(golden, got) and "sample" in check(golden, got)[0]
