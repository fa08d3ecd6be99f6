"""The benchmark bicycle's linearised equations (Meijaard, Papadopoulos, Ruina, Schwab 2007,
Proc. R. Soc. A 463, Appendix A): for q = (lean φ, steer δ) about the upright straight run at
forward speed v,

    M q̈ + v C1 q̇ + (g K0 + v² K2) q = 0,

M, C1, K0, K2 from the 25 design parameters (names as the paper's symbols). The roots are the
eigenvalues of the 4×4 first-order system; the weave and capsize speeds are where the largest
real part crosses zero, found by root-finding on the model (never by interpolating a sweep).
"""
from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

# the 25 design parameters in the paper's order (Table 1)
DESIGN = ("w", "c", "lambda", "g", "r_R", "m_R", "I_Rxx", "I_Ryy", "x_B", "z_B", "m_B",
          "I_Bxx", "I_Bxz", "I_Byy", "I_Bzz", "x_H", "z_H", "m_H", "I_Hxx", "I_Hxz", "I_Hyy",
          "I_Hzz", "r_F", "m_F", "I_Fxx", "I_Fyy")


def matrices(p: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(M, C1, K0, K2) of the paper's Appendix A at the design parameters `p`."""
    w, c, lam = p["w"], p["c"], p["lambda"]
    rR, mR, IRxx, IRyy = p["r_R"], p["m_R"], p["I_Rxx"], p["I_Ryy"]
    xB, zB, mB = p["x_B"], p["z_B"], p["m_B"]
    IBxx, IBxz, IBzz = p["I_Bxx"], p["I_Bxz"], p["I_Bzz"]
    xH, zH, mH = p["x_H"], p["z_H"], p["m_H"]
    IHxx, IHxz, IHzz = p["I_Hxx"], p["I_Hxz"], p["I_Hzz"]
    rF, mF, IFxx, IFyy = p["r_F"], p["m_F"], p["I_Fxx"], p["I_Fyy"]
    IRzz, IFzz = IRxx, IFxx                      # the wheels are planar-symmetric discs
    sl, cl = np.sin(lam), np.cos(lam)
    # the whole bicycle (A1–A6)
    mT = mR + mB + mH + mF
    xT = (xB * mB + xH * mH + w * mF) / mT
    zT = (-rR * mR + zB * mB + zH * mH - rF * mF) / mT
    ITxx = IRxx + IBxx + IHxx + IFxx + mR * rR**2 + mB * zB**2 + mH * zH**2 + mF * rF**2
    ITxz = IBxz + IHxz - mB * xB * zB - mH * xH * zH + mF * w * rF
    ITzz = IRzz + IBzz + IHzz + IFzz + mB * xB**2 + mH * xH**2 + mF * w**2
    # the front assembly A = H + F (A7–A12)
    mA = mH + mF
    xA = (xH * mH + w * mF) / mA
    zA = (zH * mH - rF * mF) / mA
    IAxx = IHxx + IFxx + mH * (zH - zA) ** 2 + mF * (rF + zA) ** 2
    IAxz = IHxz - mH * (xH - xA) * (zH - zA) + mF * (w - xA) * (rF + zA)
    IAzz = IHzz + IFzz + mH * (xH - xA) ** 2 + mF * (w - xA) ** 2
    uA = (xA - w - c) * cl - zA * sl             # the front assembly's offset from the steer axis
    IAll = mA * uA**2 + IAxx * sl**2 + 2 * IAxz * sl * cl + IAzz * cl**2
    IAlx = -mA * uA * zA + IAxx * sl + IAxz * cl
    IAlz = mA * uA * xA + IAxz * sl + IAzz * cl
    mu = c / w * cl                              # the trail ratio
    SR, SF = IRyy / rR, IFyy / rF                # gyrostatic coefficients
    ST = SR + SF
    SA = mA * uA + mu * mT * xT
    M = np.array([[ITxx, IAlx + mu * ITxz],
                  [IAlx + mu * ITxz, IAll + 2 * mu * IAlz + mu**2 * ITzz]])
    K0 = np.array([[mT * zT, -SA],
                   [-SA, -SA * sl]])
    K2 = np.array([[0.0, (ST - mT * zT) / w * cl],
                   [0.0, (SA + SF * sl) / w * cl]])
    C1 = np.array([[0.0, mu * ST + SF * cl + ITxz / w * cl - mu * mT * zT],
                   [-(mu * ST + SF * cl), IAlz / w * cl + mu * (SA + ITzz / w * cl)]])
    return M, C1, K0, K2


def state_matrix(p: dict, v: float, mats=None) -> np.ndarray:
    """A of ẋ = A x, x = (φ, δ, φ̇, δ̇), at forward speed `v` [m/s]."""
    M, C1, K0, K2 = matrices(p) if mats is None else mats
    Minv = np.linalg.inv(M)
    return np.block([[np.zeros((2, 2)), np.eye(2)],
                     [-Minv @ (p["g"] * K0 + v * v * K2), -Minv @ (v * C1)]])


def eigenvalues(p: dict, v: float, mats=None) -> np.ndarray:
    """The four roots λ [1/s] at speed `v`, sorted by real part (descending), then imaginary."""
    lam = np.linalg.eigvals(state_matrix(p, v, mats))
    return lam[np.lexsort((-lam.imag, -lam.real))]


def damping_shift(lam, r):
    """The largest change of ζ = −Re λ/|λ| a root `lam` can take moving anywhere within `r`
    [1/s] of it: ζ depends on arg λ alone, which moves by at most asin(r/|λ|) (anything, up
    to 2, once r ≥ |λ|) — exact where |δζ| ≤ 2 r/|λ| is up to 1/sin(arg λ) too wide (near-real
    roots)."""
    lam = np.atleast_1d(np.asarray(lam, complex))
    r = np.broadcast_to(np.asarray(r, float), lam.shape)
    out = np.full(lam.shape, 2.0)
    for i, (x, ri) in enumerate(zip(lam, r)):
        a, th = abs(x), abs(np.angle(x))                # ζ's sign is arg's; |arg| in [0, π]
        if a == 0 or ri >= a:
            continue
        al = np.arcsin(ri / a)
        c = [np.cos(th - al), np.cos(th + al)] + ([1.0] if th - al <= 0 else []) \
            + ([-1.0] if th + al >= np.pi else [])
        out[i] = max(abs(ci - np.cos(th)) for ci in c)
    return out


def growth_rate(p: dict, v: float, mats=None) -> float:
    """The largest real part of the roots (> 0: a motion grows)."""
    return float(np.max(eigenvalues(p, v, mats).real))


def stability_speeds(p: dict, lo: float = 0.0, hi: float = 10.0, n: int = 201,
                     xtol: float = 1e-13) -> list[tuple[float, str]]:
    """Every speed in [lo, hi] where the largest real part crosses zero, each with which way
    (“stabilises”: positive below, negative above; “destabilises”), from a scan of `n` speeds
    refined by Brent's method on the model's eigenvalues to `xtol` m/s."""
    mats = matrices(p)
    f = lambda v: growth_rate(p, v, mats)            # noqa: E731
    vs = np.linspace(lo, hi, n)
    gs = [f(v) for v in vs]
    out = []
    for a, b, ga, gb in zip(vs[:-1], vs[1:], gs[:-1], gs[1:]):
        if ga == 0.0 or np.sign(ga) != np.sign(gb):
            root = a if ga == 0.0 else brentq(f, a, b, xtol=xtol, rtol=4 * np.finfo(float).eps)
            out.append((float(root), "stabilises" if ga > 0 else "destabilises"))
    return out


def weave_capsize_speeds(p: dict, hi: float = 20.0) -> tuple[float, float]:
    """(v_w, v_c): the weave speed (the growth rate turns negative) and the capsize speed (it
    turns positive again above v_w). ValueError where the design has no such window."""
    speeds = stability_speeds(p, 0.0, hi, n=401)
    down = [v for v, way in speeds if way == "stabilises"]
    if not down:
        raise ValueError(f"no self-stable speed range below {hi:g} m/s")
    up = [v for v, way in speeds if way == "destabilises" and v > down[0]]
    return down[0], (up[0] if up else float("inf"))


def root_labels(lam: np.ndarray) -> list[str]:
    """Names of the roots as the paper gives them: a complex pair is the weave; with it, the
    larger real root the capsize and the smaller the castor; otherwise (low speed, four real
    roots) "real 1" … in descending order."""
    lam = np.asarray(lam, complex)
    osc = np.abs(lam.imag) > 0
    real = np.sort(lam.real[~osc])[::-1]
    out = {}
    if osc.sum() == 2 and len(real) == 2:
        out.update({real[0]: "capsize", real[1]: "castor"})
    else:
        out.update({r: f"real {i + 1}" for i, r in enumerate(real)})
    pairs = sorted({abs(x.imag) for x in lam[osc]})
    names = ["weave"] if len(pairs) == 1 else [f"oscillatory {i + 1}" for i in range(len(pairs))]
    return [names[pairs.index(abs(x.imag))] if abs(x.imag) > 0 else out[x.real] for x in lam]


def roots_text(lam, labels) -> str:
    """Every root in one line, a conjugate pair once: "capsize −0.3229, weave −0.7753 ± 4.465i,
    castor −14.08 [1/s]"."""
    out = []
    for x, lb in zip(lam, labels):
        if x.imag < 0:
            continue
        out.append(f"{lb} {x.real:.10g}" + (f" ± {x.imag:.10g}i" if x.imag > 0 else ""))
    return "roots: " + ", ".join(out) + " [1/s]"
