"""Element matrices on a 1-D mesh, assembled by Gauss quadrature (exact for the polynomial
coefficients used here: tension quadratic in x).

bending(): Hermite cubic, dofs (y, y') per node; ∫EI N''N'', ∫T N'N', ∫m N N.
second_order(): quadratic Lagrange (3 nodes per element), ∫k N'N', ∫c N N — torsion and
extension converge at h⁴ in frequency like the Hermite bending elements; k may vary along x
(the tension–torsion stiffness GJ + T(x)k_A², quadratic: still integrated exactly).
"""
import numpy as np

GAUSS_X, GAUSS_W = np.polynomial.legendre.leggauss(5)


def hermite(xi, h):
    """Hermite shape functions on [0, h] at ξ ∈ [0, 1]: N, N', N'' (h may be an array of
    element lengths: each then (4, elements))."""
    one = np.ones_like(h)
    N = np.array([(1 - 3 * xi**2 + 2 * xi**3) * one, h * (xi - 2 * xi**2 + xi**3),
                  (3 * xi**2 - 2 * xi**3) * one, h * (-xi**2 + xi**3)])
    dN = np.array([(-6 * xi + 6 * xi**2) * one, h * (1 - 4 * xi + 3 * xi**2),
                   (6 * xi - 6 * xi**2) * one, h * (-2 * xi + 3 * xi**2)]) / h
    ddN = np.array([(-6 + 12 * xi) * one, h * (-4 + 6 * xi), (6 - 12 * xi) * one,
                    h * (-2 + 6 * xi)]) / h**2
    return N, dN, ddN


def bending(nodes, EI, m, tension=None):
    """Global K_EI, K_T (∫T y'²), M for a Hermite mesh, dofs [y0, y0', y1, y1', …]. The
    Gauss-point terms of all elements are formed at once, then added element by element and
    point by point: the summation order of a plain loop, so the matrices are the same to the
    last bit (the helicopter's fem frequencies move by 4e-8 if the order changes)."""
    nodes = np.asarray(nodes, float)
    x0, h = nodes[:-1], np.diff(nodes)
    terms = {"K": [], "KT": [], "M": []}
    for xg, wg in zip(GAUSS_X, GAUSS_W):
        xi = 0.5 * (xg + 1)
        w = 0.5 * wg * h
        N, dN, ddN = hermite(xi, h)                      # each (4, elements)
        terms["K"].append(outer(w * EI, ddN))
        terms["M"].append(outer(w * m, N))
        if tension is not None:
            # called per point as in a plain loop (x**2 of a scalar and of an array may
            # round differently)
            T = np.array([tension(x) for x in x0 + xi * h], float)
            terms["KT"].append(outer(w * T, dN))
    n = 2 * len(nodes)
    K, KT, M = np.zeros((n, n)), np.zeros((n, n)), np.zeros((n, n))
    for e in range(len(h)):
        idx = slice(2 * e, 2 * e + 4)
        for g in range(len(GAUSS_X)):
            K[idx, idx] += terms["K"][g][e]
            M[idx, idx] += terms["M"][g][e]
            if tension is not None:
                KT[idx, idx] += terms["KT"][g][e]
    return K, KT, M


def bending_rayleigh(nodes, EI, m, X, tension=None):
    """(∫EI y''² + ∫T y'²)/∫m y² of each column of X (dofs of every node, as `bending`),
    summed element by element from the curvatures and slopes at the Gauss points: the Rayleigh
    quotient of a computed eigenvector, exact to second order in the vector's error, without
    the cancellation of forming K·x (a smooth low mode's K·x cancels to eps·λ_max: the solver's
    own λ₁ off by up to 1e-8 at 96 elements, this quotient by 1e-13)."""
    nodes = np.asarray(nodes, float)
    x0, h = nodes[:-1], np.diff(nodes)
    Xe = X[2 * np.arange(len(h))[:, None] + np.arange(4)[None, :]]      # (elements, 4, k)
    energy, mass = np.zeros(X.shape[1]), np.zeros(X.shape[1])
    for xg, wg in zip(GAUSS_X, GAUSS_W):
        xi = 0.5 * (xg + 1)
        w = 0.5 * wg * h
        N, dN, ddN = hermite(xi, h)
        curv, slope, y = (np.einsum("ie,eik->ek", f, Xe) for f in (ddN, dN, N))
        energy += np.sum((w * EI)[:, None] * curv**2, axis=0)
        if tension is not None:
            T = np.array([tension(x) for x in x0 + xi * h], float)
            energy += np.sum((w * T)[:, None] * slope**2, axis=0)
        mass += np.sum((w * m)[:, None] * y**2, axis=0)
    return energy / mass


def outer(scale, f):
    """scale_e · f_i f_j per element e, (elements, 4, 4), rounded as scale · np.outer(f, f)."""
    scale = np.broadcast_to(scale, f.shape[1:])
    return scale[:, None, None] * (f.T[:, :, None] * f.T[:, None, :])


def quadratic_nodes(n_el, L):
    return np.linspace(0.0, L, 2 * n_el + 1)


def second_order(n_el, L, stiff, inertia, extra=None):
    """K = ∫(stiff + extra(x)) q'², M = ∫inertia q² with quadratic elements (2·n_el + 1
    nodes); `extra` e.g. the tension–torsion stiffness T(x)·k_A²."""
    nn = 2 * n_el + 1
    K = np.zeros((nn, nn))
    M = np.zeros_like(K)
    h = L / n_el
    for e in range(n_el):
        idx = slice(2 * e, 2 * e + 3)
        for xg, wg in zip(GAUSS_X, GAUSS_W):
            xi = 0.5 * (xg + 1)
            w = 0.5 * wg * h
            N = np.array([2 * (xi - 0.5) * (xi - 1), -4 * xi * (xi - 1), 2 * xi * (xi - 0.5)])
            dN = np.array([4 * xi - 3, -8 * xi + 4, 4 * xi - 1]) / h
            k = stiff + (extra(e * h + xi * h) if extra is not None else 0.0)
            K[idx, idx] += w * k * np.outer(dN, dN)
            M[idx, idx] += w * inertia * np.outer(N, N)
    return K, M


def lowest_modes(K, M, count, shift=0.0):
    """Lowest `count` eigenpairs of K x = ω² M x, accurate in the low modes: solved as
    M x = μ (K + shift·M) x for the largest μ = 1/(ω² + shift) (the direct form loses the low
    modes' digits on fine meshes, where λ_max/λ_1 ~ n⁴). `shift` makes K + shift·M positive
    definite (e.g. Ω² for the lag softening)."""
    from scipy.linalg import eigh
    n = K.shape[0]
    count = min(count, n)
    mu, V = eigh(M, K + shift * M, subset_by_index=[n - count, n - 1])
    lam = 1.0 / mu[::-1] - shift
    return lam, V[:, ::-1]
