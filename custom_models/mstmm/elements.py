"""Element transfer matrices of the MSTMM (seed 002), numba-compiled.

State at a cut, in the element's local axes (x along the beam):
    Z = [X, Y, Z, Θx, Θy, Θz, Mx, My, Mz, Qx, Qy, Qz]
displacements, small rotations (right-handed), and the section resultants: the moment M and
force Q that the part beyond the cut (larger x) exerts on the part before it. With these
signs a free end has M = Q = 0 and a rigid body simply adds the resultants of its inputs.

Beam kinematics and resultants (T(x) the axial tension, e.g. centrifugal):
    flap  (w = Z):  Θy = −w',  My = −EI w'',  Qz = −EI w''' + T w'
    lag   (v = Y):  Θz =  v',  Mz =  EI v'',  Qy = −EI v''' + T v'
    torsion:        Mx = GJ Θx',  Mx' + I_α(ω² − Ω²) Θx = 0       (paper eq. 30)
                    or Mx = (GJ + T k_A²) Θx' with the tension–torsion term (k_A2 > 0)
    axial (u = X):  Qx = EA u',   Qx' + m̄(ω² + Ω²) u = 0        (spin softening)
and the bending equation EI y'''' − (T y')' − k y = 0 with k = m̄ω² (flap) or m̄(ω² + Ω²)
(lag, the paper's eq. 28 with its −Ω² m̄ y term).

The rotating-blade bending matrix is the paper's D(l2)D(l1)⁻¹ by the Frobenius power series
(eqs. 16-27), taken per segment: the series is expanded at each segment's start (where D is
the identity up to the resultant map) and the blade is cut into segments short enough that the
series keeps its digits (≤ 1.5 wavelengths/2π per segment, see `n_segments`). The paper's
single series over the whole blade loses all digits near the 20th mode (terms ~ e^{βL}/…).
"""
import numba as nb
import numpy as np

# state indices (paper order)
X, Y, Z, TX, TY, TZ, MX, MY, MZ, QX, QY, QZ = range(12)
FLAP = np.array([Z, TY, MY, QZ])
LAG = np.array([Y, TZ, MZ, QY])
TORSION = np.array([TX, MX])
AXIAL = np.array([X, QX])


@nb.njit(cache=True)
def series_derivative_transfer(EI, k, f0, f1, f2, s):
    """4x4 P: [y, y', y'', y'''](s) = P [y, y', y'', y'''](0) for EI y'''' − (T y')' − k y = 0
    with T(s) = f0 + f1 s + f2 s² (power series about s = 0, summed until the terms vanish).
    The coefficients are carried scaled by sⁿ (a_n = c_n sⁿ), so no powers are formed."""
    P = np.zeros((4, 4))
    nmax = 400
    a = np.zeros(nmax + 4)
    g0, g1, g2 = f0 * s * s / EI, f1 * s * s * s / EI, f2 * s ** 4 / EI
    kk = k * s ** 4 / EI
    for j in range(4):
        a[:] = 0.0
        fact = 1.0
        for i in range(1, j + 1):
            fact *= i
        a[j] = s ** j / fact                   # y^(j)(0) = 1, others 0
        val = np.zeros(4)
        biggest = 0.0
        small_run = 0
        for n in range(nmax):
            if n >= 4:
                m = n - 4
                a[n] = (g0 * (m + 2) * (m + 1) * a[m + 2] + g1 * (m + 1) ** 2 * a[m + 1]
                        + (g2 * m * (m + 1) + kk) * a[m]) / ((m + 1) * (m + 2) * (m + 3)
                                                             * (m + 4))
            an = a[n]
            val[0] += an
            val[1] += n * an
            val[2] += n * (n - 1) * an
            val[3] += n * (n - 1) * (n - 2) * an
            size = abs(n * (n - 1) * (n - 2) * an) + abs(an)
            for d in range(4):
                biggest = max(biggest, abs(val[d]))
            if n > 8 and size <= 1e-18 * biggest:
                small_run += 1
                if small_run >= 4:
                    break
            else:
                small_run = 0
        # y^(d)(s) = sum n!/(n-d)! c_n s^(n-d) = (sum n!/(n-d)! a_n) / s^d
        P[0, j] = val[0]
        P[1, j] = val[1] / s
        P[2, j] = val[2] / (s * s)
        P[3, j] = val[3] / (s * s * s)
    return P


