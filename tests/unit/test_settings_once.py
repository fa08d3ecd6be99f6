"""Settings are checked once per run: what a check passed comes back unchecked from the same
check, and anything changed since is checked again (compare.contract.Checked, check_once)."""
import pickle

import numpy as np
import pytest

from compare.contract import Checked, check_once, merge_settings

DEFAULTS = {"integrator": "rk4", "dt": 1e-3}


def test_merge_returns_its_own_settings_as_they_are():
    s = merge_settings({"integrator": "RK44"}, DEFAULTS, ("rk4",))
    assert s == {"integrator": "rk4", "dt": 1e-3} and isinstance(s, Checked)
    assert merge_settings(s, DEFAULTS, ("rk4",)) is s
    assert merge_settings(s, dict(DEFAULTS), ("rk4",)) is not s   # other defaults: checked


@pytest.mark.parametrize("change", [
    lambda s: s.__setitem__("bogus", 1), lambda s: s.update(bogus=1),
    lambda s: s.setdefault("bogus", 1)])
def test_a_change_in_place_is_checked_again(change):
    s = merge_settings({}, DEFAULTS, ("rk4",))
    change(s)
    with pytest.raises(ValueError, match="bogus"):
        merge_settings(s, DEFAULTS, ("rk4",))


def test_check_once_runs_the_leaf_check_once_per_span():
    calls = []

    @check_once
    def check(settings, t_out=None):
        calls.append(1)
        if float(settings["dt"]) <= 0:
            raise ValueError("dt must be positive")
        return merge_settings(settings, DEFAULTS, ("rk4",))

    t = np.linspace(0, 1, 11)
    s = check({"dt": 0.1}, t)
    assert check(s, t) is s and check(s) is s and len(calls) == 1
    check(s, t[:2])                        # another span: the horizon rules differ
    check({**s}, t)                        # a copy is a plain dict
    assert len(calls) == 3
    s["dt"] = -1.0                         # changed in place: the bad step is caught
    with pytest.raises(ValueError, match="positive"):
        check(s, t)


def test_checked_settings_survive_pickling_as_values():
    s = merge_settings({"dt": 2e-3}, DEFAULTS, ("rk4",))
    back = pickle.loads(pickle.dumps(s))
    assert back == s and merge_settings(back, DEFAULTS, ("rk4",)) == s
