"""`fem` leaf for `spinning-shaft`: Hermite cubic elements in both bending planes, rotating
frame, with the gyroscopic matrix of the physical Coriolis terms and the spin softening:
    M q̈ + Ω G q̇ + (K − Ω² M) q = 0,   G = 2 [[0, −M_b], [M_b, 0]] (u, v blocks).
Isotropic (K_u = K_v = K_b): w = u + i v turns this exactly into M_b ẅ + 2iΩ M_b ẇ +
(K_b − Ω² M_b) w = 0, whose roots w ∝ e^{iσt} are σ = ±ν − Ω with K_b W = ν² M_b W, the
shaft at rest — one symmetric eigenproblem of one plane. Anisotropic: solved as the
quadratic eigenproblem in μ = 1/λ (K μ² + Ω G μ + M = 0, linearised), which keeps the low
modes' digits. Eigenvalues with Re λ > 0 (static divergence inside an anisotropic
instability band) are reported in notes and extra["unstable"], not as frequencies.
Convergence: n and 2n elements, Richardson h⁴ extrapolation of the frequencies; the error
estimate per mode its distance to the n/2–n extrapolate.
"""
import numpy as np
from scipy.linalg import eig, eigvals

from compare.contract import LeafModes, merge_settings
from compare.physics.mstmm import spinning_shaft_omega0
from compare.physics.whirl import whirl_labels

from .beam import bending, bending_rayleigh, lowest_modes
from .blade import richardson_pair

MODES_SETTINGS = {"elements": 24, "stations": 13, "richardson": True}


def plane(nodes, EI, m):
    """K, M of one bending plane, root clamped."""
    K, _, M = bending(nodes, EI, m)
    return K[2:, 2:], M[2:, 2:]


def isotropic_eigen(p, nodes, spin):
    """λ = iσ and eigenvectors [u; v] of the isotropic shaft, sorted by |λ|: each ν gives
    σ = ν − Ω and −ν − Ω; a root with σ < 0 is kept as its conjugate (|σ|, [W; iW])."""
    K, M = plane(nodes, p["EI_xx"], p["m"])
    n = K.shape[0]
    nu2, W = lowest_modes(K, M, n)
    # each ν² as its vector's Rayleigh quotient from the curvatures (beam.py): the solver's own
    # carries the round-off of K·x, ∝ the conditioning (n⁴)
    nu2 = bending_rayleigh(nodes, p["EI_xx"], p["m"], np.vstack([np.zeros((2, n)), W]))
    nu = np.sqrt(nu2)
    sigma = np.concatenate([nu - spin, -nu - spin])
    if spin == 0:                 # planes decoupled: one planar mode in each ([W; 0], [0; W])
        V = np.block([[W, np.zeros_like(W)], [np.zeros_like(W), W]]).astype(complex)
    else:                         # circular whirl: u = W cos σt, v = W sin σt
        W2 = np.concatenate([W, W], axis=1)
        V = np.concatenate([W2, -1j * np.sign(sigma) * W2])
    keep = np.abs(sigma) > 1e-9 * np.concatenate([nu, nu])    # σ = 0: static, no frequency
    order = np.argsort(np.abs(sigma[keep]), kind="stable")
    return 1j * np.abs(sigma[keep][order]), V[:, keep][:, order], n


def state_eigen(p, nodes, spin, vectors=True):
    """λ (rad/s, complex) and eigenvectors of M λ² + G λ + K = 0, sorted by |λ|."""
    Ku, Mb = plane(nodes, p["EI_yy"], p["m"])
    Kv, _ = plane(nodes, p["EI_xx"], p["m"])
    n = Mb.shape[0]
    Z = np.zeros((n, n))
    M = np.block([[Mb, Z], [Z, Mb]])
    K = np.block([[Ku, Z], [Z, Kv]]) - spin**2 * M
    G = 2 * spin * np.block([[Z, -Mb], [Mb, Z]])
    N = 2 * n
    A = np.block([[np.zeros((N, N)), np.eye(N)],
                  [-np.linalg.solve(K, M), -np.linalg.solve(K, G)]])
    mu, V = eig(A) if vectors else (eigvals(A), np.zeros((2 * N, 2 * N)))
    lam = 1.0 / mu
    order = np.argsort(np.abs(lam))
    return lam[order], V[:N, order], n


