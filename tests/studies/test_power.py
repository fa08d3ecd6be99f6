"""`xval power`: the detection power of a run's verdicts, checked against a closed form.

rotor-whirl at rest: every solver's whirl frequency is √(k_eff / I_t)/2π with
k_eff = k + m l g_z (custom_models/rotor/closed_form.py), so a relative change ε of k in one
solver moves its frequencies by ε·k/(2 k_eff) and first breaks a verdict whose bound is `tol`
(relative: allowance + both error estimates) at ε* = 2·tol·k_eff/k, the least over the
solver's comparisons — independent of how power.py searches for it.
"""
import json

import pytest

import xval
from compare import solvers
from compare.analysis import metrics
from compare.scenes import get_scene
from tests.conftest import xval as cli


def test_epsilon_star_of_the_whirl_stiffness_is_the_closed_form():
    sc = get_scene("rotor-whirl")
    p = sc.resolve({})
    k_eff = p["k"] + p["m"] * p["l"] * p["gravity"][2]
    runs = [solvers.modes(sc, solvers.get_solver(s), p) for s in sc.leaves]
    nominal = metrics.frequency_comparisons(runs, sc.tolerances_for(p))
    r = xval.power("rotor-whirl", parameters=["k"])
    rows = r["power"]
    assert {x["solver"] for x in rows} == set(sc.leaves)
    for x in rows:
        tol = min(c.tolerance for c in nominal if x["solver"] in (c.a, c.b))
        want = 2 * tol * k_eff / p["k"]
        assert x["epsilon"] == pytest.approx(want, rel=1e-3), x
        assert x["channel"] in ("forward whirl", "backward whirl")
    assert "k" in r["summary"]


def test_a_zero_parameter_is_reported_unverified_not_skipped():
    r = xval.power("rotor-whirl", parameters=["eccentricity"])
    assert all(x["epsilon"] is None and "0" in x["how"] for x in r["power"])
    assert "not verified" in r["summary"] and "eccentricity" in r["summary"]


def test_power_json_and_bad_input():
    rc, out, err = cli("power", "rotor-whirl", "--parameter", "m", "--solver", "closed-form",
                       "--solver", "mujoco", "--json")
    assert rc == 0, err
    obj = json.loads(out)
    assert set(obj) >= {"scene", "power", "summary"}
    assert {tuple(sorted(x)) for x in obj["power"]} == {
        ("channel", "epsilon", "how", "pair", "parameter", "solver")}
    rc, out, err = cli("power", "rotor-whirl", "--parameter", "n_spin")
    assert rc == 2 and err.count("\n") == 1 and "n_spin" in err


def test_a_campaign_case_estimates_its_power_as_xval_power_confirms_it(tmp_path):
    """A campaign case's ε* comes from one solver's sensitivities without a confirming run;
    `xval power` finds each ε* from runs of the solver itself (confirmed, or bisected). The
    estimate's bracket [(B − Δ₀)/D, (B + Δ₀)/D] must hold the ε* those runs find (1.5: the
    bisection's last bracket) — a sensitivity off by its step H (ε 1e4× too large) or taken
    from a run of the wrong parameter fails this."""
    case = {"scene": "rotor-spinup", "set": {"t_end": "1", "torque": "3.2"},
            "solvers": ["euler-vector", "quaternion"]}
    f = tmp_path / "camp.json"
    f.write_text(json.dumps({"name": "p", "cases": [{"name": "c", "power": True, **case}]}))
    s = xval.campaign(str(f), out=str(tmp_path / "c"))
    (c,) = s["cases"]
    estimate = {(r["parameter"], r["solver"]): r["bracket"] for r in c["power"]}
    confirmed = xval.power("rotor-spinup", case["solvers"], params=case["set"],
                           parameters=["m", "R", "torque"])
    for r in confirmed["power"]:
        lo, hi = estimate[(r["parameter"], r["solver"])]
        assert r["epsilon"] is not None, r
        assert lo / 1.01 <= r["epsilon"] <= hi * 1.5, (r, lo, hi)
    report = (tmp_path / "c" / "report.md").read_text()
    assert "worst ε*" in report and "Detection power" in report


def test_damping_ratio_verdicts_give_power_over_the_internal_damper():
    """With the dampers on, a change of c_int in one solver moves its ζ first: ε* is decided
    by a ζ comparison and lies in [1, REFINE] × bound/|dζ/dε| (the linear estimate exactly, or
    the upper end of a bisection bracket REFINE wide), the least over the modes — dζ/dε from
    the closed-form leaf's roots, not from power.py; each mode's bound the unperturbed pair's
    (allowance + both ζ error estimates). (A ζ channel once made the search loop forever: it
    read ζ as a frequency.)"""
    import numpy as np
    over = {"c_ext": "0.5", "c_int": "2", "spin": "60"}
    sc = get_scene("rotor-whirl")
    p = sc.resolve(over)
    pair = ["closed-form", "exudyn"]
    closed = solvers.get_solver("closed-form")
    zeta = lambda q: dict(zip(*(lambda m: (m.labels, m.damping))(  # noqa: E731
        solvers.modes(sc, closed, q))))
    h = 1e-6
    z0, z1 = zeta(p), zeta({**p, "c_int": p["c_int"] * (1 + h)})
    nominal = metrics.damping_comparisons(
        [solvers.modes(sc, solvers.get_solver(s), p) for s in pair], sc.tolerances_for(p))
    assert len(nominal) == 2
    # scale 1: a ζ comparison's tolerance is its bound on |Δζ|
    want = min(c.tolerance / (abs(z1[c.channel[:-2]] - z0[c.channel[:-2]]) / h)
               for c in nominal)
    r = xval.power("rotor-whirl", parameters=["c_int"], solvers=pair, **over)
    from compare.workflows.power import REFINE
    for x in r["power"]:
        assert x["channel"].endswith("ζ"), x
        assert want * (1 - 1e-3) <= x["epsilon"] <= REFINE * want * (1 + 1e-3), x
    assert np.isfinite(want)
