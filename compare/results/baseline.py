"""A baseline (`xval baseline save`, compare/workflows/sides.py builds it) read back: one
compressed .npz holding the JSON manifest and, per run, the kept samples of every channel.
`xval diff` evaluates it on the other side's grid and adds the interpolation tolerance
`recon` = max(rel × the channel's scale, err_frac × the solver's own error estimate) to the
error bars."""
from __future__ import annotations

import json
import zipfile
from pathlib import Path

import numpy as np

from ..errors import BadInput
from .base import Result
from .records import CaseRec, RunRec, Series, Side, readable

BASELINE_FORMAT = "xval-baseline"
BASELINE_VERSION = 1


class Baseline(Result):
    """A baseline file: `manifest` (its JSON: cases, runs, inputs, maps) and its samples,
    read only when compared."""
    TYPE = "baseline"

    def __init__(self, path: Path, manifest: dict, side: Side):
        self.path, self.manifest, self._side = Path(path), manifest, side

    @classmethod
    def read(cls, p) -> Baseline:
        with readable(p):
            if not zipfile.is_zipfile(p):              # np.load would try it as a pickle
                raise zipfile.BadZipFile("not a complete .npz")
            z = np.load(p, allow_pickle=False)
            manifest = json.loads(str(z["manifest"]))
            if not isinstance(manifest, dict) or manifest.get("format") != BASELINE_FORMAT:
                raise BadInput(f"{p}: not an xval baseline")
            if manifest.get("version", 0) > BASELINE_VERSION:
                raise BadInput(f"{p}: baseline version {manifest['version']} is newer than "
                               f"this xval reads ({BASELINE_VERSION})")
            return cls(p, manifest, _side(p, manifest, z))

    def to_json(self) -> dict:
        return {"result": self.TYPE, **self.manifest}

    def save(self, path) -> Path:
        """A copy of the baseline file at `path`."""
        from ..output.baseline import copy_baseline
        return copy_baseline(self.path, Path(path))

    def where(self) -> str:
        return str(self.path)

    def side(self) -> Side:
        return self._side


def _side(p, m, z) -> Side:
    rel, frac = m["recon"]["rel"], m["recon"]["err_frac"]
    cases = {}
    for name, c in m["cases"].items():
        runs = {}
        for solver, r in c["runs"].items():
            rec = RunRec(solver, r["status"], r.get("settings") or {}, r.get("versions") or {},
                         r.get("code"), r.get("digest"), r.get("reason"), r.get("frequencies"),
                         r.get("labels"))
            if r.get("arrays"):
                rec.loader = _loader(z, r, rel, frac, p)
            runs[solver] = rec
        cases[name] = CaseRec(name, c["scene"], c["kind"], c["params"], runs,
                              c.get("verdicts", {}), c.get("critical", {}), c.get("error"))
    return Side(p, "baseline", cases, m.get("maps", {}))


def _loader(z, r, rel, frac, path):
    def load():
        pre = r["arrays"]
        with readable(path):
            t = z[f"{pre}.t"]
            xs = {ch: z[f"{pre}.x.{ch}"] for ch in r["channels"]}
            errs = {ch: z[f"{pre}.e.{ch}"].astype(float) for ch in r["errors"]}
        out = {}
        for ch in r["channels"]:
            x, err = xs[ch], errs.get(ch)
            scale = float(np.nanmax(np.abs(x))) if np.isfinite(x).any() else 0.0
            recon = np.full(len(t), rel * scale)
            if err is not None:
                recon = np.maximum(recon, frac * err)
            out[ch] = Series(t, x, err, recon)
        return out
    return load
