"""Natural frequencies: every solver's modes, matched mode by mode; the Campbell diagram and
critical speeds where the scene sweeps."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..analysis.trajectory import Modes
from ..analysis.verdict import Verdict
from ..errors import BadInput
from ..output.modes_report import DAMPED_HEADER, damped_rows, log_dec  # noqa: F401 (the tables)
from . import tables
from .base import ComparedResult, comparisons_from_json
from .records import Side, modes_case

# the run fields of the JSON (contract.md); any other key of a run is one of its `extra` arrays
_RUN_KEYS = ("solver", "status", "wall_s", "frequencies_hz", "labels", "versions", "notes",
             "reason", "omega_d", "rpm", "zeta", "log_dec", "whirl")


def _run_json(r: Modes) -> dict:
    return {"solver": r.solver, "status": r.status, "wall_s": round(r.wall_s, 6),
            "frequencies_hz": list(r.frequencies_hz), "labels": r.labels,
            "versions": r.versions, **damped_json(r),
            **({"notes": r.notes} if r.notes else {}),
            **({k: _extra_json(v) for k, v in r.extra.items()}),
            **({"reason": r.reason} if r.reason else {})}


def _extra_json(v):
    """An extra array as JSON: a flat list, or nested rows where it has two axes or more (every
    root as [Re, Im])."""
    return np.asarray(v).tolist() if np.ndim(v) > 1 else list(np.ravel(v))


def damped_json(m: Modes | None) -> dict:
    """A run's damped modes as `xval modes --json` lists them (contract.md, "Rotordynamic
    results"): ω_d [rad/s] and rpm beside frequencies_hz, ζ, log dec, whirl; {} without ζ."""
    if m is None or m.damping is None:
        return {}
    w = 2 * np.pi * np.asarray(m.frequencies_hz, float)
    return {"omega_d": list(w), "rpm": list(w * 30 / np.pi), "zeta": list(map(float, m.damping)),
            "log_dec": list(map(float, log_dec(m.damping))),
            **({"whirl": list(m.whirl)} if m.whirl is not None else {})}


def growing_modes(results: list[Modes], floor: float = 0.0) -> list[dict]:
    """Every mode that grows (the linearised system is unstable), per solver, with its growth
    rate Re λ = −ζ ω_d/√(1 − ζ²) [1/s]: ζ below zero by more than its error — the solver's
    own estimate (extra "damping_error") plus `floor`, the scene's damping allowance (what
    its solvers cannot tell from zero: an undamped rotor-whirl gives ζ = −1.2e-16 in one
    solver's eigenvalues, round-off, not a growing root)."""
    out = []
    for m in results:
        if m.status != "ok" or m.damping is None:
            continue
        errors = m.extra.get("damping_error")
        errors = np.zeros(len(m.damping)) if errors is None else np.asarray(errors, float)
        for f, lb, z, e in zip(m.frequencies_hz, m.labels, m.damping, errors):
            if z < -(floor + e):
                out.append({"solver": m.solver, "mode": lb, "frequency_hz": float(f),
                            "zeta": float(z),
                            "growth_per_s": float(-z * 2 * np.pi * f / np.sqrt(1 - z * z))})
    return out


