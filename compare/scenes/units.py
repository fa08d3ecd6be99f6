"""Units on input: `--set spin=400rpm`, `--set l=60cm` read through pint and converted to the
parameter's declared unit (what the leaves get and the JSON keeps). pint is imported only when a
value carries a unit, so a plain `xval run` does not pay for it.

The registry is pint's own with one change: the radian is a base dimension ([angle]) instead of
dimensionless, so a dimension check sees angles — `--set spin=10Hz` (10 cycles a second, or 10
rad/s?) is refused as the wrong dimension rather than read as 10 rad/s; `rpm`, `rev/s`, `deg`
convert exactly."""
from __future__ import annotations

import functools

from ..errors import BadInput

# the declared units' spellings pint reads differently
_SPELLINGS = {"·": "*", "²": "**2", "³": "**3"}


def pint_spelling(unit: str) -> str:
    """A Param's unit string as pint reads it ("" is dimensionless)."""
    for a, b in _SPELLINGS.items():
        unit = unit.replace(a, b)
    return unit or "dimensionless"


@functools.cache
def registry():
    from pathlib import Path

    import pint
    here = Path(pint.__file__).parent
    text = (here / "default_en.txt").read_text()
    if "radian = [] = rad" not in text or "@import constants_en.txt" not in text:
        raise RuntimeError("pint's default definitions changed: units/registry() needs a look")
    text = (text.replace("radian = [] = rad", "radian = [angle] = rad")
            .replace("@import constants_en.txt", (here / "constants_en.txt").read_text()))
    reg = pint.UnitRegistry(None, cache_folder=None)
    reg.load_definitions(text.splitlines())
    reg.define("rev = revolution")                  # 2 rev/s, as engineers write it
    return reg


def unit_of(unit: str):
    """The pint unit of a declared unit string (raises if pint cannot read it)."""
    return registry().Unit(pint_spelling(unit))


def convert(text: str, unit: str, name: str) -> float:
    """`text` (a number with a unit, e.g. "400rpm", "60 cm") in the declared `unit`; a unit pint
    does not know or of another dimension is BadInput (one line naming both units)."""
    import pint
    if not any(ch.isdigit() for ch in text):         # "rpm" alone is not 1 rpm
        raise BadInput(f"{name}: cannot read {text!r} as a number with a unit")
    reg = registry()
    try:
        q = reg.Quantity(text.strip())
    except (pint.errors.PintError, ValueError, TypeError, AttributeError, SyntaxError) as e:
        raise BadInput(f"{name}: cannot read {text!r} as a number with a unit ({e})") from None
    if not isinstance(q, reg.Quantity) or not isinstance(q.magnitude, (int, float)):
        raise BadInput(f"{name}: cannot read {text!r} as a number with a unit")
    target = unit_of(unit)
    try:
        return float(q.to(target).magnitude)
    except pint.errors.DimensionalityError:
        given = f"{q.units:~}" or "no unit"
        raise BadInput(f"{name}: {text!r} is in {given} ({q.dimensionality}), which does not "
                       f"convert to the parameter's unit {unit or 'none (a pure number)'} "
                       f"({target.dimensionality})") from None
