"""The records `xval identify` fits: read (CSV with a header row, or .npz; columns by the
scene's channel names plus t), checked (one line on what is wrong), and synthesised from a
solver's run with white normal noise of a stated σ and seed. Nothing is written here."""
from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from .. import solvers
from ..errors import BadInput
from ..scenes import get_scene


def fit_spec(scene):
    """The scene's `Fit` (what it identifies), or one line saying it has none."""
    if scene.fit is None:
        raise BadInput(f"scene {scene.name!r} declares nothing to identify")
    return scene.fit


# ------------------------------------------------------------------ the record
def read_record(path) -> dict:
    """A record file: CSV with a header row, or .npz; columns by name. One line on what is
    wrong with it (BadInput)."""
    path = Path(path)
    if not path.is_file():
        raise BadInput(f"--data {path}: no such file")
    if path.suffix == ".npz":
        try:
            with np.load(path, allow_pickle=False) as z:
                return {k: np.asarray(z[k], float).ravel() for k in z.files}
        except (ValueError, OSError) as e:
            raise BadInput(f"--data {path}: not a readable .npz ({str(e).splitlines()[0]})") \
                from None
    with open(path, newline="") as fh:
        rows = [r for r in csv.reader(fh) if r and any(c.strip() for c in r)]
    if len(rows) < 2:
        raise BadInput(f"--data {path}: a CSV needs a header row and at least one data row")
    head = [h.strip() for h in rows[0]]
    cols = {h: [] for h in head}
    for i, r in enumerate(rows[1:], start=2):
        if len(r) != len(head):
            raise BadInput(f"--data {path}: line {i} has {len(r)} fields, the header "
                           f"{len(head)}")
        for h, c in zip(head, r):
            try:
                cols[h].append(float(c))
            except ValueError:
                raise BadInput(f"--data {path}: line {i}, column {h}: {c.strip()!r} is not a "
                               "number") from None
    return {h: np.asarray(v, float) for h, v in cols.items()}


def check_record(scene, rec: dict, where: str = "--data") -> list[str]:
    """The record's channels (in the scene's order) after the checks every record must pass."""
    if "t" not in rec:
        raise BadInput(f"{where}: no time column 't' (columns: {', '.join(rec) or 'none'})")
    known = list(scene.channels)
    unknown = [k for k in rec if k != "t" and k not in known]
    if unknown:
        raise BadInput(f"{where}: unknown channel {unknown[0]!r} for scene {scene.name} "
                       f"(channels: {', '.join(known)})")
    chans = [c for c in known if c in rec]
    if not chans:
        raise BadInput(f"{where}: no channel of scene {scene.name} besides t")
    t = rec["t"]
    for k in ["t", *chans]:
        if len(rec[k]) != len(t):
            raise BadInput(f"{where}: column {k} has {len(rec[k])} values, t {len(t)}")
        bad = np.flatnonzero(~np.isfinite(rec[k]))
        if len(bad):
            raise BadInput(f"{where}: column {k} is not finite at row {bad[0] + 1} "
                           f"({rec[k][bad[0]]})")
    if len(t) < 4:
        raise BadInput(f"{where}: {len(t)} samples; at least 4")
    step = np.diff(t)
    if (step <= 0).any():
        i = int(np.flatnonzero(step <= 0)[0])
        raise BadInput(f"{where}: time is not increasing at row {i + 2} (t = {t[i + 1]:g} s "
                       f"after {t[i]:g} s)")
    if t[0] < 0:
        raise BadInput(f"{where}: time starts at {t[0]:g} s; the record starts at t ≥ 0 "
                       "(t = 0: the scene's initial state)")
    return chans


# ------------------------------------------------------------------ synthetic records
def clean_record(scene_name: str, solver_name: str, params: dict | None = None,
                 channels=None) -> dict:
    """A solver's noise-free record of the scene at `params` (its own grid t_end/output_dt):
    {"t", channel…} (default channels: those of the scene's `Fit.noise`)."""
    scene = get_scene(scene_name)
    spec = fit_spec(scene)
    chans = list(channels or spec.noise)
    for c in chans:
        if c not in scene.channels:
            raise BadInput(f"--channel {c}: not a channel of scene {scene.name}")
    p = scene.resolve(params or {})
    (s,) = solvers.pick(scene, [solver_name])
    st = solvers.settings_for(s, scene)
    tr = solvers.simulate(scene, s, p, st)
    if tr.status != "ok":
        raise BadInput(f"{solver_name}: the synthesising run {tr.status}: {tr.reason}")
    return {"t": tr.t, **{c: tr.channels[c] for c in chans}}


def add_noise(scene_name: str, clean: dict, noise: dict | None = None, seed: int = 0) -> dict:
    """The record with white normal noise σ per channel (default the scene's `Fit.noise`),
    drawn from numpy's Generator seeded with `seed`."""
    spec = fit_spec(get_scene(scene_name))
    sig = {**spec.noise, **(noise or {})}
    rng = np.random.default_rng(seed)
    out = {"t": clean["t"]}
    for c, y in clean.items():
        if c != "t":
            out[c] = y + sig[c] * rng.standard_normal(len(y))
    return out


def synthesise(scene_name: str, solver_name: str, params: dict | None = None,
               noise: dict | None = None, seed: int = 0, channels=None) -> dict:
    """A synthetic measured record: `clean_record` plus `add_noise`."""
    return add_noise(scene_name, clean_record(scene_name, solver_name, params, channels),
                     noise, seed)
