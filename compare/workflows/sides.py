"""One side of a diff: a campaign folder, a run folder or a saved baseline, read into the same
shape — cases (by name) of runs (by solver) with their inputs (parameters, settings, package
versions, model-code digest), statuses, verdicts and the data to compare (trajectories with
their error estimates, frequencies, critical speeds, map boundaries).

**Baselines** (`save_baseline`) are one compressed .npz a user can commit: the manifest (JSON)
and, per run, the samples of every channel at float64 on a subset of the output grid chosen so
that linear interpolation through the kept samples reproduces every dropped one within
`recon_tol` = max(1e-8 × the channel's scale, 0.1 × the solver's own error estimate there).
float32 is not enough: its 6e-8 relative rounding of a value of 1e4 is 6e-4, comparable with
the 1e-6 relative change a baseline must catch (measured in tests/test_diff.py). `xval diff`
evaluates the baseline on the other side's full grid and adds `recon_tol` to the error bars.
Error estimates are stored at the kept samples as the envelope over both neighbouring
intervals (float32: an error bar needs two digits), so their interpolation never under-states
the estimate between kept samples.
"""
from __future__ import annotations

import json
import zipfile
import zlib
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..analysis.trajectory import Trajectory
from ..errors import BadInput
from ..output.baseline import write_baseline
from . import guard

BASELINE_FORMAT = "xval-baseline"
BASELINE_VERSION = 1
RECON_REL = 1e-8          # interpolation tolerance, relative to the channel's scale: 1e-6 / 100
RECON_ERR_FRAC = 0.1      # … or a tenth of the solver's own error bar, whichever is larger


@dataclass
class Series:
    """A channel's samples on one side: values, its error estimate (or None) and how far a
    baseline's interpolation may be off (None for a full trajectory)."""
    t: np.ndarray
    x: np.ndarray
    err: np.ndarray | None = None
    recon: np.ndarray | None = None


@dataclass
class RunRec:
    solver: str
    status: str = "ok"
    settings: dict = field(default_factory=dict)
    versions: dict = field(default_factory=dict)
    code: str | None = None          # digest of the model code (None: not recorded)
    digest: str | None = None        # digest of all inputs (None: not recorded)
    reason: str | None = None
    frequencies: list | None = None  # frequency cases
    labels: list | None = None
    loader: object = None            # () -> {channel: Series} for time cases

    def series(self):
        return self.loader() if self.loader else {}


@dataclass
class CaseRec:
    name: str
    scene: str
    kind: str                        # "time" | "modes"
    params: dict
    runs: dict                       # solver -> RunRec
    verdicts: dict = field(default_factory=dict)     # "a~b~channel" -> verdict
    critical: dict = field(default_factory=dict)     # solver -> {name: value}
    error: str | None = None


@dataclass
class Side:
    path: Path
    kind: str                        # "campaign" | "run" | "baseline"
    cases: dict                      # name -> CaseRec
    maps: dict = field(default_factory=dict)         # map name -> {solver: [boundary]}


# --- reading folders --------------------------------------------------------------------------

# what reading a cut, empty or foreign file raises (JSON, .npz, a key the format must have)
UNREADABLE = (OSError, EOFError, ValueError, KeyError, TypeError, zipfile.BadZipFile, zlib.error)


@contextmanager
def readable(path):
    """A file that cannot be read as written: one line naming it and what is wrong (exit 2;
    for `diff` a traceback's exit 1 would read as "changes found")."""
    try:
        yield
    except BadInput:
        raise
    except UNREADABLE as e:
        p = Path(path)
        if p.is_file() and p.stat().st_size == 0:
            what = "empty file"
        elif isinstance(e, json.JSONDecodeError):
            what = f"broken JSON ({e.msg}, line {e.lineno} column {e.colno}); cut short?"
        elif isinstance(e, KeyError):
            what = f"not what xval writes (no {e})"
        else:
            line = str(e).splitlines()[0] if str(e) else ""
            what = f"cannot be read ({type(e).__name__}: {line}); cut short, or not xval's?"
        raise BadInput(f"{path}: {what}") from None


def _json(path):
    with readable(path):
        return json.loads(Path(path).read_text())


def load_side(path) -> Side:
    p = Path(path)
    if p.is_file():
        return _load_baseline(p)
    if not p.is_dir():
        raise BadInput(f"{path}: no such campaign folder, run folder or baseline file")
    if (p / "summary.json").exists() or (p / "jobs").is_dir():
        return _load_campaign(p)
    if (p / "result.json").exists() or guard.is_incomplete(p):
        return _load_run(p)
    if (p / "map.json").exists():                    # an `xval map` folder
        return Side(p, "map", {}, _load_maps(p))
    raise BadInput(f"{path}: not a campaign folder (summary.json), run folder (result.json) "
                   f"or baseline file")


