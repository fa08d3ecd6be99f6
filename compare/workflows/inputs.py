"""Checks of what a user asks for before anything runs, shared by the command line and the
Python API so both doors refuse alike: one BadInput line, nothing written."""
import math
import os

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


def positive(name, value):
    """A positive finite number or None (the option left out); the command line's wording."""
    if value is None:
        return None
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise BadInput(f"{name} must be a number, got {value!r}") from None
    if isinstance(value, bool) or not (math.isfinite(v) and v > 0):
        raise BadInput(f"{name} must be a positive number, got {value!r}")
    return v


def positive_int(name, value):
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int):
        raise BadInput(f"{name} must be a whole number, got {value!r}")
    if value < 1:
        raise BadInput(f"{name} must be at least 1, got {value!r}")
    return value
