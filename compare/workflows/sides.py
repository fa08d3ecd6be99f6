"""Baselines: one compressed .npz a user can commit (`xval baseline save`), built from any
result `xval diff` reads (a campaign, run or map folder; compare/results/records.py's `Side`):
the manifest (JSON) and, per run, the samples of every channel at float64 on a subset of the
output grid chosen so that linear interpolation through the kept samples reproduces every
dropped one within `recon_tol` = max(1e-8 × the channel's scale, 0.1 × the solver's own error
estimate there). float32 is not enough: its 6e-8 relative rounding of a value of 1e4 is 6e-4,
comparable with the 1e-6 relative change a baseline must catch (measured in
tests/studies/test_diff.py). `xval diff` evaluates the baseline on the other side's full grid and
adds `recon_tol` to the error bars (compare/results/baseline.py reads it back). Error estimates are
stored at the kept samples as the envelope over both neighbouring intervals (float32: an error
bar needs two digits), so their interpolation never under-states the estimate between kept
samples.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import BadInput
from ..output.baseline import write_baseline
from ..results import Result
from ..results.baseline import BASELINE_FORMAT, BASELINE_VERSION

RECON_REL = 1e-8          # interpolation tolerance, relative to the channel's scale: 1e-6 / 100
RECON_ERR_FRAC = 0.1      # … or a tenth of the solver's own error bar, whichever is larger


def keep_indices(t, xs, tols):
    """Sample indices (first and last always) such that linear interpolation through the kept
    samples reproduces every channel in `xs` within its tolerance array in `tols`; refined by
    bisecting every interval that has a sample off by more."""
    n = len(t)
    if n <= 2:
        return np.arange(n)
    kept = np.unique(np.r_[np.arange(0, n, 64), n - 1])
    while True:
        bad = np.zeros(n, bool)
        for x, tol in zip(xs, tols):
            fin = np.isfinite(x)
            if not fin.all():                  # non-finite samples: keep them all, as they are
                bad |= ~fin
                x = np.where(fin, x, 0.0)
            bad |= np.abs(np.interp(t, t[kept], x[kept]) - x) > tol
        bad[kept] = False
        if not bad.any():
            return kept
        seg = np.unique(np.searchsorted(kept, np.nonzero(bad)[0]) - 1)   # their intervals
        kept = np.unique(np.r_[kept, (kept[seg] + kept[seg + 1]) // 2])


def recon_tolerance(x, err):
    scale = float(np.nanmax(np.abs(x))) if np.isfinite(x).any() else 0.0
    tol = np.full(len(x), max(RECON_REL * scale, 1e-300))
    if err is not None:
        tol = np.maximum(tol, RECON_ERR_FRAC * np.nan_to_num(np.abs(err)))
    return tol


def _envelope(e, kept):
    """At each kept sample the largest |e| over the intervals on both sides of it."""
    e = np.abs(np.nan_to_num(e, nan=np.inf))
    seg_max = np.maximum.reduceat(e, kept[:-1]) if len(kept) > 1 else e[kept]
    # reduceat over [kept[k], kept[k+1]) misses the right end: include it
    seg_max = np.maximum(seg_max, e[kept[1:]]) if len(kept) > 1 else seg_max
    left = np.r_[seg_max[:1], seg_max]
    right = np.r_[seg_max, seg_max[-1:]]
    return np.maximum(left, right)


def save_baseline(source, out) -> dict:
    """Write the baseline of a result (a `Result`, or a campaign or run folder) to `out`
    (.npz); returns its summary."""
    side = (source if isinstance(source, Result) else Result.load(source)).side()
    if side.kind == "baseline":
        raise BadInput(f"{source}: is a baseline already")
    arrays, cases, n_full, n_kept = {}, {}, 0, 0
    for ci, (name, c) in enumerate(side.cases.items()):
        runs = {}
        for si, (solver, r) in enumerate(c.runs.items()):
            rec = {k: getattr(r, k) for k in ("status", "settings", "versions", "code",
                                              "digest", "reason", "frequencies", "labels")}
            ser = r.series()
            if ser:
                t = next(iter(ser.values())).t
                tols = [recon_tolerance(s.x, s.err) for s in ser.values()]
                kept = keep_indices(t, [s.x for s in ser.values()], tols)
                pre = f"c{ci}.r{si}"
                arrays[f"{pre}.t"] = t[kept]
                for ch, s in ser.items():
                    arrays[f"{pre}.x.{ch}"] = s.x[kept]
                    if s.err is not None:
                        arrays[f"{pre}.e.{ch}"] = _envelope(s.err, kept).astype(np.float32)
                rec.update(arrays=pre, channels=list(ser),
                           errors=[ch for ch, s in ser.items() if s.err is not None])
                n_full += len(t)
                n_kept += len(kept)
            runs[solver] = rec
        cases[name] = {"scene": c.scene, "kind": c.kind, "params": c.params, "runs": runs,
                       "verdicts": c.verdicts, "critical": c.critical, "error": c.error}
    manifest = {"format": BASELINE_FORMAT, "version": BASELINE_VERSION,
                "source": str(side.path), "source_kind": side.kind,
                "recon": {"rel": RECON_REL, "err_frac": RECON_ERR_FRAC},
                "cases": cases, "maps": side.maps}
    out = write_baseline(Path(out), manifest, arrays)
    return {"baseline": str(out), "bytes": out.stat().st_size, "cases": len(cases),
            "samples_full": n_full, "samples_kept": n_kept}
