"""Scene parameters as validated data: name, default, unit, meaning and the admissible range."""
import math
from dataclasses import dataclass

import numpy as np

from ..errors import BadInput

# every time scene's horizon and output grid (Scene.output_grid): how a run is made
RUN_PARAMS = ("t_end", "output_dt")


@dataclass(frozen=True)
class Param:
    name: str
    default: object
    unit: str
    doc: str
    kind: str = "float"        # float | int | vector | choice
    lo: float = -math.inf      # admissible range (closed unless open_lo/open_hi)
    hi: float = math.inf
    open_lo: bool = False      # e.g. a mass must be > 0, not >= 0
    choices: tuple = ()
    size: int = 3              # length of a vector
    # a property of the physical system (mass, length, stiffness, speed, torque …), as opposed to
    # how it is run (horizon, output grid, sweep range) or a threshold that only schedules an
    # event: goldens' noise and `xval power` perturb only continuous physical parameters
    physical: bool = True

    @property
    def is_float(self) -> bool:
        return self.kind == "float"

    @property
    def is_numeric(self) -> bool:
        """A scalar number (float or int): what a map axis can sweep."""
        return self.kind in ("float", "int")

    def shown_default(self):
        """The default as `xval show` prints it (a vector as comma-separated numbers)."""
        return ",".join(f"{x:g}" for x in self.default) if self.kind == "vector" else self.default

    @property
    def continuous_physical(self) -> bool:
        return (self.physical and self.kind in ("float", "vector")
                and self.name not in RUN_PARAMS)

    def parse(self, text):
        """Value from a `--set` string (or a campaign file's value), validated. A number may
        carry a unit (`400rpm`, `60 cm`): converted to the declared unit; a plain number is in
        the declared unit."""
        try:
            if self.kind == "vector":
                parts = text.split(",") if isinstance(text, str) else list(text)
                value = np.array([self._number(x) for x in parts])
            elif self.kind == "int":
                value = self._whole(text)
            elif self.kind == "choice":
                value = type(self.choices[0])(text)
            else:
                value = self._number(text)
        except BadInput:
            raise
        except (TypeError, ValueError):
            raise BadInput(f"{self.name}: cannot read {text!r} as {self.kind}"
                           f"{f' ({self.unit})' if self.unit else ''}") from None
        return self.check(value)

    def _number(self, text) -> float:
        try:
            return float(text)
        except ValueError:
            if not isinstance(text, str) or not any(ch.isalpha() for ch in text):
                raise
        # pint only for a value with a unit
        from .units import convert
        return convert(text, self.unit, self.name)

    def _whole(self, text) -> int:
        try:
            return int(text)
        except ValueError:
            value = self._number(text)
            if not math.isfinite(value) or value != int(value):
                raise BadInput(f"{self.name}: {text!r} is not a whole number") from None
            return int(value)

    def check(self, value):
        if self.kind == "choice":
            if value not in self.choices:
                raise BadInput(f"{self.name}: {value!r} is not one of "
                               f"{', '.join(map(str, self.choices))}")
            return value
        if self.kind == "vector":
            values = np.atleast_1d(np.asarray(value, float))
            if values.shape != (self.size,):
                raise BadInput(f"{self.name}: needs {self.size} comma-separated numbers, "
                               f"got {values.size}")
        else:           # a scalar without numpy's round trip: a map resolves every point
            values = (float(value),)
        if not all(math.isfinite(v) for v in values):
            raise BadInput(f"{self.name}: must be a finite number, got {value!r}")
        for v in values:
            low_bad = v <= self.lo if self.open_lo else v < self.lo
            if low_bad or v > self.hi:
                raise BadInput(f"{self.name}: {v:g} {self.unit} is outside the admissible range "
                               f"{'(' if self.open_lo else '['}{self.lo:g}, {self.hi:g}]"
                               .replace("  ", " "))
        return value

    def describe_range(self):
        if self.kind == "choice":
            return " | ".join(map(str, self.choices))
        return f"{'(' if self.open_lo else '['}{self.lo:g}, {self.hi:g}]"


def positive(name: str, default: float, unit: str, doc: str, hi: float = math.inf,
             physical: bool = True) -> Param:
    return Param(name, default, unit, doc, lo=0.0, hi=hi, open_lo=True, physical=physical)