def _load_campaign(p):
    owner = guard.lock_owner(p)
    if owner:
        raise BadInput(f"{p}: a campaign is writing this folder (pid {owner.get('pid')} on "
                       f"{owner.get('host')}): diff it when it has finished")
    if not (p / "summary.json").exists():
        raise BadInput(f"{p}: incomplete campaign folder (no summary.json: it was stopped); "
                       f"run the same `xval campaign` again to finish it")
    summary = _json(p / "summary.json")
    cases = {}
    with readable(p / "summary.json"):
        for obj in summary["cases"]:
            name = obj["case"]
            case_dir = p / name
            if "frequencies_hz" in (obj.get("runs") or [{}])[0] or "campbell" in obj \
                    or (case_dir / "modes.json").exists():
                cases[name] = _modes_case(name, obj)
            else:
                cases[name] = _time_case(name, obj, case_dir)
    return Side(p, "campaign", cases, _load_maps(p))


def _load_run(p):
    if guard.is_incomplete(p) or not (p / "result.json").exists():
        raise BadInput(f"{p}: incomplete run folder ({guard.MARKER} marker, no result.json: "
                       f"the run was stopped before it finished); run it again")
    obj = _json(p / "result.json")
    with readable(p / "result.json"):
        name = obj["scene"]
        if obj.get("runs") and "frequencies_hz" in obj["runs"][0]:
            return Side(p, "run", {name: _modes_case(name, obj)})
        return Side(p, "run", {name: _time_case(name, obj, p)})


def _verdicts(obj):
    return {f"{c['a']}~{c['b']}~{c['channel']}": c["verdict"] for c in obj.get("comparisons", [])}


def _time_case(name, obj, folder):
    runs = {}
    for r in obj.get("runs", []):
        f = folder / f"{r['solver']}.npz"
        rec = RunRec(r["solver"], r["status"], r.get("settings", {}), reason=r.get("reason"))
        if f.exists():
            with readable(f), np.load(f, allow_pickle=False) as z:
                meta = json.loads(str(z["meta"]))
            rec.versions = meta.get("versions", {})
            rec.digest = meta["stats"].get("input_digest")
            rec.code = meta["stats"].get("code_digest")
            rec.loader = _trajectory_loader(f)
        runs[r["solver"]] = rec
    return CaseRec(name, obj["scene"], "time", obj.get("params", {}), runs, _verdicts(obj),
                   error=obj.get("error"))


def _trajectory_loader(path):
    def load():
        with readable(path):
            tr = Trajectory.load(path)
        return {ch: Series(tr.t, x, tr.errors.get(ch)) for ch, x in tr.channels.items()}
    return load


def _modes_case(name, obj):
    runs = {r["solver"]: RunRec(r["solver"], r["status"], versions=r.get("versions", {}),
                                code=obj.get("code_digest"), digest=obj.get("input_digest"),
                                reason=r.get("reason"),
                                frequencies=[float(f) for f in r.get("frequencies_hz", [])],
                                labels=list(r.get("labels", [])))
            for r in obj.get("runs", [])}
    return CaseRec(name, obj["scene"], "modes", obj.get("params", {}), runs, _verdicts(obj),
                   {s: dict(c) for s, c in (obj.get("critical_speeds") or {}).items()},
                   error=obj.get("error"))


def _load_maps(p):
    """Every `map.json` in the campaign folder (written by `xval map` cases): its boundaries
    per solver, keyed by the map's folder."""
    out = {}
    for f in sorted(p.rglob("map.json")):
        if "jobs" in f.relative_to(p).parts[:1]:
            continue
        obj = _json(f)
        key = str(f.parent.relative_to(p))
        out[obj.get("scene", "map") if key == "." else key] = {
            "scene": obj.get("scene"), "boundaries": obj.get("boundaries") or {}}
    return out


# --- baselines ----------------------------------------------------------------------------------

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


def save_baseline(path_in, out) -> dict:
    """Write the baseline of a campaign or run folder to `out` (.npz); returns its summary."""
    side = load_side(path_in)
    if side.kind == "baseline":
        raise BadInput(f"{path_in}: is a baseline already")
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


def _load_baseline(p):
    with readable(p):
        if not zipfile.is_zipfile(p):              # np.load would try it as a pickle
            raise zipfile.BadZipFile("not a complete .npz")
        z = np.load(p, allow_pickle=False)
        manifest = json.loads(str(z["manifest"]))
        if not isinstance(manifest, dict) or manifest.get("format") != BASELINE_FORMAT:
            raise BadInput(f"{p}: not an xval baseline")
        if manifest.get("version", 0) > BASELINE_VERSION:
            raise BadInput(f"{p}: baseline version {manifest['version']} is newer than this "
                           f"xval reads ({BASELINE_VERSION})")
        rel, frac = manifest["recon"]["rel"], manifest["recon"]["err_frac"]
        cases = {}
        for name, c in manifest["cases"].items():
            runs = {}
            for solver, r in c["runs"].items():
                rec = RunRec(solver, r["status"], r.get("settings") or {},
                             r.get("versions") or {}, r.get("code"), r.get("digest"),
                             r.get("reason"), r.get("frequencies"), r.get("labels"))
                if r.get("arrays"):
                    rec.loader = _baseline_loader(z, r, rel, frac, p)
                runs[solver] = rec
            cases[name] = CaseRec(name, c["scene"], c["kind"], c["params"], runs,
                                  c.get("verdicts", {}), c.get("critical", {}), c.get("error"))
    return Side(p, "baseline", cases, manifest.get("maps", {}))


def _baseline_loader(z, r, rel, frac, path):
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
