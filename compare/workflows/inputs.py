"""Checks of what a user asks for before anything runs, shared by the command line and the
Python API so both doors refuse alike: one BadInput line, nothing written (the output folder's
checks: compare/output/folders.py)."""
import math

from ..errors import BadInput


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
