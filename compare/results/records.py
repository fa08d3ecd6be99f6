"""What `xval diff` compares, whatever a result was read from: a `Side` — cases (by name) of
runs (by solver) with their inputs (parameters, settings, package versions, model-code
digest), statuses, verdicts and the data to compare (trajectories with their error estimates,
frequencies, critical speeds, map boundaries). Every `Result` gives its own (`Result.side()`);
the readers here are shared by a run folder, a campaign folder and a baseline, and turn a file
that cannot be read into one line (`readable`)."""
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
    path: Path | str
    kind: str                        # "campaign" | "run" | "map" | "baseline"
    cases: dict                      # name -> CaseRec
    maps: dict = field(default_factory=dict)         # map name -> {solver: [boundary]}


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


def read_json(path):
    with readable(path):
        return json.loads(Path(path).read_text())


def verdicts(obj):
    return {f"{c['a']}~{c['b']}~{c['channel']}": c["verdict"] for c in obj.get("comparisons", [])}


def trajectory_run(tr: Trajectory) -> RunRec:
    """A run held in memory (or read whole from its .npz)."""
    series = {ch: Series(tr.t, x, tr.errors.get(ch)) for ch, x in tr.channels.items()}
    return RunRec(tr.solver, tr.status, tr.settings, tr.versions, tr.stats.get("code_digest"),
                  tr.stats.get("input_digest"), tr.reason, loader=lambda: series)


def time_case(name, obj, folder):
    """A time case from its JSON and the .npz files in `folder`, read only when compared (a
    campaign's trajectories are not all held at once)."""
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
    return CaseRec(name, obj["scene"], "time", obj.get("params", {}), runs, verdicts(obj),
                   error=obj.get("error"))


def _trajectory_loader(path):
    def load():
        with readable(path):
            tr = Trajectory.load(path)
        return {ch: Series(tr.t, x, tr.errors.get(ch)) for ch, x in tr.channels.items()}
    return load


def modes_case(name, obj):
    runs = {r["solver"]: RunRec(r["solver"], r["status"], versions=r.get("versions", {}),
                                code=obj.get("code_digest"), digest=obj.get("input_digest"),
                                reason=r.get("reason"),
                                frequencies=[float(f) for f in r.get("frequencies_hz", [])],
                                labels=list(r.get("labels", [])))
            for r in obj.get("runs", [])}
    return CaseRec(name, obj["scene"], "modes", obj.get("params", {}), runs, verdicts(obj),
                   {s: dict(c) for s, c in (obj.get("critical_speeds") or {}).items()},
                   error=obj.get("error"))


def case_type(obj, folder=None) -> str:
    """"modes" or "time": the type a result's JSON (or a campaign case's) says it is in its
    "result" field; one written before every case said so, by what it holds."""
    if obj.get("result"):
        return obj["result"]
    holds_modes = "frequencies_hz" in (obj.get("runs") or [{}])[0] or "campbell" in obj \
        or bool(folder and (Path(folder) / "modes.json").exists())
    return "modes" if holds_modes else "time"


def read_maps(p):
    """Every `map.json` under the folder `p` (an `xval map` folder, or a campaign's maps): its
    boundaries per solver, keyed by the map's folder."""
    out = {}
    for f in sorted(Path(p).rglob("map.json")):
        if "jobs" in f.relative_to(p).parts[:1]:
            continue
        obj = read_json(f)
        key = str(f.parent.relative_to(p))
        out[obj.get("scene", "map") if key == "." else key] = {
            "scene": obj.get("scene"), "boundaries": obj.get("boundaries") or {}}
    return out
