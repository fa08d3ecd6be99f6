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
    """Global K_EI, K_T (∫T y'²), M for a Hermite mesh, dofs [y0, y0', y1, y1', …]; the
    element matrices of all elements at once (`tension` is called with arrays of x)."""
    nodes = np.asarray(nodes, float)
    x0, h = nodes[:-1], np.diff(nodes)
    Ke = np.zeros((len(h), 4, 4))
    KTe = np.zeros_like(Ke)
    Me = np.zeros_like(Ke)
    for xg, wg in zip(GAUSS_X, GAUSS_W):
        xi = 0.5 * (xg + 1)
        w = 0.5 * wg * h
        N, dN, ddN = hermite(xi, h)                      # each (4, elements)
        Ke += np.einsum("e,ie,je->eij", w * EI, ddN, ddN)
        Me += np.einsum("e,ie,je->eij", w * m, N, N)
        if tension is not None:
            T = np.broadcast_to(tension(x0 + xi * h), h.shape)
            KTe += np.einsum("e,ie,je->eij", w * T, dN, dN)
    return tuple(assemble(E, 2) for E in (Ke, KTe, Me))


def assemble(E, step):
    """Global matrix of element matrices E (elements, k, k) whose dofs start `step` apart."""
    k = E.shape[1]
    n = step * (len(E) - 1) + k
    G = np.zeros((n, n))
    for e, Ee in enumerate(E):
        G[step * e:step * e + k, step * e:step * e + k] += Ee
    return G


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
