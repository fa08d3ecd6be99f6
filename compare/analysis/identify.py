"""Natural frequencies identified from a free-response time series of any solver, so
time-domain-only models can be checked against modal results.

- `pencil_poles` / `matrix_pencil`: Hua & Sarkar's matrix-pencil fit of damped exponentials
  (exact for a noise-free sum of modes, whatever the record length): poles of a real or complex
  record, or frequencies and damping ratios of a real one;
- `growing_pole`: the fitted pole with the largest real part (a growth rate from a record);
- `fft_peak`: Hann-windowed FFT with a parabola through the log-magnitude peak (its bias shrinks
  as the record lengthens).
"""
import numpy as np


def pencil_poles(x: np.ndarray, dt: float, n_poles: int,
                 pencil: int | None = None) -> np.ndarray:
    """Continuous-time poles λ [1/s] of the `n_poles` strongest damped exponentials in x (real:
    poles in conjugate pairs; complex, e.g. x + iy of an orbit: a pole with Im λ > 0 turns
    counter-clockwise, one with Im λ < 0 clockwise), x(t) = Σ a_k e^{λ_k t}."""
    x = np.asarray(x)
    x = x.astype(complex if np.iscomplexobj(x) else float)
    L = pencil or len(x) // 3
    Y = np.lib.stride_tricks.sliding_window_view(x, L + 1)       # (N − L) × (L + 1) Hankel
    _, s, Vh = np.linalg.svd(Y, full_matrices=False)
    M = min(n_poles, int(np.sum(s > s[0] * 1e-10)))
    V = Vh[:M].T              # the rows of Vh span the windows (z_k^j)_j: shift-invariant
    z = np.linalg.eigvals(np.linalg.pinv(V[:-1]) @ V[1:])
    return np.log(z.astype(complex)) / dt


def matrix_pencil(x: np.ndarray, dt: float, n_modes: int = 2,
                  pencil: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Frequencies [rad/s] (≥ 0, sorted) and damping ratios of the strongest modes in real x."""
    lam = pencil_poles(np.asarray(x, float), dt, 2 * n_modes, pencil)
    keep = lam.imag >= 0
    w = np.abs(lam[keep].imag)
    zeta = -lam[keep].real / np.maximum(np.abs(lam[keep]), 1e-300)
    o = np.argsort(w)
    return w[o], zeta[o]


def growing_pole(x: np.ndarray, dt: float, n_poles: int, pencil: int | None = None) -> complex:
    """The pole λ [1/s] with the largest real part among `pencil_poles` of x: the root that
    grows first, the time-domain counterpart of a linearisation's max Re λ."""
    lam = pencil_poles(x, dt, n_poles, pencil)
    return complex(lam[np.argmax(lam.real)])


def fft_peak(x: np.ndarray, dt: float) -> float:
    """Dominant frequency [rad/s] from a Hann-windowed FFT, peak refined by a parabola."""
    x = np.asarray(x, float) - np.mean(x)
    X = np.abs(np.fft.rfft(x * np.hanning(len(x))))
    i = int(np.argmax(X[1:])) + 1
    if 0 < i < len(X) - 1:
        a, b, c = np.log(X[i - 1: i + 2] + 1e-300)
        i = i + 0.5 * (a - c) / (a - 2 * b + c)
    return 2 * np.pi * i / (len(x) * dt)


def transverse_components(orientation: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(γ_x, γ_y) of the transverse Euler vector from (n, 4) w,x,y,z orientations."""
    w, x, y, z = orientation.T
    nx, ny, nz = 2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)
    s = np.hypot(nx, ny)
    th = np.arctan2(s, nz)
    f = np.where(s > 1e-12, th / np.maximum(s, 1e-300), 1.0)
    return -ny * f, nx * f
