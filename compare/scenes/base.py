"""The Scene type: a frozen, validated parameter set plus what to compare and how strictly."""
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..errors import BadInput
from ..params import Param


@dataclass(frozen=True)
class Scene:
    name: str
    title: str
    source: str                     # the paper / spec it comes from
    kind: str                       # "time" (xval run) or "modes" (xval modes)
    params: tuple[Param, ...]
    channels: tuple[str, ...] = ()
    # per-channel verdict tolerance, relative to the channel's scale (max |value| of the pair)
    tolerances: dict = field(default_factory=dict)
    key_channel: str = ""           # the channel whose final value the benchmark measures
    energy_channel: str | None = "energy_balance"
    # a run whose energy balance drifts by more than this fraction of the energy scale is
    # reported `diverged` (stable-but-wrong integration must not pass as "ok")
    energy_bound: float = 0.05
    # conserved quantities (channel -> reported as relative drift in `invariants`)
    invariant_channels: tuple[str, ...] = ()
    # closed forms drawn with a channel: channel -> (trajectory extra key, label); plotted in
    # the report and recorded as `<channel>/<label>` next to the solvers
    analytic: dict = field(default_factory=dict)
    # the bench's reference: the first runs tightest, the second confirms it (names only)
    reference_solvers: tuple[str, ...] = ()
    check: Callable | None = None   # cross-parameter physical checks, raises BadInput
    findings: Callable | None = None  # (params, trajectories) -> list[Finding]
    notes: str = ""

    def param(self, name):
        for p in self.params:
            if p.name == name:
                return p
        raise BadInput(f"{name}: unknown parameter of scene {self.name} "
                       f"(known: {', '.join(p.name for p in self.params)})")

    def resolve(self, overrides=None):
        """Defaults with `--set` overrides applied; every value validated. Raises BadInput."""
        values = {p.name: p.default for p in self.params}
        for name, text in (overrides or {}).items():
            values[name] = self.param(name).parse(text)
        for p in self.params:                      # defaults are checked too (campaign files)
            p.check(values[p.name])
        if self.check:
            self.check(values)
        if self.kind == "time":
            self.output_grid(values)               # the grid must fit before anything runs
        return values

    def output_grid(self, params):
        t_end, dt = params["t_end"], params["output_dt"]
        n = int(round(t_end / dt))
        if n < 1 or abs(n * dt - t_end) > 1e-9 * t_end:
            raise BadInput(f"output_dt: {dt:g} s must divide t_end = {t_end:g} s into whole steps")
        return np.linspace(0.0, t_end, n + 1)


@dataclass(frozen=True)
class Finding:
    """One statement of the report, with the number that backs it."""
    name: str
    value: float | None
    unit: str
    text: str
