"""Results: `Trajectory` (time-domain run) and `Modes` (frequencies), with .npz round trip."""
import json
from dataclasses import dataclass, field

import numpy as np


@dataclass
class Trajectory:
    scene: str
    solver: str
    t: np.ndarray
    channels: dict                      # name -> array on t (SI)
    status: str = "ok"                  # ok | diverged | timeout | error
    t_fail: float | None = None
    reason: str | None = None           # why it diverged / the error message
    settings: dict = field(default_factory=dict)
    stats: dict = field(default_factory=dict)
    wall_s: float = 0.0
    versions: dict = field(default_factory=dict)
    invariants: dict = field(default_factory=dict)   # conserved quantity -> max relative drift
    extra: dict = field(default_factory=dict)        # auxiliary arrays (e.g. orientation)
    # the solver's own numerical error per channel on t (from a tighter rerun), where estimated
    errors: dict = field(default_factory=dict)
    # where a step halving estimated `errors`: per channel its estimator and the members'
    # offsets y_member − y (rows 2·dt, dt/2), and the scheme ("leaf
    # integrator dt"): two runs of one scheme bound their difference by them
    # (`analysis.step_errors.pair_error`)
    members: dict = field(default_factory=dict)
    estimators: dict = field(default_factory=dict)
    scheme: str | None = None

    def final(self):
        return {k: float(v[-1]) for k, v in self.channels.items()}

    def meta(self):
        return {k: getattr(self, k) for k in ("scene", "solver", "status", "t_fail", "reason",
                                              "settings", "stats", "wall_s", "versions",
                                              "invariants", "scheme", "estimators")}

    def arrays(self) -> dict:
        """What its .npz holds (compare.output.run_folder writes it): `t`, one array per
        channel, `extra.<name>`, `error.<channel>` and `member.<channel>` arrays, `meta`
        (JSON)."""
        return {"t": self.t, **self.channels,
                **{f"extra.{k}": v for k, v in self.extra.items()},
                **{f"error.{k}": v for k, v in self.errors.items()},
                **{f"member.{k}": v for k, v in self.members.items()},
                "meta": np.array(json.dumps(self.meta(), default=_py))}

    @classmethod
    def load(cls, path):
        with np.load(path, allow_pickle=False) as z:
            meta = json.loads(str(z["meta"]))
            channels = {k: z[k] for k in z.files if k not in ("t", "meta")
                        and not k.startswith(("extra.", "error.", "member."))}
            extra = {k[6:]: z[k] for k in z.files if k.startswith("extra.")}
            errors = {k[6:]: z[k] for k in z.files if k.startswith("error.")}
            members = {k[7:]: z[k] for k in z.files if k.startswith("member.")}
            return cls(t=z["t"], channels=channels, extra=extra, errors=errors,
                       members=members, **meta)


@dataclass
class Modes:
    scene: str
    solver: str
    frequencies_hz: np.ndarray
    labels: list
    damping: np.ndarray | None = None
    shapes: np.ndarray | None = None       # one row per mode (for MAC tracking across a sweep)
    whirl: list | None = None              # "forward" / "backward" / "mixed" / "—" per mode
    notes: list = field(default_factory=list)   # e.g. "approximate: …"
    extra: dict = field(default_factory=dict)
    status: str = "ok"
    reason: str | None = None
    settings: dict = field(default_factory=dict)
    wall_s: float = 0.0
    versions: dict = field(default_factory=dict)


def _py(x):
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, np.ndarray):
        return x.tolist()
    raise TypeError(type(x).__name__)
