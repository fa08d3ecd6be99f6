"""sin, cos and atan2 that LLVM can vectorise: the rotor's right-hand sides and row reduce on
the SIMD lanes (`integrators.lanes`).

numba calls libm for np.sin, np.cos and np.arctan2, and the pip build of llvmlite has no SVML
to give those calls vector variants (`numba -s`: "SVML State False"): the loops over the lanes
vectorised around them, one scalar libm call per lane (atan2 was 16 % of a cheap quaternion map
point under perf). These are Cephes' double-precision algorithms (S. L. Moshier, "Methods and
Programs for Mathematical Functions", 1989; netlib cephes/double sin.c and atan.c) written with
selects instead of branches: only arithmetic, floor, sqrt and copysign, all of which vectorise.
Measured in one process against the libm build (ns a lane, AMD EPYC, AVX2): quaternion
right-hand side 40 → 19, row reduce 48 → 19; euler-vector 53 → 30 and 91 → 48. Cephes' atan adds
the bits of π/2 below its double (MOREBITS) back in; measured against libm that made more
results differ (28 % against 26 %, each within 2 ulp), so it is left out.
tests/physics/test_trig.py holds them to libm within 2 ulp over the ranges the models use.
"""
import numba as nb
import numpy as np

# the scalar/tuple helpers of the right-hand sides, inlined at numba's level: left to LLVM's
# inliner they came too late for the loop vectoriser of `integrators.lanes`. Inlined, they take
# their caller's error model: numpy's in the lane loops (a zero divisor gives inf/NaN, no
# division check to keep the loop scalar), python's in the scalar right-hand sides
tuple_math = nb.njit(cache=True, inline="always")

_PIO2, _PIO4 = np.pi / 2, np.pi / 4
# π/4 in three parts for the argument reduction (Cody and Waite): y·_DP1 and y·_DP2 are exact
# for the multiples y of π/4 up to LOSS (2^30, Cephes' `lossth`)
_DP1, _DP2, _DP3 = 7.85398125648498535156e-1, 3.77489470793079817668e-8, \
    2.69515142907905952645e-15
LOSS = 1.073741824e9       # |x| beyond which the reduction loses the result: NaN, not noise


@tuple_math
def _sin_poly(z, zz):
    return z + z * (zz * (((((1.58962301576546568060e-10 * zz - 2.50507477628578072866e-8) * zz
                               + 2.75573136213857245213e-6) * zz
                              - 1.98412698295895385996e-4) * zz
                             + 8.33333333332211858878e-3) * zz
                            - 1.66666666666666307295e-1))


@tuple_math
def _cos_poly(zz):
    return 1.0 - 0.5 * zz + zz * zz * (((((-1.13585365213876817300e-11 * zz
                                            + 2.08757008419747316778e-9) * zz
                                           - 2.75573141792967388112e-7) * zz
                                          + 2.48015872888517045348e-5) * zz
                                         - 1.38888888888730564116e-3) * zz
                                        + 4.16666666666665929218e-2)


@tuple_math
def sincos(x):
    """(sin x, cos x), |x| < LOSS (beyond it, and for a non-finite x: NaN)."""
    ax = abs(x)
    y = np.floor(ax / _PIO4)                 # the octant, made even: z in [−π/4, π/4]
    j = y - 8.0 * np.floor(y * 0.125)
    odd = j - 2.0 * np.floor(j * 0.5)
    y += odd
    j = j + odd
    j = j - 8.0 * np.floor(j * 0.125)        # 0, 2, 4 or 6
    z = ((ax - y * _DP1) - y * _DP2) - y * _DP3
    zz = z * z
    ps, pc = _sin_poly(z, zz), _cos_poly(zz)
    s = ps if j == 0.0 else (pc if j == 2.0 else (-ps if j == 4.0 else -pc))
    c = pc if j == 0.0 else (-ps if j == 2.0 else (-pc if j == 4.0 else ps))
    s *= np.copysign(1.0, x)                 # sin is odd
    nan = not ax < LOSS
    return (np.nan if nan else s), (np.nan if nan else c)


@tuple_math
def _atan01(t):
    """atan t for 0 ≤ t ≤ 1 (Cephes' two lower ranges)."""
    big = t > 0.66
    x = (t - 1.0) / (t + 1.0) if big else t
    z = x * x
    p = ((((-8.750608600031904122785e-1 * z - 1.615753718733365076637e1) * z
           - 7.500855792314704667340e1) * z - 1.228866684490136173410e2) * z
         - 6.485021904942025371773e1)
    q = (((((z + 2.485846490142306297962e1) * z + 1.650270098316988542046e2) * z
           + 4.328810604912902668951e2) * z + 4.853903996359136964868e2) * z
         + 1.945506571482613964425e2)
    r = x * (z * p / q) + x
    return (_PIO4 + r) if big else r


@tuple_math
def atan2(y, x):
    """The angle of (x, y) in [−π, π], as np.arctan2 for finite arguments (signed zeros
    included)."""
    a, b = abs(y), abs(x)
    steep = a > b
    lo, hi = (b, a) if steep else (a, b)
    r = _atan01(lo / hi if hi > 0.0 else 0.0)
    r = (_PIO2 - r) if steep else r
    r = (np.pi - r) if np.copysign(1.0, x) < 0.0 else r
    return np.copysign(r, y)
