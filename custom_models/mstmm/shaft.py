"""`mstmm` leaf for `spinning-shaft`: the spinning cantilever shaft of Table 2 (seed 002).

Rotating frame, Euler–Bernoulli, the physical (skew-symmetric) gyroscopic coupling:
    EI_yy u'''' + m ü − 2mΩ v̇ − mΩ² u = 0,   EI_xx v'''' + m v̈ + 2mΩ u̇ − mΩ² v = 0.
The paper's eq. 32 prints the same sign on both Coriolis terms; taken literally (u, v ∝ e^{iωt})
its characteristic roots are real-exponential and cannot give Table 2. With the whirl ansatz
u = U cos ωt, v = V sin ωt the physical equations become the paper's eq. 33 exactly, real:
    EI_yy U'''' = m(ω² + Ω²) U + 2mΩω V,   EI_xx V'''' = m(ω² + Ω²) V + 2mΩω U,
which is what we solve (so eq. 33 and the table are right, eq. 32 has the sign slip).
The element matrix is the exact exponential of this constant-coefficient first-order system
(the closed form of the paper's α, β roots, eqs. 34-41, written as a matrix exponential), in the
state (U, V, θx = −V', θy = −U', Mx = EI_xx V'', My = −EI_yy U'', Sx = EI_yy U''', Sy = EI_xx V''')
(the paper's eqs. 36-38); it is split into segments of ≤ 1.5 rad wavenumber and the clamped-root
basis re-orthonormalised after each, as for the blade.

ω > 0 covers both whirl senses (ω < 0 is ω > 0 with V → −V). The fixed-frame whirl rate is
sense·ω + Ω with sense = sign(∫U V) (+1: counter-clockwise about the spin axis in the rotating
frame, reported in extra["whirl_sense"]): forward whirl if > 0, each direction numbered by
that fixed-frame frequency (compare.physics.whirl). Inside an anisotropic instability band a
mode has no real ω: it is missing from the real roots and reported in notes.
"""
import numpy as np
from scipy.linalg import expm

from compare.contract import LeafModes, merge_settings
from compare.physics.mstmm import spinning_shaft_omega0
from compare.physics.whirl import whirl_labels

from .elements import shaft_tip_det
from .roots import find_roots, root_error_hz

MODES_SETTINGS = {"rtol": 1e-12, "stations": 13}


def first_order_matrix(EIx, EIy, m, omega, spin):
    """A in y' = A y, y = [U, U', U'', U''', V, V', V'', V''']."""
    A = np.zeros((8, 8))
    for k in range(3):
        A[k, k + 1] = 1.0
        A[4 + k, 5 + k] = 1.0
    a, c = m * (omega**2 + spin**2), 2 * m * spin * omega
    A[3, 0], A[3, 4] = a / EIy, c / EIy
    A[7, 4], A[7, 0] = a / EIx, c / EIx
    return A


def characteristic(p, spin, plane=None):
    """Scaled det of the tip resultants (elements.shaft_tip_det). At rest the planes decouple
    and each has simple roots (together they would give exact double roots): plane 'u' or
    'v' solves one."""
    code = {None: 0, "u": 1, "v": 2}[plane]
    args = (float(p["EI_xx"]), float(p["EI_yy"]), float(p["m"]), float(p["L"]))
    return lambda omega: shaft_tip_det(*args, float(omega), float(spin), code)


def shape(p, omega, spin, stations):
    """[U, V] at the stations (root→tip), from the null vector at the root."""
    EIx, EIy, m, L = p["EI_xx"], p["EI_yy"], p["m"], p["L"]
    A = first_order_matrix(EIx, EIy, m, omega, spin)
    tip = expm(A * L)             # (one call per mode: scipy's expm is exact enough here)
    _, _, vt = np.linalg.svd(tip[np.ix_([2, 3, 6, 7], [2, 3, 6, 7])])
    y0 = np.zeros(8)
    y0[[2, 3, 6, 7]] = vt[-1]
    step = expm(A * L / (stations - 1))
    ys = [y0]
    for _ in range(stations - 1):
        ys.append(step @ ys[-1])
    ys = np.array(ys)
    s = np.concatenate([ys[:, 0], ys[:, 4]])
    return s / s[np.argmax(np.abs(s))]


def modes(params: dict, settings: dict) -> LeafModes:
    s = merge_settings(settings, MODES_SETTINGS, ())
    p = params
    w0 = spinning_shaft_omega0(p["EI_xx"], p["m"], p["L"])
    spin = p["spin_ratio"] * w0
    planes = ("u", "v") if spin == 0 else (None,)
    EImax = max(p["EI_xx"], p["EI_yy"])
    # n_modes + 1 roots lie below the k-th non-rotating frequency (< (kπ)² ω₀) plus the spin
    # for k = ⌈(n_modes + 1)/2⌉ (two roots per k: planes or whirls); the loop widens if not
    k = (p["n_modes"] + 2) // 2
    omega_max = ((k * np.pi) ** 2 + p["spin_ratio"]) * w0 * np.sqrt(EImax / p["EI_xx"])
    while True:
        # wavenumber grid: β L = (m (ω+Ω)²/EI)^¼ L in steps of 0.2 rad
        bl_max = (p["m"] * (omega_max + spin) ** 2 / min(p["EI_xx"], p["EI_yy"])) ** 0.25 * p["L"]
        grid = np.linspace(0, 1, int(bl_max / 0.1) + 8) ** 2 * omega_max
        grid[0] = 1e-9 * omega_max
        roots = sorted(r for pl in planes
                       for r in find_roots(characteristic(p, spin, pl), grid, s["rtol"]))
        if len(roots) >= p["n_modes"] + 1:
            break
        omega_max *= 1.6
    roots = roots[:p["n_modes"]]
    n = s["stations"]
    shapes = [shape(p, w, spin, n) for w in roots]
    sense = [1.0 if spin == 0 else float(np.sign(sh[:n] @ sh[n:])) for sh in shapes]
    labels = whirl_labels(np.array(roots) / (2 * np.pi), sense, spin / (2 * np.pi))
    notes = [f"ω₀ = {w0:.6g} rad/s; shapes [U, V] at {s['stations']} stations; rotating frame"]
    if p["EI_xx"] != p["EI_yy"]:
        notes.append("anisotropic: modes inside an instability band have no real frequency")
    return LeafModes(frequencies_hz=np.array(roots) / (2 * np.pi), labels=labels,
                       shapes=np.array(shapes), settings=s, notes=notes,
                       extra={"omega_star": (np.array(roots) / w0).tolist(),
                              "whirl_sense": sense,
                              "frequency_error_hz": root_error_hz(np.array(roots) / (2 * np.pi),
                                                                  s["rtol"])})
