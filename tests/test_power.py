"""`xval power`: the detection power of a run's verdicts, checked against a closed form.

rotor-whirl at rest: every solver's whirl frequency is √(k_eff / I_t)/2π with
k_eff = k + m l g_z (custom_models/rotor/closed_form.py), so a relative change ε of k in one
solver moves its frequencies by ε·k/(2 k_eff) and first breaks the frequency allowance `tol` at
ε* = 2·tol·k_eff/k — independent of how power.py searches for it.
"""
import json

import pytest
from conftest import xval as cli

import xval
from compare.scenes import get_scene


def test_epsilon_star_of_the_whirl_stiffness_is_the_closed_form():
    sc = get_scene("rotor-whirl")
    p = sc.resolve({})
    k_eff = p["k"] + p["m"] * p["l"] * p["gravity"][2]
    r = xval.power("rotor-whirl", parameters=["k"])
    rows = r["power"]
    assert {x["solver"] for x in rows} == set(sc.leaves)
    for x in rows:
        # the bound also holds both solvers' error estimates (round-off, ≤ 1e-13 relative)
        want = 2 * sc.tolerances["frequency"] * k_eff / p["k"]
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