# explicit signatures: called with the constants True/False, numba would also compile a
# Literal[bool] version of these and of everything they call (~3 s more on a fresh clone)
@nb.njit(nb.float64[:, ::1](nb.float64, nb.float64, nb.boolean), cache=True)
def resultant_map(EI, T, flap):
    """C: state (disp, rot, moment, force) = C [y, y', y'', y''']."""
    C = np.zeros((4, 4))
    C[0, 0] = 1.0
    sgn = -1.0 if flap else 1.0
    C[1, 1] = sgn
    C[2, 2] = sgn * EI
    C[3, 1] = T
    C[3, 3] = -EI
    return C


@nb.njit(cache=True)
def centrifugal_tension(x, m, spin, hub_radius, L):
    """T(x) = m̄Ω²[r_H(L − x) + (L² − x²)/2] (paper eq. 11, free tip F0 = 0), and its
    expansion coefficients about x."""
    w2 = m * spin * spin
    T = w2 * (hub_radius * (L - x) + 0.5 * (L * L - x * x))
    return T, -w2 * (hub_radius + x), -0.5 * w2


@nb.njit(cache=True)
def n_segments(EI, k, Tmax, length):
    """Segments so that each spans ≤ 1.5 rad of the bending wavenumber (k/EI)^¼ and ≤ 3 rad
    of the tension wavenumber √(T/EI): the series then needs ~30 terms and keeps ~15 digits
    (the growth between segments is taken out by the re-orthonormalisation)."""
    beta = (abs(k) / EI) ** 0.25
    kt = np.sqrt(abs(Tmax) / EI)
    return max(1, int(np.ceil(length * max(beta / 1.5, kt / 3.0))))


@nb.njit(nb.float64[:, ::1](nb.float64, nb.float64, nb.float64, nb.float64, nb.float64,
                            nb.float64, nb.float64, nb.float64, nb.boolean), cache=True)
def bending_transfer(EI, m, omega, spin, hub_radius, L, x_a, x_b, flap):
    """4x4 transfer (disp, rot, moment, force) from x_a to x_b (either order) of a rotating
    blade in flap (k = m̄ω²) or lag (k = m̄(ω² + Ω²))."""
    k = m * omega * omega if flap else m * (omega * omega + spin * spin)
    T0, _, _ = centrifugal_tension(0.0, m, spin, hub_radius, L)
    nseg = n_segments(EI, k, T0, abs(x_b - x_a))
    U = np.eye(4)
    h = (x_b - x_a) / nseg
    for i in range(nseg):
        xs = x_a + i * h
        f0, f1, f2 = centrifugal_tension(xs, m, spin, hub_radius, L)
        P = series_derivative_transfer(EI, k, f0, f1, f2, h)
        Te, _, _ = centrifugal_tension(xs + h, m, spin, hub_radius, L)
        Cs = resultant_map(EI, f0, flap)
        Ce = resultant_map(EI, Te, flap)
        U = Ce @ P @ np.linalg.inv(Cs) @ U
    return U


@nb.njit(cache=True)
def second_order_transfer(stiff, g2, s):
    """2x2 transfer of (q, R = stiff·q') for R' + stiff·g2·q = 0 over length s (g2 may be < 0):
    torsion (stiff = GJ, g2 = I_α(ω² − Ω²)/GJ) and axial (EA, m̄(ω² + Ω²)/EA)."""
    U = np.empty((2, 2))
    if g2 > 0:
        g = np.sqrt(g2)
        c, sn = np.cos(g * s), np.sin(g * s)
        U[0, 0], U[0, 1], U[1, 0], U[1, 1] = c, sn / (stiff * g), -stiff * g * sn, c
    elif g2 < 0:
        g = np.sqrt(-g2)
        c, sn = np.cosh(g * s), np.sinh(g * s)
        U[0, 0], U[0, 1], U[1, 0], U[1, 1] = c, sn / (stiff * g), stiff * g * sn, c
    else:
        U[0, 0], U[0, 1], U[1, 0], U[1, 1] = 1.0, s / stiff, 0.0, 1.0
    return U


