"""The beams' frequency error bars against an independent truth (issue 47, item 1): fem's per
mode against mstmm (the same continuous beam, solved to its root tolerance), the engines'
linearisation part against the other engine of the same chain. Each must cover its error and
stay within 10× of it where the error is resolved (above 1e3·eps of the frequency)."""
import numpy as np
import pytest

from compare import solvers as reg
from compare.analysis.metrics import frequency_errors
from compare.scenes import get_scene

EPS = np.finfo(float).eps
# the defaults and three sets of `xval calibrate SCENE --samples 20 --seed 11` (anisotropic
# shafts at rest: the two planes' symmetric route)
SETS = {"rotating-beam": [{}, {"L": 3.585, "chord": 0.4995, "thickness": 0.046, "rho": 173.8,
                               "E": 4.358e9, "G": 4.944e9},
                          {"L": 7.52, "chord": 0.366, "thickness": 0.0242, "rho": 497.9,
                           "E": 8.991e9, "G": 2.778e9},
                          {"L": 7.2485, "chord": 0.312, "thickness": 0.0399, "rho": 186.24,
                           "E": 8.281e9, "G": 1.8825e9}],
        "spinning-shaft": [{}, {"L": 0.7708, "EI_xx": 582.4, "EI_yy": 671.1, "m": 1.493},
                           {"L": 1.6167, "EI_xx": 426.96, "EI_yy": 352.94, "m": 4.2786}]}
CASES = [(s, o) for s, sets in SETS.items() for o in sets]


def _runs(scene, overrides, names):
    sc = get_scene(scene)
    p = sc.resolve({k: str(v) for k, v in overrides.items()})
    return [reg.modes(sc, reg.get_solver(n), p) for n in names]


@pytest.mark.parametrize("scene, overrides", CASES, ids=str)
def test_fem_bars_cover_its_distance_to_mstmm_per_mode(scene, overrides):
    ref, fem = _runs(scene, overrides, ("mstmm", "fem"))
    f_ref = dict(zip(ref.labels, ref.frequencies_hz))
    resolved = []
    for lb, f, e in zip(fem.labels, fem.frequencies_hz, frequency_errors(fem)):
        true = abs(f - f_ref[lb])
        assert true <= e, (lb, true / f, e / f)
        if true > 1e3 * EPS * f:
            resolved.append(e / true)
    # sharp where resolved: the bar no wider than 10 × the error at the median mode
    assert not resolved or np.median(resolved) <= 10, resolved


@pytest.mark.parametrize("scene, overrides", CASES, ids=str)
def test_engines_differ_by_their_linearisation_bars(scene, overrides):
    """Two engines of one chain share its discretisation error; what is left between them is
    each one's linearisation (the finite-difference step) and round-off under the scene's
    floor (1e-11 of the frequency)."""
    a, b = _runs(scene, overrides, ("exudyn", "mujoco"))
    fb = dict(zip(b.labels, b.frequencies_hz))
    lb_ = dict(zip(b.labels, frequency_errors(b, linearisation=True)))
    ratios = []
    for lb, f, e in zip(a.labels, a.frequencies_hz, frequency_errors(a, linearisation=True)):
        d, bar = abs(f - fb[lb]), e + lb_[lb]
        assert d <= bar + 1e-11 * f, (lb, d / f, bar / f)
        if d > 1e-11 * f:
            ratios.append(bar / d)
    assert ratios and max(ratios) <= 10, ratios


# `xval calibrate spinning-shaft --samples 20 --seed 11` set 4 (EI_yy = 1.52 EI_xx) and
# `--seed 2027` set 18 (EI_yy = 0.78 EI_xx): along the Campbell sweep the forward whirl 2's
# extrapolate from N/2 and N changes sign of its residual near Ω* = 20 and 18, where the
# claimed seventh of the two extrapolates' difference fell short
SHAFT_SETS = {"seed 11 set 4": {"L": "1.6336424203133195", "EI_xx": "593.0898211735569",
                                "EI_yy": "904.3986614940769", "m": "3.0720491001409314"},
              "seed 2027 set 18": {"L": "0.8768578457860732", "EI_xx": "742.9310721441515",
                                   "EI_yy": "578.7702229370227", "m": "3.725768199342856"}}


@pytest.mark.parametrize("engine", ["exudyn", "mujoco"])
@pytest.mark.parametrize("where, spin, within", [("seed 11 set 4", 20.0, None),
                                                 ("seed 11 set 4", 19.5, 5.0),
                                                 ("seed 2027 set 18", 18.0, None)])
def test_an_extrapolate_whose_residual_is_no_one_order_is_not_claimed_a_seventh(
        engine, where, spin, within):
    """The chain's successive extrapolates (N/8–N/4, N/4–N/2, N/2–N) differ by ratios 16–34 where
    an order-4/5 residual rules (the claim holds with true/claimed 0.44–0.47); by −91 at
    seed 11 set 4, Ω* = 20, where the extrapolate was 2.26e-6 Hz off mstmm against a claim of
    1.67e-6, and by −5079 at seed 2027 set 18, Ω* = 18, where the two extrapolates were 8e-7
    apart and the N/2–N one 5.1e-6 off: the difference itself small by chance. The bar covers
    both; at Ω* = 19.5 (ratio 27) the claim stands, within 5× of the true error (unclaimed it
    would be 18×)."""
    sc = get_scene("spinning-shaft")
    p = sc.resolve({**SHAFT_SETS[where], "spin_ratio": str(spin)})
    ref, run = (reg.modes(sc, reg.get_solver(n), p) for n in ("mstmm", engine))
    j = run.labels.index("forward whirl 2")
    true = abs(run.frequencies_hz[j] - ref.frequencies_hz[ref.labels.index("forward whirl 2")])
    bar = frequency_errors(run)[j]
    assert true <= bar, (spin, true, bar)
    assert within is None or bar <= within * true, (spin, true, bar)


# `xval calibrate rotating-beam --samples 20 --seed 2027` set 18: a 9.77 m blade 21 mm thick;
# at speed its tension leaves bending a boundary layer the meshes resolve late
THIN_BLADE = {"L": "9.765235440513687", "chord": "0.2579820745333124",
              "thickness": "0.020911003793247927", "rho": "342.28163425644",
              "E": "4149548164.4080696", "G": "2794113381.1665325"}


@pytest.mark.parametrize("speed", [20.0, 38.0, 40.0])
def test_fems_bar_reads_the_order_its_meshes_converge_at(speed):
    """fem's flap extrapolates converge at q = 8.5 → 20.6 → 64 (successive distances, from
    n = 48) at 38 rad/s, not the h⁶ term's 64 its /63 claimed: 1.87e-5 Hz off mstmm against a
    bar of 1.8e-5 (`xval calibrate rotating-beam --seed 2027 --campbell`: 4 sweep
    disagreements). Over q − 1 where the n/4 mesh shows q < 48, the bars cover every mode and
    stay within 10× of the true error of the flap modes."""
    sc = get_scene("rotating-beam")
    p = sc.resolve({**THIN_BLADE, "speed": str(speed)})
    ref, fem = (reg.modes(sc, reg.get_solver(n), p) for n in ("mstmm", "fem"))
    f_ref = dict(zip(ref.labels, ref.frequencies_hz))
    for lb, f, e in zip(fem.labels, fem.frequencies_hz, frequency_errors(fem)):
        true = abs(f - f_ref[lb])
        assert true <= e, (lb, true, e)
        assert not lb.startswith("flap") or e <= 10 * true, (lb, true, e)
