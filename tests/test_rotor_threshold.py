"""Internal-damping instability of rotor-whirl (issue 28): forward whirl grows above
Ω_th = √(k_eff / (r (r I_t − I_p))), r = c_int/(c_ext + c_int) (compare.physics.rotor.
instability_speed). The formula is checked against the Jeffcott rotor's classical threshold and
against each solver's own linearisation, whose largest growth rate must change sign at Ω_th."""
import numpy as np
import pytest

from compare import solvers
from compare.physics.rotor import constants, instability_speed
from compare.scenes import get_scene

SCENE = get_scene("rotor-whirl")
# r I_t − I_p > 0 in each (I_p/I_t = 0.118 at the defaults): r = 1/2, 1, 1/4
DAMPERS = ({"c_ext": 1.0, "c_int": 1.0}, {"c_ext": 0.0, "c_int": 2.0},
           {"c_ext": 3.0, "c_int": 1.0})


def _growth(solver_name, params):
    m = solvers.modes(SCENE, solvers.get_solver(solver_name), params)
    assert m.status == "ok", m.reason
    return m.extra["max_re_per_s"]


def test_jeffcott_limit():
    """A point disk (R → 0: I_p → 0, I_t → m l²) is the Jeffcott rotor in tilt:
    Ω_th = ω_n (1 + c_e/c_i), ω_n = √(k_eff/(m l²)), the classical rotating-damping threshold
    (issue 28). The disk's own I_p/I_t = R²/(2 l²) = 2e-12 is the deviation left."""
    for d in DAMPERS:
        p = SCENE.resolve({"R": 1e-6, **{k: str(v) for k, v in d.items()}})
        omega_n = np.sqrt(constants(p)["k_eff"] / (p["m"] * p["l"] ** 2))
        jeffcott = omega_n * (1 + d["c_ext"] / d["c_int"])
        assert instability_speed(p) == pytest.approx(jeffcott, rel=1e-9)


@pytest.mark.parametrize("solver_name", list(SCENE.leaves))
@pytest.mark.parametrize("dampers", DAMPERS, ids=lambda d: f"ce{d['c_ext']:g}-ci{d['c_int']:g}")
def test_growth_rate_changes_sign_at_the_threshold(solver_name, dampers):
    """Each solver's largest Re λ is < 0 at 0.999 Ω_th and > 0 at 1.001 Ω_th, for either spin
    sense. Measured there: |Re λ| ≈ 7e-4…1.4e-3 /s; the solvers differ from the quadratic by
    ≤ 1.4e-12 /s (mujoco), 7e-13 (euler-vector's central differences), 1e-14 (exudyn)."""
    p = SCENE.resolve({k: str(v) for k, v in dampers.items()})
    w_th = instability_speed(p)
    for sense in (1, -1):
        below = _growth(solver_name, {**p, "spin": sense * w_th * (1 - 1e-3)})
        above = _growth(solver_name, {**p, "spin": sense * w_th * (1 + 1e-3)})
        assert below < 0 < above, (sense, below, above)


@pytest.mark.parametrize("solver_name", list(SCENE.leaves))
def test_gyroscopic_stabilisation(solver_name):
    """r I_t < I_p (c_ext = 9 c_int: r = 0.1 < I_p/I_t = 0.118): no threshold, every spin
    stable."""
    p = SCENE.resolve({"c_ext": "9", "c_int": "1"})
    assert instability_speed(p) == np.inf
    for spin in (50.0, 500.0, 5000.0):
        assert _growth(solver_name, {**p, "spin": spin}) < 0


def test_no_damping_no_growth():
    """The defaults are undamped: every root on the imaginary axis, ζ = 0."""
    p = SCENE.resolve({"spin": "100"})
    m = solvers.modes(SCENE, solvers.get_solver("closed-form"), p)
    assert m.extra["max_re_per_s"] == 0 and not np.any(m.damping)
    assert instability_speed(p) == np.inf


def test_modes_workflow_reports_unstable_above_the_threshold():
    """`xval modes rotor-whirl --set c_int=1 --set c_ext=1 --set spin=…`: above Ω_th = 88.206
    rad/s every solver's forward whirl is listed as growing and the summary says `unstable`;
    just below, nothing is."""
    from compare.workflows.modes import run_modes
    p = SCENE.resolve({"c_int": "1", "c_ext": "1"})
    w_th = instability_speed(p)
    names = ["closed-form", "exudyn"]

    def run(spin):
        return run_modes("rotor-whirl", names, {"c_int": "1", "c_ext": "1", "spin": str(spin)},
                         log=lambda *a: None, campbell_sweep=False, identify=False)
    above, below = run(w_th * 1.001), run(w_th * 0.999)
    assert "unstable" in above.summary and "unstable" not in below.summary
    assert [(g["solver"], g["mode"]) for g in above.extra["unstable"]] == [
        (n, "forward whirl") for n in names]
    assert "unstable" not in below.extra


def test_round_off_is_not_a_growing_root():
    """Undamped, every root lies on the imaginary axis (closed form); the finite-difference
    linearisations put some at ζ ≈ −1e-16 (euler-vector −1.2e-16, MuJoCo −8.5e-20 at 40 rad/s).
    Those are round-off, inside the scene's damping allowance: no solver is `unstable`."""
    from compare.workflows.modes import run_modes
    res = run_modes("rotor-whirl", list(SCENE.leaves), {"spin": "40"}, log=lambda *a: None,
                    campbell_sweep=False, identify=False)
    assert "unstable" not in res.summary and "unstable" not in res.extra
    assert all(c.verdict == "agree" for c in res.comparisons)


def test_damping_verdicts_see_a_one_percent_damper_error():
    """ζ is judged like the frequencies (allowance 5e-13, set from |Δζ| ≤ 6.2e-14 measured):
    MuJoCo with c_ext 1 % off (ζ moves by ~4e-4) disagrees with the closed form on ζ, while
    its frequencies barely move."""
    p = SCENE.resolve({"spin": "60", "c_ext": "0.5", "c_int": "2"})
    exact = solvers.modes(SCENE, solvers.get_solver("closed-form"), p)
    right = solvers.modes(SCENE, solvers.get_solver("mujoco"), p)
    wrong = solvers.modes(SCENE, solvers.get_solver("mujoco"), {**p, "c_ext": 0.505})
    zeta = lambda cs: [c.verdict for c in cs if c.channel.endswith("ζ")]
    assert zeta(SCENE.verdicts(p, [exact, right])) == ["agree", "agree"]
    assert zeta(SCENE.verdicts(p, [exact, wrong])) == ["disagree", "disagree"]


def test_campbell_marks_where_the_forward_whirl_starts_to_grow():
    """On the Campbell sweep every solver's forward-whirl line turns growing between the two
    samples that bracket the closed-form threshold Ω_th (88.206 rad/s at c_int = c_ext = 1),
    its onset interpolated within the bracket; the backward whirl never grows."""
    from compare.workflows.modes import run_modes
    over = {"c_int": "1", "c_ext": "1", "spin": "100", "n_spin": "34"}
    w_th = instability_speed(SCENE.resolve(over))
    res = run_modes("rotor-whirl", list(SCENE.leaves), over, log=lambda *a: None,
                    identify=False)
    onsets = res.campbell["growing_from"]
    assert sorted(onsets) == sorted(SCENE.leaves)
    for name, rows in onsets.items():
        assert [r["line"] for r in rows] == ["forward whirl"], name
        r = rows[0]
        assert r["lo"] < w_th < r["hi"] and abs(r["from"] - w_th) < 0.05 * (r["hi"] - r["lo"])
