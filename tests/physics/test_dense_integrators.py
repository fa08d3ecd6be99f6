"""Dense-output drivers (`custom_models.integrators.dense`) against closed forms.

The oscillator y'' = −ω²y has y = cos ωt: the output grid is filled by each method's
continuous extension, so every grid value — not just the step ends — must carry the method's
accuracy, and the step must not be capped by the output interval.
"""
import numba as nb
import numpy as np
import pytest

from custom_models.integrators import no_guard
from custom_models.integrators.dense import (
    DENSE_TABLEAUS,
    FIXED,
    integrate_adaptive_dense,
    integrate_fixed_dense,
    solve,
)

W = 3.0


@nb.njit(cache=True)
def oscillator(t, y, p, dy):
    dy[0] = y[1]
    dy[1] = -p[0] * p[0] * y[0]


@nb.njit(cache=True)
def stop_at_half(t, y, p):
    return 11 if t >= 0.5 else 0


def _adaptive(name, t_out, rtol, guard=no_guard):
    tb = DENSE_TABLEAUS[name]
    return integrate_adaptive_dense(oscillator, guard, np.array([1.0, 0.0]), np.array([W]),
                                    t_out, rtol, rtol * 1e-2, 0.0, 10**6, tb["A"], tb["B"],
                                    tb["C"], tb["E"], tb["E3"], tb["err_order"], tb["dense"],
                                    tb["P"], tb["AX"], tb["CX"], tb["D"])


@pytest.mark.parametrize("name, rtol, window", [("dop853", 1e-10, 1e-8), ("dopri5", 1e-8, 1e-6),
                                                ("rk23", 1e-6, 1e-4)])
def test_adaptive_dense_output_matches_closed_form(name, rtol, window):
    t_out = np.linspace(0.0, 10.0, 2001)          # 2000 outputs, far more than steps
    Y, steps, evals, rej, t_fail, code = _adaptive(name, t_out, rtol)
    assert code == 0 and np.isnan(t_fail)
    assert steps < 2000                          # steps are set by rtol, not by the grid
    err = np.max(np.abs(Y[:, 0] - np.cos(W * t_out)))
    # global error of a tolerance-controlled run is a few hundred × rtol over 5 periods; the
    # interpolant must not add more than the steps' own error
    assert err < window


def test_dop853_interpolant_is_as_accurate_as_the_steps():
    # same run sampled on a coarse grid (outputs ≈ step ends) and on a fine one (interpolated):
    # the interpolated values must carry the same accuracy, not a 3rd-order Hermite's
    coarse = np.linspace(0.0, 10.0, 11)
    fine = np.linspace(0.0, 10.0, 4001)
    e_coarse = np.max(np.abs(_adaptive("dop853", coarse, 1e-11)[0][:, 0] - np.cos(W * coarse)))
    e_fine = np.max(np.abs(_adaptive("dop853", fine, 1e-11)[0][:, 0] - np.cos(W * fine)))
    assert e_fine < 10 * max(e_coarse, 1e-12)


def test_fixed_hermite_is_exact_on_step_ends_and_fourth_order_between():
    t_out = np.linspace(0.0, 2.0, 801)            # outputs between the steps
    errs = []
    for dt in (0.02, 0.01):
        tb = FIXED["rk4"]
        Y, steps, evals, t_fail, code = integrate_fixed_dense(
            oscillator, no_guard, np.array([1.0, 0.0]), np.array([W]), t_out, dt,
            tb["A"], tb["B"], tb["C"])
        assert code == 0 and steps == round(2.0 / dt) and evals == 4 * steps + 1
        errs.append(np.max(np.abs(Y[:, 0] - np.cos(W * t_out))))
    order = np.log2(errs[0] / errs[1])
    assert 3.5 < order < 4.5                     # RK4 steps + cubic Hermite (local O(h⁴))


def test_guard_stops_on_the_step_and_leaves_nan():
    t_out = np.linspace(0.0, 1.0, 101)
    Y, steps, evals, rej, t_fail, code = _adaptive("dop853", t_out, 1e-8, stop_at_half)
    assert code == 11 and 0.5 <= t_fail < 1.0
    assert np.all(np.isnan(Y[t_out > t_fail]))
    # the rows of the failed step are not written either: the finite rows are a prefix that
    # ends inside the steps accepted before it
    ok = np.isfinite(Y).all(axis=1)
    n_ok = int(ok.sum())
    assert ok[:n_ok].all() and 0.2 < t_out[n_ok - 1] < 0.5


def test_solve_with_first_class_values_matches_the_plain_drivers():
    """`solve` hands the drivers `first_class` values (address looked up once): the same
    machine code runs, so the trajectory is the plain driver's bit for bit, and y = cos ωt to
    rk4's accuracy (h = 1e-3: (ωh)^4 ≈ 1e-10 per unit time, measured 1.2e-12)."""
    t_out = np.linspace(0.0, 1.0, 11)
    tb = FIXED["rk4"]
    Y0 = integrate_fixed_dense(oscillator, no_guard, np.array([1.0, 0.0]), np.array([W]), t_out,
                               1e-3, tb["A"], tb["B"], tb["C"])[0]
    Y, stats, t_fail, code, used = solve(oscillator, no_guard, np.array([1.0, 0.0]),
                                         np.array([W]), t_out, "rk4", dt=1e-3)
    assert code == 0 and np.array_equal(Y, Y0)
    assert stats["rhs_evals"] == 4 * 1000 + 1 and stats["integrate_s"] > 0
    assert np.max(np.abs(Y[:, 0] - np.cos(W * t_out))) < 1e-10


def test_the_tableaus_are_scipys():
    """custom_models.integrators.tableaus gives scipy's numbers without importing
    scipy.integrate (RK23 and RK45 written out, DOP853 read from scipy's coefficient file):
    every array equal to scipy.integrate's public class attribute, bit for bit. Seeded: one
    digit of RK45's P changed, DOP853's extra stages taken from row N_STAGES — each fails."""
    import scipy.integrate as si

    from custom_models.integrators import tableaus
    for name, fields in (("RK23", "A B C E P"), ("RK45", "A B C E P"),
                         ("DOP853", "A B C E3 E5 D A_EXTRA C_EXTRA")):
        for f in fields.split():
            ours, theirs = getattr(getattr(tableaus, name), f), getattr(getattr(si, name), f)
            assert ours.shape == theirs.shape and np.array_equal(ours, theirs), (name, f)
