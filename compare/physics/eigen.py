"""How far an eigenvalue of ẋ = A x can move: round-off in forming and solving A, and a change
δA of the linearisation (another finite-difference step). First-order perturbation of a simple
root, right vector x_i, left vector y_i:

    δλ_i = y_iᴴ δA x_i / (y_iᴴ x_i),   |δλ_i| ≤ κ_i ‖δA‖,   κ_i = ‖y_i‖ ‖x_i‖ / |y_iᴴ x_i|.

Round-off: LAPACK's QR algorithm works on the balanced B = D⁻¹ A D (diagonal D) with a
backward error of order eps·‖B‖, so the floor is C_ROUND_OFF · eps · ‖B‖₁ · κ_i(B). Roots
within CLUSTER of each other (a repeated root, e.g. an isotropic shaft at rest) are perturbed
as a group: their bound uses the group's vectors together, and a δA's change is bounded by the
row sums of y_kᴴ δA x_j over the group (Gershgorin), which also covers a split of the group.
A damping ratio ζ = −Re λ/|λ| moves by at most |δλ|/|λ|.
"""
from __future__ import annotations

import numpy as np
from scipy.linalg import matrix_balance

EPS = np.finfo(float).eps
# Measured on conservative systems (true Re λ = 0): the largest |Re λ| / (eps ‖B‖₁ κ) was 1.08
# over 60 random gyroscopic M, K, G (6–60 states, stiffness spread 10–1e6) and 4.4 over all
# roots of the engines' beam chains (240 states, blade 0–200 rad/s, shaft Ω* 0–20), whose
# M⁻¹K (cond M 1.4e7) adds rounding of its own (0.17 over their reported lowest six roots);
# 10 covers both with a margin of 2.
C_ROUND_OFF = 10.0
CLUSTER = 1e-6         # roots closer than this (relative) are perturbed together


def left_rows(V: np.ndarray) -> np.ndarray:
    """The left eigenvectors as the rows of V⁻¹ (row i is y_iᴴ, y_iᴴ x_j = δ_ij): the dual
    basis stays defined inside a repeated root's eigenspace, where LAPACK's own left vectors
    may come out nearly orthogonal to the right ones."""
    return np.linalg.inv(V)


def _groups(lam: np.ndarray) -> np.ndarray:
    """[i, j] true where roots i and j are perturbed together (each with itself)."""
    lam = np.asarray(lam, complex)
    scale = np.maximum(np.abs(lam)[:, None], np.abs(lam)[None, :])
    return np.abs(lam[:, None] - lam[None, :]) <= CLUSTER * scale


def round_off(A: np.ndarray, lam: np.ndarray, V: np.ndarray, W: np.ndarray,
              idx=None) -> np.ndarray:
    """Bound on |δλ| from round-off for the roots `idx` (default all) of A: `lam`, right
    vectors `V` (columns) and `W` = `left_rows(V)`, all of A in full."""
    idx = np.arange(len(lam)) if idx is None else np.asarray(idx)
    B, (d, _) = matrix_balance(A, permute=False, separate=True)
    nx = np.sum(np.abs(V[:, idx] / d[:, None]) ** 2, axis=0)     # x in B's coordinates
    ny = np.sum(np.abs(W[idx] * d[None, :]) ** 2, axis=1)        # y in B's coordinates
    norm_y_x = np.abs(np.einsum("ij,ji->i", W[idx], V[:, idx]))  # |y_iᴴ x_i| (1 up to rounding)
    g = _groups(lam[idx]).astype(float)
    kappa = np.sqrt(g @ ny) * np.sqrt(g @ nx) / norm_y_x
    return C_ROUND_OFF * EPS * np.linalg.norm(B, 1) * kappa


# the reported roots' rounding against the most three other solves of the same A move them
SPREAD_SAFETY = 3.0


def solve_spread(A: np.ndarray, lam: np.ndarray) -> np.ndarray:
    """The round-off the solve makes in the roots `lam` of A, measured rather than bounded:
    SPREAD_SAFETY × the most they move when A is solved again as Aᵀ, reversed (P A Pᵀ) and
    both — exact similarities that LAPACK rounds otherwise — each root against the nearest of
    the others' (a repeated root's twins land on either one alike). The bound `round_off`
    holds every root at once and sits 10–1000 × above this on the helicopters' low roots
    (docs/scenes/mstmm.md, the engines)."""
    lam = np.asarray(lam, complex)
    R = A[::-1, ::-1]
    moved = [np.min(np.abs(np.linalg.eigvals(B)[None, :] - lam[:, None]), axis=1)
             for B in (A.T, R, R.T)]
    return SPREAD_SAFETY * np.max(moved, axis=0)


