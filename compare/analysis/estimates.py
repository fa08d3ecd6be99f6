"""Least-squares estimates as values: the noise of a record, the intervals and identifiability
from a fit's Jacobian, and the verdict on two estimates of one parameter (`xval identify`).

Units: the fit works in scaled unknowns u = x / scale, on residuals already divided by each
sample's σ, so a Jacobian here is d(residual/σ)/du and (JᵀJ)⁻¹ is the covariance of u."""
from __future__ import annotations

import math

import numpy as np

from .verdict import Verdict

Z95 = 1.959963984540054     # two-sided 95 % of a normal: the interval's half width in σ
NULL = 1e-8                 # a singular value below NULL·largest is a direction the data miss
IN_NULL = 0.1               # an unknown with this share of such a direction is undetermined


def noise_sigma(y) -> float:
    """σ of white noise on a smooth record: the second differences are noise (variance 6σ²)
    where the signal is smooth on the sampling scale; their median absolute value (÷ 0.6745, a
    normal's) ignores the few samples where it is not (a defect's bump)."""
    d2 = np.diff(np.asarray(y, float), 2)
    if len(d2) == 0:
        return float("nan")
    return float(np.median(np.abs(d2 - np.median(d2))) / 0.6744897501960817 / math.sqrt(6.0))


def intervals(jac, scale, z: float = Z95, width_limit=None) -> dict:
    """From the Jacobian of σ-weighted residuals in scaled unknowns: each unknown's standard
    deviation and interval half width (z·sd, in the unknown's own unit), the correlation
    matrix, and whether the data determine it. An unknown is undetermined where it has a
    share ≥ IN_NULL in a direction the Jacobian does not see (singular value < NULL of the
    largest: a null column or a combination of columns), or where its half width exceeds
    `width_limit` (its own unit; None: no limit)."""
    J = np.asarray(jac, float)
    scale = np.asarray(scale, float)
    n = J.shape[1]
    _, s, vt = np.linalg.svd(J, full_matrices=False)
    seen = s > NULL * (s[0] if len(s) and s[0] > 0 else 1.0)
    blind = np.zeros(n, bool)
    for k in np.flatnonzero(~seen):
        blind |= np.abs(vt[k]) >= IN_NULL
    if len(s) < n:
        blind[:] = True
    cov_u = (vt[seen].T / s[seen] ** 2) @ vt[seen] if seen.any() else np.zeros((n, n))
    sd_u = np.sqrt(np.clip(np.diag(cov_u), 0.0, None))
    sd = sd_u * np.abs(scale)
    half = z * sd
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov_u / np.outer(sd_u, sd_u)
    limit = np.full(n, np.inf) if width_limit is None else np.asarray(width_limit, float)
    ok = ~blind & np.isfinite(half) & (half <= limit)
    sd[blind], half[blind] = np.inf, np.inf
    corr[blind, :], corr[:, blind] = np.nan, np.nan
    return {"sd": sd, "half_width": half, "correlation": corr, "identifiable": ok,
            "singular_values": s}


def wrap(x: float, period: float | None) -> float:
    """x into [−period/2, period/2) (unchanged without a period)."""
    if not period:
        return float(x)
    return float((x + 0.5 * period) % period - 0.5 * period)


def judge(a: dict, b: dict, period: float | None = None) -> dict:
    """Two estimates of one parameter (each a dict with value, half_width, identifiable, ok):
    agree when they differ by less than their combined interval √(h_a² + h_b²); a failed fit
    on either side is incomplete, an unknown neither determines is no data, one only one side
    determines is incomplete — never agree."""
    if not (a.get("ok") and b.get("ok")):
        return {"verdict": Verdict.INCOMPLETE, "why": "a fit did not converge"}
    if not (a["identifiable"] or b["identifiable"]):
        return {"verdict": Verdict.NO_DATA, "why": "neither fit determines it"}
    if not (a["identifiable"] and b["identifiable"]):
        return {"verdict": Verdict.INCOMPLETE, "why": "only one fit determines it"}
    diff = abs(wrap(a["value"] - b["value"], period))
    bound = math.hypot(a["half_width"], b["half_width"])
    return {"verdict": Verdict.AGREE if diff <= bound else Verdict.DISAGREE,
            "difference": diff, "bound": bound, "ratio": diff / bound if bound > 0 else math.inf}
