"""Output folders: made once every check has passed, copied with the paths in their JSON."""
from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

from ..atomic import write_json
from ..errors import BadInput


def check_out(path):
    """`--out` must name a folder or a place where one can be made; checked before anything
    runs (BadInput, one line). Nothing is created here."""
    p = os.path.abspath(path)
    if os.path.exists(p) and not os.path.isdir(p):
        raise BadInput(f"--out {path}: exists and is not a folder")
    parent = p
    while not os.path.exists(parent):
        parent = os.path.dirname(parent)
    if not os.path.isdir(parent):
        raise BadInput(f"--out {path}: {parent} is not a folder")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise BadInput(f"--out {path}: no permission to write in {parent}")


def result_kind(folder) -> str | None:
    """The kind of xval result `folder` holds (the "result" field its JSON names: "time" for
    `xval run`, "modes", "response", "campaign", "bench", "map", "extremes", "diff", …), None
    where it holds none."""
    from .guard import LOCK, MARKER
    p = Path(folder)
    if (p / "summary.json").exists() or (p / "jobs").is_dir() or (p / LOCK).exists():
        return "campaign"
    for name, kind in (("response.json", "response"), ("bench.json", "bench"),
                       ("map.json", "map"), ("diff.json", "diff"),
                       ("identify.json", "identify"), ("detection.json", "detection"),
                       ("calibration.json", "calibration"),
                       ("result.json", None)):
        if (p / name).exists():
            try:
                return kind or json.loads((p / name).read_text()).get("result") or "time"
            except (OSError, ValueError, AttributeError):
                return None
    if (p / MARKER).exists():                        # a stopped run: "xval run started …"
        try:
            words = (p / MARKER).read_text().split()
        except OSError:
            return None
        what = words[1] if len(words) > 1 and words[0] == "xval" else None
        return "time" if what == "run" else what
    if (p / "points").is_dir():                      # a stopped map: its stored points alone
        return "map"
    if any(p.glob("reference-*.npz")):               # a stopped bench: its first trajectories
        return "bench"
    return None


def claim_out(path, kind: str, force: bool = False):
    """`--out DIR` is the result's own folder: missing, empty, or holding an xval result of the
    same `kind` (run again, it is written over; a campaign resumes in it). Any other non-empty
    folder is refused (one line) unless `force` — so a folder of other files, or one that holds
    earlier results under runs/ or campaign/, loses nothing. Checked before anything runs;
    nothing is created here."""
    check_out(path)
    p = Path(path)
    if force or not p.is_dir() or not any(p.iterdir()) or result_kind(p) == kind:
        return
    found = result_kind(p)
    roots = [f"{d}/" for d in ("runs", "campaign", "bench", "maps", "extremes", "diff")
             if (p / d).is_dir()]                # the old layout: --out was a root of these
    a = "an" if kind[:1] in "aeiou" else "a"
    what = (f"an xval {found} result (this command writes {a} {kind} result)" if found else
            f"earlier xval results under {', '.join(roots)} (--out now names the result's own "
            "folder: give a new one, e.g. DIR/NAME)" if roots else "other files")
    raise BadInput(f"--out {path}: is not empty and holds {what}; name a new or empty folder, "
                   f"or add --force to write into it anyway")


def make_out(path):
    """Create the output folder after every other check passed; a system that refuses
    (/proc, a read-only mount) is bad input, one line."""
    check_out(path)
    try:
        os.makedirs(path, exist_ok=True)
        probe = os.path.join(path, f".xval-write-test-{os.getpid()}")
        with open(probe, "w"):
            pass
        os.unlink(probe)
    except OSError as e:
        raise BadInput(f"--out {path}: cannot write there ({e.strerror})") from None


def _repath(obj, old: str, new: str):
    if isinstance(obj, dict):
        return {k: _repath(v, old, new) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_repath(v, old, new) for v in obj]
    if isinstance(obj, str) and obj.startswith(old):
        return new + obj[len(old):]
    return obj


def copy_folder(src: Path, dest, data: dict) -> tuple[Path, dict]:
    """The folder `src` copied to `dest` (made if missing), the paths in its JSON files and in
    `data` pointing at the copy."""
    make_out(str(dest))
    dest = Path(dest)
    shutil.copytree(src, dest, dirs_exist_ok=True)
    for f in dest.glob("*.json"):
        write_json(f, _repath(json.loads(f.read_text()), str(src), str(dest)))
    return dest, _repath(data, str(src), str(dest))


def write_result_json(folder, name: str, obj: dict) -> Path:
    """A result's JSON alone (a result without a report: `xval power`'s)."""
    make_out(str(folder))
    write_json(Path(folder) / name, obj)
    return Path(folder)