class ModesResult(ComparedResult):
    """`xval.modes(...)`, `xval modes`: per solver the `Modes` (`r["mstmm"].frequencies_hz`,
    `.labels`, `.status`, `.wall_s`), the mode-by-mode `comparisons`, the `critical_speeds`
    (solver -> {name: value}) and `campbell` (the diagram's JSON) where the scene sweeps,
    `status` (agree / inconclusive / disagree / incomplete) and its one line `summary`,
    `unpaired_modes`, `incomplete`; what else the study found (explanations, identification)
    in `extra`.

    A result made in memory holds what its report needs beyond the JSON (`parts`: the scene's
    mode-by-mode comparisons, its hooks' lines, the Campbell sweep's verdicts; `drawing`: the
    Campbell lines), composed and written by `save` (compare/output/modes_report.py); one read
    from files is saved by copying its folder."""
    TYPE = "modes"
    FREQ_HEADER = ["solver", "status", "wall [s]", "frequencies [Hz] (labels)"]

    def __init__(self, scene, params: dict, runs: list[Modes], comparisons: list, *,
                 status: str | None = None, summary: str | None = None,
                 critical_speeds: dict | None = None, campbell: dict | None = None,
                 unpaired_modes: list | None = None, incomplete: list | None = None,
                 extra: dict | None = None, parts: dict | None = None, drawing=None,
                 out_dir=None, files: dict | None = None):
        self.scene_name = self._of(scene)
        self.params = params
        self.runs = {r.solver: r for r in runs}
        self.comparisons = comparisons
        self.status, self.summary = status, summary
        self.critical_speeds = critical_speeds or {}
        self.campbell = campbell
        self.unpaired_modes = unpaired_modes or []
        self.incomplete = incomplete or []
        self.extra = extra or {}
        self.parts, self.drawing = parts, drawing
        self.out_dir = Path(out_dir) if out_dir else None
        self.files = dict(files or {})

    solvers = property(lambda self: list(self.runs))
    disagreements = property(lambda self: [c for c in self.comparisons
                                           if c.verdict == Verdict.DISAGREE])

    def __getitem__(self, solver):
        return self.runs[solver]

    # --- JSON and files ----------------------------------------------------------------------

    def to_json(self) -> dict:
        """What `xval modes --json` prints (contract.md) and result.json holds."""
        out = {"result": self.TYPE, "scene": self.scene_name, "params": self.params,
               "runs": [_run_json(r) for r in self.runs.values()],
               "comparisons": [c.as_dict() for c in self.comparisons],
               "unpaired_modes": self.unpaired_modes, "incomplete": self.incomplete,
               **self.extra}
        if self.campbell is not None:
            out["critical_speeds"], out["campbell"] = self.critical_speeds, self.campbell
        out.update({k: str(v) for k, v in self.files.items()})
        out["status"], out["summary"] = self.status, self.summary
        return out

    @classmethod
    def from_json(cls, obj: dict, folder=None) -> ModesResult:
        runs = [Modes(obj["scene"], r["solver"], np.asarray(r["frequencies_hz"], float),
                      list(r["labels"]), notes=r.get("notes", []),
                      damping=np.asarray(r["zeta"], float) if "zeta" in r else None,
                      whirl=r.get("whirl"),
                      extra={k: np.asarray(v) for k, v in r.items() if k not in _RUN_KEYS},
                      status=r["status"], reason=r.get("reason"), wall_s=r.get("wall_s", 0.0),
                      versions=r.get("versions", {})) for r in obj["runs"]]
        files = ("report", "recording", "mode_shapes_recording", "mode_shapes_figure",
                 "frequencies_figure")
        known = {"result", "scene", "params", "runs", "comparisons", "unpaired_modes",
                 "incomplete", "critical_speeds", "campbell", "status", "summary", *files}
        return cls(obj["scene"], obj["params"], runs, comparisons_from_json(obj["comparisons"]),
                   status=obj.get("status"), summary=obj.get("summary"),
                   critical_speeds=obj.get("critical_speeds"), campbell=obj.get("campbell"),
                   unpaired_modes=obj.get("unpaired_modes"), incomplete=obj.get("incomplete"),
                   extra={k: v for k, v in obj.items() if k not in known}, out_dir=folder,
                   files={k: Path(folder) / Path(obj[k]).name if folder else Path(obj[k])
                          for k in files if obj.get(k)})

    def save(self, path) -> Path:
        """Write what `xval modes --out` writes into the folder `path`: report.md,
        result.json, the Campbell diagram and its recording, the mode shapes."""
        from ..output.folders import copy_folder, make_out
        from ..output.modes_folder import write_modes_folder
        if self.parts is None:                  # read from files: its folder holds them
            if self.out_dir is None:
                raise BadInput("nothing to save: this modes result holds no report")
            self.out_dir = copy_folder(self.out_dir, path, {})[0]
            self.files = {k: self.out_dir / Path(v).name for k, v in self.files.items()}
            return self.out_dir
        make_out(str(path))
        write_modes_folder(Path(path), self)
        return Path(path)

    # --- views ---------------------------------------------------------------------------

    def title(self):
        return f"{self.scene_name}: {len(self.runs)} solvers, {self.summary}"

    def tables(self):
        damped = damped_rows(list(self.runs.values()))   # ζ, log dec, rad/s and rpm beside Hz
        return [(self.FREQ_HEADER, self._freq_rows()),
                *([(DAMPED_HEADER, damped)] if damped else []),
                (tables.VERDICT_HEADER, tables.verdict_rows(self.comparisons))]

    def lines(self):
        return self._crit() + threshold_lines(self.extra.get("threshold"))

    def _freq_rows(self):
        return [[s, m.status, tables.num(m.wall_s),
                 ", ".join(f"{f:.6g}" + (f" ({lb})" if lb else "")
                           for f, lb in zip(m.frequencies_hz,
                                            m.labels or [""] * len(m.frequencies_hz)))
                 or (m.reason or "")] for s, m in self.runs.items()]

    def _crit(self):
        return [f"critical {s}: " + ", ".join(f"{k} {v:.6f}" for k, v in c.items())
                for s, c in self.critical_speeds.items() if c]

    def figure(self):
        """A matplotlib Figure: the Campbell diagram where the scene sweeps, else each
        solver's frequencies side by side."""
        from ..output.frequency_plot import overview_figure
        return overview_figure(self.scene_name, self.runs, self.campbell)

    plot = figure

    def to_arrow(self, what: str = "frequencies"):
        """"frequencies": one row per solver and mode; "comparisons": one per comparison."""
        if what == "comparisons":
            return tables.arrow_rows([c.as_dict() for c in self.comparisons])
        if what != "frequencies":
            raise BadInput(f"to_arrow: {what!r} is not 'frequencies' or 'comparisons'")
        return tables.arrow_rows([{"solver": s, "mode": i + 1,
                                   "label": (m.labels[i] if i < len(m.labels) else "") or "",
                                   "frequency_hz": float(f)}
                                  for s, m in self.runs.items()
                                  for i, f in enumerate(m.frequencies_hz)])

    def to_pandas(self, what: str = "frequencies"):
        return tables.pandas(self.to_arrow(what))

    def side(self) -> Side:
        return Side(self.where(), "run", {self.scene_name: modes_case(self.scene_name,
                                                                      self.to_json())})


def threshold_lines(th: dict | None) -> list[str]:
    """One line per source of `xval modes`' threshold block (workflows/threshold.py)."""
    if not th:
        return []
    if th["closed_form_rad_s"] is None:
        return ["threshold: none (closed form: every speed stable)"]
    out = [f"threshold closed form: {th['closed_form_rad_s']:.10g} rad/s"]
    for kind in ("eigenvalues", "time_domain"):
        out += [f"threshold {r['solver']} {kind.replace('_', ' ')}: "
                + (f"{r['threshold_rad_s']:.10g} ± {r['error_rad_s']:.2g} rad/s"
                   + ("" if r["agrees"] else " — disagrees with the closed form")
                   if r["status"] == "ok" else f"{r['status']}: {r['reason']}")
                for r in th[kind]]
    return out