@nb.njit(cache=True)
def tension_torsion_transfer(GJ, kA2, I_alpha, m, omega, spin, hub_radius, L, x_a, x_b):
    """2x2 transfer of (φ, Mx = p φ') from x_a to x_b for (p φ')' + I_α(ω² − Ω²) φ = 0 with
    p(x) = GJ + k_A² T(x) (tension–torsion term; T quadratic in x). Per segment the power
    series about its start: p0 (n+2)(n+1) a_{n+2} = −[p1 (n+1)² a_{n+1} + (p2 n(n+1) + q) a_n]
    (coefficients scaled by hⁿ). p has its two real roots X1 < 0 and X2 > L (p ≥ GJ on the
    blade, p'' < 0), so each segment is kept to ≤ half their distance d from the blade (the
    series' convergence radius) and ≤ 1.5 rad of the wavenumber √(|q|/GJ)."""
    q = I_alpha * (omega * omega - spin * spin)
    c2 = -0.5 * kA2 * m * spin * spin                # p(x) = c0 + c1 x + c2 x²
    c1 = -kA2 * m * spin * spin * hub_radius
    c0 = GJ + kA2 * m * spin * spin * (hub_radius * L + 0.5 * L * L)
    disc = np.sqrt(c1 * c1 - 4.0 * c2 * c0)
    r1, r2 = (-c1 + disc) / (2.0 * c2), (-c1 - disc) / (2.0 * c2)
    d = min(abs(min(r1, r2)), abs(max(r1, r2) - L))
    span = abs(x_b - x_a)
    if span == 0.0:
        return np.eye(2)
    nseg = max(1, int(np.ceil(max(2.0 * span / d, span * np.sqrt(abs(q) / GJ) / 1.5))))
    h = (x_b - x_a) / nseg
    U = np.eye(2)
    a = np.zeros(404)
    for i in range(nseg):
        xs = x_a + i * h
        p0 = c0 + c1 * xs + c2 * xs * xs
        p1 = (c1 + 2.0 * c2 * xs) * h                # scaled by h, h²: a_n = coeff·hⁿ
        p2 = c2 * h * h
        qq = q * h * h
        P = np.zeros((2, 2))                         # [φ, φ'](h) from [φ, φ'](0)
        for j in range(2):
            a[:] = 0.0
            a[j] = 1.0 if j == 0 else h
            val0, val1, biggest, small_run = 0.0, 0.0, 0.0, 0
            for n in range(400):
                if n >= 2:
                    k = n - 2
                    a[n] = -(p1 * (k + 1) ** 2 * a[k + 1] + (p2 * k * (k + 1) + qq) * a[k]) \
                        / (p0 * (k + 2) * (k + 1))
                val0 += a[n]
                val1 += n * a[n]
                biggest = max(biggest, abs(val0), abs(val1))
                if n > 4 and abs(a[n]) * (n + 1) <= 1e-18 * biggest:
                    small_run += 1
                    if small_run >= 4:
                        break
                else:
                    small_run = 0
            P[0, j] = val0
            P[1, j] = val1 / h
        pe = c0 + c1 * (xs + h) + c2 * (xs + h) ** 2
        Cs = np.array([[1.0, 0.0], [0.0, 1.0 / p0]])     # [φ, φ'] from [φ, Mx]
        Ce = np.array([[1.0, 0.0], [0.0, pe]])
        U = Ce @ P @ Cs @ U
    return U


@nb.njit(cache=True)
def rotating_blade(omega, spin, L, hub_radius, EI_flap, EI_lag, GJ, EA, m, I_alpha, x_a, x_b,
                   kA2):
    """12x12 transfer of a rotating blade (local x = span from the root) from x_a to x_b;
    kA2 > 0 adds the tension–torsion term."""
    U = np.zeros((12, 12))
    B = bending_transfer(EI_flap, m, omega, spin, hub_radius, L, x_a, x_b, True)
    for i in range(4):
        for j in range(4):
            U[FLAP[i], FLAP[j]] = B[i, j]
    B = bending_transfer(EI_lag, m, omega, spin, hub_radius, L, x_a, x_b, False)
    for i in range(4):
        for j in range(4):
            U[LAG[i], LAG[j]] = B[i, j]
    s = x_b - x_a
    if kA2 > 0.0 and spin != 0.0:
        B2 = tension_torsion_transfer(GJ, kA2, I_alpha, m, omega, spin, hub_radius, L, x_a,
                                      x_b)
    else:
        B2 = second_order_transfer(GJ, I_alpha * (omega * omega - spin * spin) / GJ, s)
    for i in range(2):
        for j in range(2):
            U[TORSION[i], TORSION[j]] = B2[i, j]
    B2 = second_order_transfer(EA, m * (omega * omega + spin * spin) / EA, s)
    for i in range(2):
        for j in range(2):
            U[AXIAL[i], AXIAL[j]] = B2[i, j]
    return U


@nb.njit(cache=True)
def orthonormalize(S):
    """Gram–Schmidt with a positive-diagonal R: the basis of the same column space, continuous
    in ω (R > 0 drops only a positive factor from any determinant built on S). Scalar loops:
    the columns of a row-major array are strided, and slicing them cost ~8 µs per 8x4 basis."""
    Q = S.copy()
    rows, cols = Q.shape
    for j in range(cols):
        for _ in range(2):                       # second pass: orthogonal to machine precision
            for i in range(j):
                d = 0.0
                for r in range(rows):
                    d += Q[r, i] * Q[r, j]
                for r in range(rows):
                    Q[r, j] -= d * Q[r, i]
        d = 0.0
        for r in range(rows):
            d += Q[r, j] * Q[r, j]
        d = np.sqrt(d)
        for r in range(rows):
            Q[r, j] /= d
    return Q


