"""Building blocks for implicit (stiff) integrators, compiled with numba.

- `block3_tridiag_factor` / `block3_tridiag_solve`: symmetric block-tridiagonal systems with 3x3
  blocks (chains of point masses joined by springs: the Newton matrix of an implicit step for a
  spring-mass chain has exactly this structure).
- `bordered_block3_solve`: the same system bordered by one extra scalar unknown
  (e.g. a hub rotation coupled to the chain):

      [ A   U ] [x]   [r  ]
      [ U^T δ ] [z] = [rho]

  solved with the Schur complement  z = (rho − Uᵀ A⁻¹ r) / (δ − Uᵀ A⁻¹ U),  x = A⁻¹ (r − U z),
  from one factorisation of A (two block sweeps). O(N) work, no dense matrix.

The model owns the implicit method itself (it knows its events and invariants); see
`custom_models/thread_spool.py` for an implicit-midpoint stepper built on these.
"""
import numba as nb
import numpy as np


@nb.njit(cache=True)
def inv3(a, out):
    """Inverse of the 3x3 matrix a into out (cofactor formula). Returns the determinant."""
    c00 = a[1, 1] * a[2, 2] - a[1, 2] * a[2, 1]
    c01 = a[1, 2] * a[2, 0] - a[1, 0] * a[2, 2]
    c02 = a[1, 0] * a[2, 1] - a[1, 1] * a[2, 0]
    det = a[0, 0] * c00 + a[0, 1] * c01 + a[0, 2] * c02
    inv = 1.0 / det
    out[0, 0] = c00 * inv
    out[1, 0] = c01 * inv
    out[2, 0] = c02 * inv
    out[0, 1] = (a[0, 2] * a[2, 1] - a[0, 1] * a[2, 2]) * inv
    out[1, 1] = (a[0, 0] * a[2, 2] - a[0, 2] * a[2, 0]) * inv
    out[2, 1] = (a[0, 1] * a[2, 0] - a[0, 0] * a[2, 1]) * inv
    out[0, 2] = (a[0, 1] * a[1, 2] - a[0, 2] * a[1, 1]) * inv
    out[1, 2] = (a[0, 2] * a[1, 0] - a[0, 0] * a[1, 2]) * inv
    out[2, 2] = (a[0, 0] * a[1, 1] - a[0, 1] * a[1, 0]) * inv
    return det


@nb.njit(cache=True)
def block3_tridiag_factor(D, B, N, Dinv, work):
    """Factor the symmetric block-tridiagonal matrix with diagonal blocks D[0..N-1] and
    off-diagonal blocks B[i] = A[i, i+1] = A[i+1, i] (symmetric 3x3 blocks).

    Stores the inverses of the Schur-reduced diagonal blocks in Dinv; work: a (2, 3, 3) scratch
    array (an implicit step factors several times per step: nothing is allocated here). Returns
    False if a pivot block is singular."""
    tmp, L = work[0], work[1]
    for i in range(N):
        for a in range(3):
            for c in range(3):
                tmp[a, c] = D[i, a, c]
        if i > 0:
            # L = B[i-1]^T Dinv[i-1];  tmp -= L B[i-1]
            for a in range(3):
                for c in range(3):
                    s = 0.0
                    for k in range(3):
                        s += B[i - 1, k, a] * Dinv[i - 1, k, c]
                    L[a, c] = s
            for a in range(3):
                for c in range(3):
                    s = 0.0
                    for k in range(3):
                        s += L[a, k] * B[i - 1, k, c]
                    tmp[a, c] -= s
        det = inv3(tmp, Dinv[i])
        if not np.isfinite(det) or det == 0.0:
            return False
    return True


@nb.njit(cache=True)
def block3_tridiag_solve(B, Dinv, N, r, x):
    """Solve A x = r with the factorisation from `block3_tridiag_factor` (r, x: (N, 3)); the
    forward sweep's intermediate lives in x (nothing allocated)."""
    for a in range(3):
        x[0, a] = r[0, a]
    for i in range(1, N):
        # y_i = r_i − B[i-1]^T Dinv[i-1] y_{i-1}
        D, yp = Dinv[i - 1], x[i - 1]
        t0 = D[0, 0] * yp[0] + D[0, 1] * yp[1] + D[0, 2] * yp[2]
        t1 = D[1, 0] * yp[0] + D[1, 1] * yp[1] + D[1, 2] * yp[2]
        t2 = D[2, 0] * yp[0] + D[2, 1] * yp[1] + D[2, 2] * yp[2]
        for a in range(3):
            x[i, a] = r[i, a] - (B[i - 1, 0, a] * t0 + B[i - 1, 1, a] * t1 + B[i - 1, 2, a] * t2)
    for i in range(N - 1, -1, -1):
        y0, y1, y2 = x[i, 0], x[i, 1], x[i, 2]
        if i < N - 1:
            xn = x[i + 1]
            y0 -= B[i, 0, 0] * xn[0] + B[i, 0, 1] * xn[1] + B[i, 0, 2] * xn[2]
            y1 -= B[i, 1, 0] * xn[0] + B[i, 1, 1] * xn[1] + B[i, 1, 2] * xn[2]
            y2 -= B[i, 2, 0] * xn[0] + B[i, 2, 1] * xn[1] + B[i, 2, 2] * xn[2]
        for a in range(3):
            x[i, a] = Dinv[i, a, 0] * y0 + Dinv[i, a, 1] * y1 + Dinv[i, a, 2] * y2


@nb.njit(cache=True)
def bordered_block3_solve(B, Dinv, N, U, delta, r, rho, x, xu):
    """Solve [[A, U], [Uᵀ, δ]] [x; z] = [r; rho] given A's factorisation. Returns z; x is
    written in place. U, r, x and the scratch xu (A⁻¹ U): (N, 3)."""
    block3_tridiag_solve(B, Dinv, N, r, x)
    block3_tridiag_solve(B, Dinv, N, U, xu)
    ur = 0.0
    uu = 0.0
    for i in range(N):
        for a in range(3):
            ur += U[i, a] * x[i, a]
            uu += U[i, a] * xu[i, a]
    z = (rho - ur) / (delta - uu)
    for i in range(N):
        for a in range(3):
            x[i, a] -= xu[i, a] * z
    return z
