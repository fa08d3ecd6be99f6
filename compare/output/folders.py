"""Output folders: made once every check has passed, copied with the paths in their JSON."""
from __future__ import annotations

import json
import os
import shutil
import tempfile
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


def temporary_folder() -> Path:
    return Path(tempfile.mkdtemp(prefix="xval-"))


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