@nb.njit(cache=True)
def blade_subspace(omega, spin, L, hub_radius, EI_flap, EI_lag, GJ, EA, m, I_alpha, x_a, x_b,
                   S, scale, kA2):
    """Carry the solution basis S (12 x k, in the scaled state diag(scale)·Z) from x_a to x_b
    segment by segment, re-orthonormalising after each: the growing e^{βx} solutions never
    swamp the decaying ones (the full-span matrix has entries ~e^{βL}, ~1e26 at the 20th flap
    mode, and its 2x2 determinants cancel to nothing)."""
    k = m * (omega * omega + spin * spin)
    T0, _, _ = centrifugal_tension(0.0, m, spin, hub_radius, L)
    nseg = max(n_segments(EI_flap, k, T0, abs(x_b - x_a)),
               n_segments(EI_lag, k, T0, abs(x_b - x_a)))
    h = (x_b - x_a) / nseg
    Q = orthonormalize(S)
    for i in range(nseg):
        U = rotating_blade(omega, spin, L, hub_radius, EI_flap, EI_lag, GJ, EA, m, I_alpha,
                           x_a + i * h, x_a + (i + 1) * h, kA2)
        for r in range(12):
            for c in range(12):
                U[r, c] *= scale[r] / scale[c]
        Q = orthonormalize(U @ Q)
    return Q


@nb.njit(cache=True)
def coupled_fourth_order_transfer(K, s):
    """8x8 E(s): y(s) = E y(0), y = [W, W', W'', W'''] per component of W = [U, V] (order
    U, U', U'', U''', V, …), for W'''' = K W (K 2x2 constant, real, or complex for the spinning
    shaft with e^{iωt}; E has K's dtype): the exponential series Σ Kⁿ s^(4n+j−d)/(4n+j−d)! —
    exact, and short for segments with ‖K‖^¼ s ≤ 1.5."""
    E = np.zeros((8, 8), dtype=K.dtype)
    Kn = np.zeros((2, 2), dtype=K.dtype)
    Kn[0, 0] = 1.0
    Kn[1, 1] = 1.0
    c_p = np.ones(100)                           # s^p / p!
    for p in range(1, 100):
        c_p[p] = c_p[p - 1] * s / p
    for n in range(25):
        for d in range(4):
            for j in range(4):
                p = 4 * n + j - d
                if p >= 0:
                    c = c_p[p]
                    E[d, j] += Kn[0, 0] * c
                    E[d, 4 + j] += Kn[0, 1] * c
                    E[4 + d, j] += Kn[1, 0] * c
                    E[4 + d, 4 + j] += Kn[1, 1] * c
        a, b = Kn[0, 0] * K[0, 0] + Kn[0, 1] * K[1, 0], Kn[0, 0] * K[0, 1] + Kn[0, 1] * K[1, 1]
        c, d = Kn[1, 0] * K[0, 0] + Kn[1, 1] * K[1, 0], Kn[1, 0] * K[0, 1] + Kn[1, 1] * K[1, 1]
        Kn[0, 0], Kn[0, 1], Kn[1, 0], Kn[1, 1] = a, b, c, d     # Kn @ K (no BLAS call for 2x2)
    return E


@nb.njit(cache=True)
def shaft_coupling(EIx, EIy, m, omega, spin):
    """K of the spinning shaft in the whirl ansatz u = U cos ωt, v = V sin ωt (rotating frame,
    physical gyroscopic coupling): [U, V]'''' = K [U, V]."""
    K = np.empty((2, 2))
    a, c = m * (omega * omega + spin * spin), 2.0 * m * spin * omega
    K[0, 0], K[0, 1] = a / EIy, c / EIy
    K[1, 0], K[1, 1] = c / EIx, a / EIx
    return K