def planes_at_rest(p, nodes):
    """λ = iν and eigenvectors [u; v] of the anisotropic shaft at rest, sorted by ν: its two
    bending planes decouple, each one symmetric problem (ν² its vector's Rayleigh quotient, as
    `isotropic_eigen`) instead of the state space's unsymmetric one."""
    parts = []
    for EI in (p["EI_yy"], p["EI_xx"]):                 # u, then v
        K, M = plane(nodes, EI, p["m"])
        n = K.shape[0]
        _, W = lowest_modes(K, M, n)
        parts.append((np.sqrt(bending_rayleigh(nodes, EI, p["m"],
                                               np.vstack([np.zeros((2, n)), W]))), W))
    (nu_u, Wu), (nu_v, Wv) = parts
    Z = np.zeros_like(Wu)
    V = np.block([[Wu, Z], [Z, Wv]]).astype(complex)
    nu = np.concatenate([nu_u, nu_v])
    order = np.argsort(nu, kind="stable")
    return 1j * nu[order], V[:, order], n


def solve(p, n_el, spin, n_modes, vectors=True):
    nodes = np.linspace(0.0, p["L"], n_el + 1)
    if p["EI_xx"] == p["EI_yy"]:
        lam, V, n = isotropic_eigen(p, nodes, spin)
    elif spin == 0:
        lam, V, n = planes_at_rest(p, nodes)
    else:
        lam, V, n = state_eigen(p, nodes, spin, vectors)
    keep = [i for i in range(len(lam)) if lam[i].imag > 1e-9 * abs(lam[i])]
    unstable = [float(lam[i].real) for i in range(len(lam))
                if lam[i].real > 1e-9 * abs(lam[i]) and abs(lam[i].imag) <= 1e-9 * abs(lam[i])]
    keep = keep[:n_modes]
    return np.array([lam[i].imag for i in keep]), V[:, keep], n, unstable


def modes(params: dict, settings: dict) -> LeafModes:
    s = merge_settings(settings, MODES_SETTINGS, ())
    p = params
    w0 = spinning_shaft_omega0(p["EI_xx"], p["m"], p["L"])
    spin = p["spin_ratio"] * w0
    n_st = s["stations"]
    k = n_st - 1
    n_el = max(int(s["elements"]), k * int(np.ceil(4 * p["n_modes"] / k)))
    n_el = k * int(np.ceil(n_el / k))
    w, V, n, unstable = solve(p, n_el, spin, p["n_modes"], vectors=not s["richardson"])
    err, change = 0.0, None
    if s["richardson"]:
        # per mode: the n–2n extrapolate's distance to the n/2–n one (fem/blade.py's
        # richardson_pair: the coarser's discretisation error plus the fine solves' round-off)
        w2, V, n, unstable = solve(p, 2 * n_el, spin, p["n_modes"])
        half = solve(p, n_el // 2, spin, p["n_modes"], vectors=False)[0]
        # the state space (spinning, anisotropic) has no Rayleigh quotient: its round-off is
        # bounded by the largest distance of any mode, carried as it is (the two planes' lowest
        # alone missed forward whirl 1 at Ω* = 6, EI_yy = 400: 9.2e-11 against 7e-11)
        state_space = spin != 0 and p["EI_xx"] != p["EI_yy"]
        w, bar = richardson_pair(half, w, w2, lowest=len(w) if state_space else 0)
        err = float(np.max(bar / w))
        change = bar / (2 * np.pi)
    step = (2 if s["richardson"] else 1) * n_el // k
    shapes, sense = [], []
    for j in range(len(w)):
        x = V[:, j]
        u = np.concatenate([[0.0], x[0:n:2]])
        v = np.concatenate([[0.0], x[n::2]])
        big = u[np.argmax(np.abs(u))] if np.abs(u).max() > 1e-9 * np.abs(v).max() else \
            v[np.argmax(np.abs(v))]
        u, v = u / big, v / big
        U, Vs = u.real, -v.imag                       # u = U cos ωt, v = V sin ωt
        if spin == 0:                                 # planes decoupled: no whirl sense
            U, Vs = u.real, v.real
        # +1: counter-clockwise about the spin axis in the rotating frame
        sense.append(1.0 if spin == 0 else float(np.sign(U @ Vs)))
        sh = np.concatenate([U[::step], Vs[::step]])
        shapes.append(sh / sh[np.argmax(np.abs(sh))])
    labels = whirl_labels(w / (2 * np.pi), sense, spin / (2 * np.pi))
    notes = [f"ω₀ = {w0:.6g} rad/s; elements {n_el} and {2 * n_el}, Richardson error estimate "
             f"{err:.1e}"]
    if unstable:
        notes.append(f"unstable (divergence) growth rates {np.round(unstable, 6).tolist()} 1/s")
    return LeafModes(frequencies_hz=w / (2 * np.pi), labels=labels, shapes=np.array(shapes),
                       settings=dict(s, elements=n_el), notes=notes,
                       extra={"omega_star": (w / w0).tolist(), "unstable": unstable,
                              "whirl_sense": sense,
                              **({"frequency_error_hz": change} if change is not None else {})})
