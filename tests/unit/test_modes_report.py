"""The head of `xval modes`' report.md is composed from data alone (compare/output/modes_report.py):
two solvers' frequencies and a growing mode written here by hand show up in its tables and in
its "unstable" line."""
import math

import numpy as np

from compare.analysis import metrics
from compare.analysis.trajectory import Modes
from compare.output import modes_report
from compare.results.modes import growing_modes
from compare.scenes import get_scene

LABELS = ["backward whirl", "forward whirl"]


def _runs():
    # exudyn's forward whirl grows: ζ = −0.02 at 7.5 Hz
    a = ("closed-form", [3.0, 7.5], [0.0, 0.0])
    b = ("exudyn", [3.0000001, 7.5], [0.0, -0.02])
    return [Modes("rotor-whirl", s, np.array(f), list(LABELS), damping=np.array(z),
                  whirl=["backward", "forward"],
                  extra={"frequency_error_hz": np.array([1e-9, 1e-9])})
            for s, f, z in (a, b)]


def test_the_head_shows_each_solvers_frequencies_and_names_the_growing_mode():
    sc = get_scene("rotor-whirl")
    runs = _runs()
    growing = [{"solver": "exudyn", "mode": "forward whirl", "frequency_hz": 7.5,
                "zeta": -0.02, "growth_per_s": 0.5}]
    cmp = metrics.frequency_comparisons(runs, {"frequency": 1e-6})
    md = modes_report.head(sc, sc.resolve({}), runs, cmp, growing, [])
    assert md[0] == f"# rotor-whirl: {sc.title}"
    assert "| closed-form | ok | 3, 7.5 | backward whirl, forward whirl |  |" in md
    assert "| exudyn | ok | 3.0000001, 7.5 | backward whirl, forward whirl |  |" in md
    # the damped table: exudyn's forward whirl at 7.5 Hz = 15π rad/s = 450 rpm, ζ = −0.02
    damped = [ln for ln in md if ln.startswith("| exudyn | forward whirl |")]
    assert len(damped) == 1
    cells = [c.strip() for c in damped[0].strip("|").split("|")]
    assert math.isclose(float(cells[4]), 15 * math.pi, rel_tol=1e-9)     # printed to 10 digits
    assert float(cells[5]) == 450.0 and float(cells[6]) == -0.02
    assert math.isclose(float(cells[7]), -2 * math.pi * 0.02 / math.sqrt(1 - 0.02 ** 2),
                        rel_tol=1e-5)                                    # log dec, 6 digits
    unstable = [ln for ln in md if ln.startswith("**unstable**")]
    assert unstable == ["**unstable**: exudyn forward whirl grows at 0.5 /s (ζ = -0.02)"]
    # both modes of both solvers judged: the verdict table's rows
    assert sum(ln.startswith("| closed-form | exudyn |") for ln in md) == len(cmp) == 2


def test_the_growth_rate_the_unstable_line_reports_is_minus_zeta_omega_over_root():
    """growing_modes' rate Re λ = −ζ ω_d/√(1 − ζ²), against the closed form written here."""
    (g,) = growing_modes(_runs())
    assert (g["solver"], g["mode"]) == ("exudyn", "forward whirl")
    assert math.isclose(g["growth_per_s"], 0.02 * 2 * math.pi * 7.5 / math.sqrt(1 - 0.0004),
                        rel_tol=1e-14)


def test_no_growing_mode_no_unstable_line_and_no_threshold_without_a_closed_form():
    sc = get_scene("rotor-whirl")
    md = modes_report.head(sc, sc.resolve({}), _runs(), [], [], [])
    assert not any(ln.startswith("**unstable**") for ln in md)
    assert modes_report.threshold_section({"parameter": "spin", "closed_form_rad_s": None}) \
        == ["", "## Threshold speed (a root starts to grow)", "",
            "Closed form: none — every speed is stable."]

