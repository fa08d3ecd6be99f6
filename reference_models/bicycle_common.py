"""What both engine leaves of `bicycle` share: the release (a short roll torque pulse on the
rear frame of the bicycle rolling upright), the matrix-pencil fit of its roots from the lean
and steer that follow, and each root's error bar — the engine's step (a run at twice it) and
the fit (the record halved). Imports numpy only.
"""
from __future__ import annotations

from collections.abc import Callable

import numpy as np

from compare.contract import LeafModes
from compare.physics.bicycle import damping_shift, root_labels, roots_text

PULSE = (1e-3, 0.02)            # roll torque [N·m] on the rear frame, and how long [s]
LEAN_CUT = 1e-5                 # rad: a growing record is cut here
# the paper's axes (x forward, y right, z down) -> the engines' (x forward, y left, z up)
Z_UP = np.diag([1.0, -1.0, -1.0])


def tensor(xx, yy, zz, xz) -> np.ndarray:
    """A body's inertia tensor given in the paper's axes, in the engines' z-up axes (I_xz
    changes sign)."""
    return Z_UP @ np.array([[xx, 0.0, xz], [0.0, yy, 0.0], [xz, 0.0, zz]]) @ Z_UP.T


def steer_axis(p: dict) -> tuple[np.ndarray, np.ndarray]:
    """(unit steer axis pointing up, the point of it level with the front hub), z-up axes: the
    axis tilted back by λ meets the ground at x = w + c."""
    lam = p["lambda"]
    axis = np.array([-np.sin(lam), 0.0, np.cos(lam)])
    return axis, np.array([p["w"] + p["c"], 0.0, 0.0]) + p["r_F"] / np.cos(lam) * axis


def pencil(channels, dt: float, n_poles: int = 4) -> np.ndarray:
    """Poles λ [1/s] of the `n_poles` damped exponentials common to all channels (Hua and
    Sarkar's matrix pencil on the channels' Hankel matrices stacked), sorted as the
    `meijaard` solver's: by real part descending, then imaginary."""
    rows = []
    for x in channels:
        x = np.asarray(x, float) / np.max(np.abs(x))
        rows.append(np.lib.stride_tricks.sliding_window_view(x, len(x) // 3 + 1))
    _, _, Vh = np.linalg.svd(np.vstack(rows), full_matrices=False)
    V = Vh[:n_poles].T
    lam = np.log(np.linalg.eigvals(np.linalg.pinv(V[:-1]) @ V[1:]).astype(complex)) / dt
    lam = np.where(np.abs(lam.imag) < 1e-9 * np.abs(lam), lam.real + 0j, lam)
    return lam[np.lexsort((-lam.imag, -lam.real))]


def match(lam, ref) -> np.ndarray:
    """`ref`'s roots reordered to pair with `lam`'s (nearest first)."""
    ref, out = list(ref), []
    for x in lam:
        j = int(np.argmin(np.abs(np.asarray(ref) - x)))
        out.append(ref.pop(j))
    return np.array(out)


def fitted_modes(free_response: Callable, params: dict, s: dict, note: str) -> LeafModes:
    """The roots from `free_response(params, speed, dt) -> (t, lean, steer, wall_s)` (samples
    every s["output_dt"] from the pulse's end) at s["dt"], with error bars: 4/3 of the change
    from a run at 2·dt (a second-order integrator) plus twice the change of the fit on half the
    record (with 1× the capsize root at 2–2.5 m/s — a decaying root under a growing weave — sat
    at 0.92–0.96 of its bar in Exudyn)."""
    v = float(params["speed"])
    t, lean, steer, wall = free_response(params, v, s["dt"])
    if len(t) < 40:
        raise RuntimeError(f"only {len(t)} samples before the lean reached {LEAN_CUT:g} rad")
    lam = pencil([lean, steer], s["output_dt"])
    _, lean2, steer2, wall2 = free_response(params, v, 2 * s["dt"])
    coarse = match(lam, pencil([lean2, steer2], s["output_dt"]))
    half = len(t) // 2
    short = match(lam, pencil([lean[:half], steer[:half]], s["output_dt"]))
    err = 4 / 3 * np.abs(lam - coarse) + 2 * np.abs(lam - short)
    # the frequency's bar by the same rule on Im λ itself (|δλ| bounds it, 1.1–8 × wider on 7
    # drawn designs, where Exudyn's weave frequencies are off the equations' by 0.03–0.25 of
    # this bar; `xval calibrate bicycle`: coverage 1.0, median 0.25). ζ keeps the modulus'
    # bound: where a fit fails (MuJoCo's weave at ζ = 0.94, its frequency 93 % off) the
    # three fits' ζ agree while their frequencies do not
    err_im = 4 / 3 * np.abs(lam.imag - coarse.imag) + 2 * np.abs(lam.imag - short.imag)
    labels = root_labels(lam)
    osc = [i for i in np.argsort(lam.imag) if lam[i].imag > 0]
    return LeafModes(
        frequencies_hz=lam[osc].imag / (2 * np.pi), labels=[labels[i] for i in osc],
        damping=-lam[osc].real / np.abs(lam[osc]), settings=s,
        notes=[note, roots_text(lam, labels)],
        extra={"eigenvalues": np.column_stack([lam.real, lam.imag]),
               "eigenvalue_labels": labels, "eigenvalue_error_per_s": err,
               "frequency_error_hz": err_im[osc] / (2 * np.pi),
               # ζ anywhere within |δλ| of the root (ζ = −cos arg λ: 1/sin(arg λ) sharper
               # than 2 |δλ|/|λ| near a real root)
               "damping_error": damping_shift(lam[osc], err[osc]),
               "max_re_per_s": float(np.max(lam.real)), "record_s": float(t[-1] - t[0]),
               "simulate_s": wall + wall2})
