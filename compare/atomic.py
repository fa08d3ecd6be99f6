"""Atomic file writes: a reader sees the old file or the new one, never half of one.

Every file is written under a temporary name in its own folder and renamed over the target
when complete (a rename within one file system is atomic). `mkstemp` creates files with mode
0600; the finished file gets the mode a plain `open()` would give (0666 less the user's umask,
0644 by default), so teammates on a shared machine can read the reports.
"""
import json
import os
import re
import shutil
import tempfile
from contextlib import contextmanager
from pathlib import Path


def _umask():
    mask = os.umask(0o022)      # the only portable way to read it is to set it and set it back
    os.umask(mask)
    return mask


def readable_mode():
    """The mode `open(path, "w")` would create a file with."""
    return 0o666 & ~_umask()


# mkstemp's name: the prefix, 8 characters from [a-z0-9_], the suffix
_TEMPORARY = re.compile(r"^\.(?P<stem>.+)\.[a-z0-9_]{8}(?P<suffix>\.[^.]*)?$")


def remove_orphans(folder):
    """Remove the temporary files a killed writer left under `folder` (SIGKILL runs no
    `finally`). Only safe while no other process writes there: the caller holds the folder's
    lock. Returns how many were removed."""
    n = 0
    for f in Path(folder).rglob(".*"):
        if f.is_file() and _TEMPORARY.match(f.name):
            f.unlink(missing_ok=True)
            n += 1
    return n


@contextmanager
def atomic_path(path):
    """Yield a temporary path beside `path`; rename it over `path` only if the block succeeds."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=path.suffix, dir=path.parent)
    os.close(fd)
    try:
        yield Path(tmp)
        os.chmod(tmp, readable_mode())
        os.replace(tmp, path)
    except OSError as e:                 # name the file the user asked for, not the temporary
        if e.filename in (None, tmp, str(tmp)):
            e.filename = str(path)
        raise
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def write_text(path, text):
    with atomic_path(path) as tmp:
        tmp.write_text(text)


def write_json(path, obj):
    write_text(path, json.dumps(_unsigned_zero(obj), indent=1, default=_jsonable) + "\n")


def _unsigned_zero(x):
    """−0.0 written as 0.0 (x + 0.0 is +0.0 for either zero), everything else as it is."""
    if isinstance(x, dict):
        return {k: _unsigned_zero(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_unsigned_zero(v) for v in x]
    if isinstance(x, float) or getattr(getattr(x, "dtype", None), "kind", "") in ("f", "c"):
        return x + 0.0                   # a float, a numpy float or float array
    return x


def publish(src, dst):
    """Make `dst` a copy of the finished file `src` atomically: a hard link where the file
    system allows (no bytes copied), else a copy under a temporary name, then a rename."""
    with atomic_path(dst) as tmp:
        os.unlink(tmp)
        try:
            os.link(src, tmp)
        except OSError:
            shutil.copyfile(src, tmp)
    return Path(dst)


def _jsonable(x):
    import numpy as np
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, np.generic):
        return x.item()
    raise TypeError(f"not JSON serialisable: {type(x).__name__}")


def num(x, spec: str = "g") -> str:
    """`format(x, spec)` without a sign on zero: a ζ of −0.0 (a root's real part rounded to
    −0) reads 0, as it is."""
    return format(x + 0.0 if x == 0 else x, spec)


def clean_json(x):
    """JSON without NaN/Infinity (they become null), −0.0 as 0.0, and with numpy values as
    plain Python."""
    import math

    import numpy as np
    if isinstance(x, dict):
        return {str(k): clean_json(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [clean_json(v) for v in x]
    if isinstance(x, np.ndarray):
        return clean_json(x.tolist())
    if isinstance(x, np.generic):
        x = x.item()
    if isinstance(x, float) and not math.isfinite(x):
        return None
    if isinstance(x, float) and x == 0:
        return 0.0
    return x
