"""compare.physics.trig against libm (numpy's sin, cos, arctan2): the rotor kernels' elementary
functions, written so that LLVM can vectorise them, must give libm's numbers to round-off.

Measured (10⁶ random arguments per range): at most 2 ulp of the result for sin, cos and atan2;
cos reaches 4 ulp only for |x| near 1e9, beyond any angle the models form."""
import numba as nb
import numpy as np
import pytest

from compare.physics.trig import LOSS, atan2, sincos

ULP = 2


@nb.njit(error_model="numpy")
def _sincos(x):
    s, c = np.empty_like(x), np.empty_like(x)
    for i in range(x.shape[0]):
        s[i], c[i] = sincos(x[i])
    return s, c


@nb.njit(error_model="numpy")
def _atan2(y, x):
    out = np.empty_like(x)
    for i in range(x.shape[0]):
        out[i] = atan2(y[i], x[i])
    return out


def _ulps(got, ref):
    return np.max(np.abs(got - ref) / np.spacing(np.abs(ref)))


@pytest.mark.parametrize("span", [4.0, 1e3, 1e6])
def test_sin_and_cos_are_libms_within_2_ulp(span):
    x = np.random.default_rng(7).uniform(-span, span, 200_000)
    s, c = _sincos(x)
    assert _ulps(s, np.sin(x)) <= ULP
    assert _ulps(c, np.cos(x)) <= ULP


def test_sin_and_cos_at_the_octants_edges():
    """At x = kπ/4 the reduction's remainder is exact but for π/4's own three-part split:
    where sin or cos is zero its error is absolute, ≤ 1e-30 |x| (measured 2.8e-31 |x| up to
    |x| = 2.4e5); elsewhere ≤ 2 ulp."""
    x = np.arange(-300_000, 300_001) * (np.pi / 4)
    for got, ref in zip(_sincos(x), (np.sin(x), np.cos(x))):
        zero = np.abs(ref) < 1e-8
        assert np.all(np.abs(got - ref)[zero] <= 1e-30 * np.abs(x[zero]))
        assert _ulps(got[~zero], ref[~zero]) <= ULP


def test_sin_and_cos_at_the_edges():
    s, c = _sincos(np.array([0.0, -0.0, 1e-300, -1e-300]))
    assert np.array_equal(np.signbit(s), [False, True, False, True])    # sin is odd
    assert np.array_equal(s, [0.0, -0.0, 1e-300, -1e-300]) and np.all(c == 1.0)
    s, c = _sincos(np.array([np.nan, np.inf, -np.inf, LOSS, -2 * LOSS]))
    assert np.all(np.isnan(s)) and np.all(np.isnan(c))     # no silent noise past the reduction


@pytest.mark.parametrize("scale", [1e-5, 1.0, 1e5])
def test_atan2_is_libms_within_2_ulp(scale):
    rng = np.random.default_rng(11)
    y, x = rng.normal(size=(2, 200_000)) * scale
    assert _ulps(_atan2(y, x), np.arctan2(y, x)) <= ULP


def test_atan2_on_the_axes_and_signed_zeros_is_libms():
    y = np.array([0.0, -0.0, 0.0, -0.0, 1.0, -1.0, 0.0, -0.0, 2.0, -2.0, 1.0, 1.0])
    x = np.array([0.0, 0.0, -0.0, -0.0, 0.0, 0.0, -1.0, -1.0, 2.0, -2.0, 1e-300, -1e300])
    got, ref = _atan2(y, x), np.arctan2(y, x)
    assert np.array_equal(got, ref) and np.array_equal(np.signbit(got), np.signbit(ref))
