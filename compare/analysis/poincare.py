"""The stroboscopic Poincaré section of a rotor's orbit: a point's (x, y) sampled once per
revolution, where the shaft's angle passes `phase` + 2πk (`xval identify --poincare`)."""
from __future__ import annotations

import math

import numpy as np


def section(t, angle, x, y, phase: float) -> dict:
    """The revolutions k the record completes past `phase` (angle = phase + 2πk, the angle
    increasing through it), the crossing times (linear in the angle between samples) and x, y
    there (linear between samples: a record and a model read on the same times interpolate
    alike). Returns {"k", "t", "x", "y"} arrays (empty where the angle never passes)."""
    t, a = np.asarray(t, float), np.asarray(angle, float)
    s = (a - phase) / (2.0 * math.pi)
    ks, ts, xs, ys = [], [], [], []
    crossed = np.flatnonzero(np.floor(s[1:]) > np.floor(s[:-1]))
    for i in crossed:
        k = math.floor(s[i + 1])
        f = (k - s[i]) / (s[i + 1] - s[i])
        if ks and k <= ks[-1]:
            continue          # noise on the angle crossing back and forth: the first passage
        ks.append(k)
        ts.append(t[i] + f * (t[i + 1] - t[i]))
        xs.append(x[i] + f * (x[i + 1] - x[i]))
        ys.append(y[i] + f * (y[i + 1] - y[i]))
    return {"k": np.array(ks, int), "t": np.array(ts), "x": np.array(xs), "y": np.array(ys)}


def matched(data: dict, model: dict, missing: float) -> tuple[np.ndarray, np.ndarray]:
    """Model − data of x and y at the data's revolutions; `missing` where the model has no
    such revolution (it turned slower)."""
    pos = {k: i for i, k in enumerate(model["k"])}
    dx, dy = [], []
    for j, k in enumerate(data["k"]):
        i = pos.get(k)
        dx.append(missing if i is None else model["x"][i] - data["x"][j])
        dy.append(missing if i is None else model["y"][i] - data["y"][j])
    return np.array(dx), np.array(dy)