def change(dA: np.ndarray, lam: np.ndarray, V: np.ndarray, W: np.ndarray,
           idx=None) -> tuple[np.ndarray, np.ndarray]:
    """Bounds on |Re δλ| and |δλ| of the roots `idx` when A becomes A + dA, to first order
    (mode by mode: no matching needed): δλ_k = P_kk, P = W dA V; a repeated root's group by
    Gershgorin's discs about P_kk with radii Σ_{j≠k} |P_kj| over the group."""
    idx = np.arange(len(lam)) if idx is None else np.asarray(idx)
    P = W[idx] @ dA @ V[:, idx]
    g = _groups(lam[idx])
    radius = np.sum(np.where(g, np.abs(P), 0.0), axis=1) - np.abs(np.diag(P))
    widest = lambda x: np.max(np.where(g, x[None, :], 0.0), axis=1)   # noqa: E731
    return (widest(np.abs(np.diag(P).real) + radius), widest(np.abs(np.diag(P)) + radius))


def zeta_error(dlam, lam, d_re=None) -> np.ndarray:
    """A bound on |δλ| as a bound on the damping ratio ζ = −Re λ/|λ|: |δλ|/|λ|, or, where the
    bound on |Re δλ| is known apart (`d_re`), (|Re δλ| + |ζ| |δλ|)/|λ|."""
    lam = np.asarray(lam, complex)
    if d_re is None:
        return np.asarray(dlam, float) / np.abs(lam)
    return (np.asarray(d_re, float) + np.abs(lam.real) / np.abs(lam) * np.asarray(dlam, float)) \
        / np.abs(lam)


def _matched(A: np.ndarray, roots):
    """A solved again: its roots, right vectors, left rows and the index of the eigenvalue
    nearest each of `roots`."""
    lam, V = np.linalg.eig(A)
    return lam, V, left_rows(V), [int(np.argmin(np.abs(lam - r))) for r in np.atleast_1d(roots)]


def root_errors(A: np.ndarray, roots, A_varied: np.ndarray | None = None,
                formation: float = 1.0) -> np.ndarray:
    """Bounds on |δλ| of the given `roots` of a small A: round-off (× `formation` where the
    engine's own forming of A rounds more than the eigensolver, measured by its leaf), plus the
    first-order change to `A_varied` (the same linearisation at another finite-difference
    step) where given."""
    lam, V, W, idx = _matched(A, roots)
    out = formation * round_off(A, lam, V, W, idx)
    if A_varied is not None:
        out = out + change(np.asarray(A_varied) - A, lam, V, W, idx)[1]
    return out


def root_zeta_errors(A: np.ndarray, roots, A_varied: np.ndarray | None = None,
                     reported=None) -> np.ndarray:
    """Bounds on the ζ of the given `roots` of a small A, as `root_errors` (the change's real
    part bounded apart). `reported`: the roots as the leaf reports them where its ζ uses
    another frame's frequency (same Re λ)."""
    lam, V, W, idx = _matched(A, roots)
    reported = np.atleast_1d(roots if reported is None else reported)
    out = zeta_error(round_off(A, lam, V, W, idx), reported)
    if A_varied is not None:
        d_re, d_abs = change(np.asarray(A_varied) - A, lam, V, W, idx)
        out = out + zeta_error(d_abs, reported, d_re)
    return out


def refine_gyroscopic(K, G, M, lam, x, steps: int = 4):
    """A root λ and vector x of (λ²M + λG + K) x = 0 (K, M symmetric, G skew: a conservative
    gyroscopic system) refined by inverse iteration with the Rayleigh functional — λ the root
    of xᴴ(λ²M + λG + K)x = 0 nearest the last, stationary in x, so the error in λ falls as
    the square of x's. ARPACK's shift-invert roots of fem's helicopter were off by up to
    1.1e-5 relative (residuals 2–26 against 1e-9–1e-6 refined; helicopter-hover's fourth
    calibration set, the lag cyclic pair): its tolerance bounds the inverted operator's
    residual, not λ's. K, G, M sparse or dense (converted here: pass them sparse to refine
    many roots). Returns (λ, x, a bound on |δλ|): to first order, the residual left and
    the rounding of the matrices' products, eps·|x|ᵀ(|K| + |λ||G| + |λ|²|M|)|x|, over
    |xᴴ(2λM + G)x| — the cancellation of a low mode that strains a stiff member (the clamped
    aircraft's twelfth calibration set, lag collective 1: 9.1e-10 off mstmm, 4 × its mesh
    change, inside this 1.3e-8)."""
    from scipy import sparse
    from scipy.sparse.linalg import splu
    K, G, M = (sparse.csc_matrix(A) for A in (K, G, M))
    x = np.asarray(x, complex) / np.linalg.norm(x)
    for _ in range(steps):
        y = splu((lam * lam * M + lam * G + K).tocsc()).solve((2 * lam * M + G) @ x)
        x = y / np.linalg.norm(y)
        a, b, c = (np.vdot(x, A @ x) for A in (M, G, K))
        roots = np.roots([a, b, c])
        lam = roots[np.argmin(np.abs(roots - lam))]
    ax = np.abs(x)
    rounding = EPS * sum(w * (ax @ (abs(A) @ ax)) for w, A in ((1.0, K), (abs(lam), G),
                                                              (abs(lam) ** 2, M)))
    residual = np.linalg.norm((lam * lam * M + lam * G + K) @ x)
    return lam, x, float((residual + rounding) / abs(np.vdot(x, (2 * lam * M + G) @ x)))