@nb.njit(cache=True)
def shaft_tip_det(EIx, EIy, m, L, omega, spin, plane):
    """Characteristic function of the clamped–free spinning shaft (whirl ansatz): the
    clamped-root basis (U'', U''', V'', V''' free) carried to the tip in segments of ≤ 1.5 rad
    wavenumber, re-orthonormalised after each; det of its tip rows U'', U''', V'', V'''.
    plane 0: both planes; 1 (u) or 2 (v): that plane's pair alone (at rest the planes
    decouple, and each has simple roots where together they would give double ones)."""
    beta = (m * (abs(omega) + abs(spin)) ** 2 / min(EIx, EIy)) ** 0.25
    n = max(1, int(np.ceil(beta * L / 1.5)))
    U = coupled_fourth_order_transfer(shaft_coupling(EIx, EIy, m, omega, spin), L / n)
    Q = np.zeros((8, 4))
    Q[2, 0] = Q[3, 1] = Q[6, 2] = Q[7, 3] = 1.0
    for _ in range(n):
        Q = orthonormalize(U @ Q)
    if plane == 0:
        return np.linalg.det(Q[np.array([2, 3, 6, 7]), :])
    c, r = (0, 2) if plane == 1 else (2, 6)      # basis columns stay in their plane at rest
    P = orthonormalize(np.ascontiguousarray(Q[:, c:c + 2]))
    return P[r, 0] * P[r + 1, 1] - P[r, 1] * P[r + 1, 0]


@nb.njit(cache=True)
def spinning_shaft(omega, spin, EI, m, EA, GJ, I_p, x_a, x_b):
    """12x12 complex transfer of the spinning shaft (local x = spin axis) from x_a to x_b,
    u ∝ e^{iωt}, rotating frame, physical gyroscopic coupling:
        EI v'''' + m(v̈ − 2Ωẇ − Ω²v) = 0,   EI w'''' + m(ẅ + 2Ωv̇ − Ω²w) = 0,
    v along local y (lag-like signs), w along local z (flap-like signs); extension and torsion
    about the spin axis as a non-rotating bar."""
    a, c = m * (omega * omega + spin * spin), 2.0 * m * spin * omega
    K = np.empty((2, 2), np.complex128)
    K[0, 0], K[0, 1], K[1, 0], K[1, 1] = a / EI, 1j * c / EI, -1j * c / EI, a / EI
    s = x_b - x_a
    beta = (abs(a + c) / EI) ** 0.25
    n = max(1, int(np.ceil(abs(s) * beta / 1.5)))
    E = np.linalg.matrix_power(coupled_fourth_order_transfer(K, s / n), n)
    # C E C⁻¹ to the (v, w)-state; with no tension the resultant maps are diagonal, so this
    # scales E's rows by C's diagonal and its columns by the inverse's (the roundings of the
    # matrix products: each of their sums has one non-zero term)
    Cv, Cw = resultant_map(EI, 0.0, False), resultant_map(EI, 0.0, True)
    d = np.empty(8)
    for i in range(4):
        d[i], d[4 + i] = Cv[i, i], Cw[i, i]
    idx = np.concatenate((LAG, FLAP))
    U = np.zeros((12, 12), dtype=np.complex128)
    for i in range(8):
        for j in range(8):
            U[idx[i], idx[j]] = d[i] * E[i, j] * (1.0 / d[j])
    Tq = second_order_transfer(GJ, I_p * omega * omega / GJ, s)
    Ax = second_order_transfer(EA, m * omega * omega / EA, s)
    for i in range(2):
        for j in range(2):
            U[TORSION[i], TORSION[j]] = Tq[i, j]
            U[AXIAL[i], AXIAL[j]] = Ax[i, j]
    return U


@nb.njit(cache=True)
def bending_tip_det(EI, m, omega, spin, hub_radius, L, flap):
    """Characteristic function of one bending family of the clamped-free rotating blade: the
    clamped-root basis (moment, force free) carried to the tip with re-orthonormalisation
    after every segment (scaled state: resultants / EI), det of its tip resultant rows."""
    k = m * omega * omega if flap else m * (omega * omega + spin * spin)
    T0, _, _ = centrifugal_tension(0.0, m, spin, hub_radius, L)
    nseg = n_segments(EI, k, T0, L)
    h = L / nseg
    Q = np.zeros((4, 2))
    Q[2, 0] = 1.0
    Q[3, 1] = 1.0
    D = np.array([1.0, 1.0, 1.0 / EI, 1.0 / EI])
    for i in range(nseg):
        xs = i * h
        f0, f1, f2 = centrifugal_tension(xs, m, spin, hub_radius, L)
        P = series_derivative_transfer(EI, k, f0, f1, f2, h)
        Te, _, _ = centrifugal_tension(xs + h, m, spin, hub_radius, L)
        U = resultant_map(EI, Te, flap) @ P @ np.linalg.inv(resultant_map(EI, f0, flap))
        for r in range(4):
            for c in range(4):
                U[r, c] *= D[r] / D[c]
        Q = orthonormalize(U @ Q)
    return Q[2, 0] * Q[3, 1] - Q[2, 1] * Q[3, 0]
