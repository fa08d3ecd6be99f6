"""Every modelling allowance against what its pair was measured to deviate by (issue 26, item
5): no wider than 10 × the measured deviation unless the scene file says why, and never
narrower than it (the measured cases agree). The measurements are tests/allowances.json
(`python -m tests.allowances` regenerates them); one cheap case per scene is rerun here to
check the table is what the solvers produce today."""
import json

import numpy as np
import pytest

from compare.scenes import ORIGIN, SCENES
from tests import allowances

TABLE = json.loads(allowances.TABLE.read_text())
ROWS = allowances.allowance_table(TABLE)

# one cheap case per scene, rerun against the stored table (a few seconds each; the
# helicopters' ~2 min each on a loaded 2-core machine: slow)
CHEAP = {"rotor-spinup": "1.5Nm-1s", "rotor-whirl": "spin0", "bearing-rotor": "0.5s",
         "press": "default", "press-cycle": "default", "sail-deploy": "0.2s",
         "rotating-beam": "speed0", "spinning-shaft": "spin0",
         "helicopter-clamped": "speed0", "helicopter-hover": "speed0"}
CHEAP["bicycle"] = "speed5"


def test_the_allowance_table(capsys):
    with capsys.disabled():
        print("\n" + allowances.markdown(ROWS))
    # a scene served by one solver has no pair to allow for
    assert {r["scene"] for r in ROWS} == {n for n in SCENES
                                          if n not in ORIGIN and len(SCENES[n].leaves) > 1}


@pytest.mark.parametrize("row", ROWS, ids=lambda r: f"{r['scene']}:{r['regime']}:{r['pair']}:"
                                                   f"{r['channel']}")
def test_every_allowance_is_measured_and_within_10x(row):
    if row["ratio"] is None:
        assert row["wider"], "no measured case judges this allowance and the scene file " \
                             "gives no reason"
        return
    assert row["covers"], "a measured case deviates beyond its allowance (+ estimates)"
    assert row["ratio"] <= 10 or row["wider"], (
        f"allowance {allowances.fmt_allowance(row['allowance'])} is {row['ratio']:.3g} × the "
        f"measured {row['measured']:.2e} ({row['cases']}) with no documented reason")


# What "the same as the table" means across machines. The stored deviations are round-off
# sensitive: measured between an Intel AVX-512 machine (where the table was written) and an AMD
# AVX2 one, the cheap cases' deviations moved by at most 0.016 of the pair's own error estimate
# (press-cycle, lagrange-exact–exudyn crank_accel) and, for frequencies (no estimate), by at
# most 5.9e-8 relative (helicopter-hover at rest, mstmm–fem, a slow case, worst mode flap
# collective 1: 2.3e-8 → 8.2e-8; which step of the two solvers amplifies the round-off is not
# traced) and 3.1e-10 in the default cases (rotating-beam, exudyn–mujoco). A stale table —
# one solver's parameter off by 1 % — moves them by orders of magnitude more than either bound
# (E + 1 % in exudyn: rotating-beam's frequency deviation 1.3e-3 → 5.0e-3).
OF_ESTIMATE = 0.1
FREQUENCY = 2e-7


def _close(new, old, estimate=None, frequency=False):
    """Equal to a tenth of the pair's error estimate, to 2e-7 for a relative frequency
    difference, else (no estimate, or a zero one) to 1e-6 of the deviation or both at round-off
    (≤ 1e-13) within 10×."""
    if estimate:
        return abs(new - old) <= OF_ESTIMATE * estimate
    if frequency and abs(new - old) <= FREQUENCY:
        return True
    if abs(new - old) <= 1e-6 * max(abs(old), 1e-300):
        return True
    return max(new, old) <= 1e-13 and new <= 10 * old + 1e-300 and old <= 10 * new + 1e-300


@pytest.mark.parametrize("scene", [pytest.param(s, marks=pytest.mark.slow)
                                   if s.startswith("helicopter") else s for s in sorted(CHEAP)])
def test_stored_measurements_are_what_the_solvers_give_today(scene):
    case = TABLE[scene][CHEAP[scene]]
    names = [n for n in SCENES[scene].leaves if n in case["status"]]   # the scene's order
    rows, status = allowances.run_case(scene, case["set"], names)
    assert status == case["status"]

    def key(r):
        return frozenset((r["a"], r["b"])), r["channel"]
    stored = {key(r): r for r in case["rows"]}
    assert {key(r) for r in rows} == set(stored)
    for r in rows:
        s = stored[key(r)]
        estimate = s["error_estimate"] and s["error_estimate"] / s["scale"]
        for k in ("max_abs", "left"):
            assert _close(r[k] / r["scale"], s[k] / s["scale"], estimate,
                          r["channel"] == "frequency"), (r["a"], r["b"], r["channel"], k, r[k],
                                                         s[k])
        assert (r["error_estimate"] is None) == (s["error_estimate"] is None)
        assert np.isclose(r["scale"], s["scale"], rtol=1e-6)
