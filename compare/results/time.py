"""A time-domain run: every solver's trajectory, the pairwise comparisons, the findings."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..analysis import metrics
from ..analysis.trajectory import Trajectory
from ..analysis.verdict import Verdict, agree_text
from ..errors import BadInput
from ..scenes import Finding
from . import tables
from .base import ComparedResult, comparisons_from_json
from .records import CaseRec, Side, readable, trajectory_run, verdicts


class TimeResult(ComparedResult):
    """`xval.run(...)`, `xval run`: per solver a `Trajectory` (`r["quaternion"].t`,
    `.channels[...]`, `.errors[...]` — the solver's own error estimate on the grid —,
    `.status`, `.wall_s`, `.settings`, `.stats`), the pairwise `comparisons` with their
    verdicts, the `findings`; `scene` is the `Scene`, `scene_name` its name. `out_dir` and
    `files` (solver -> .npz, "recording", "report", "iftomm": solver -> results file of a
    benchmark problem) once written."""
    TYPE = "time"

    def __init__(self, scene, params: dict, trajectories: list, comparisons: list,
                 findings: list, out_dir=None, files: dict | None = None,
                 power: dict | None = None):
        self.scene_name = self._of(scene)
        self.params = params
        self.runs = {tr.solver: tr for tr in trajectories}
        self.comparisons = comparisons
        self.findings = findings
        self.out_dir = Path(out_dir) if out_dir else None
        self.files = dict(files or {})
        # the detection power estimated for these verdicts (a campaign case that measured
        # its sensitivities): {"rows": [Power dicts], "summary": one line}
        self.power = power

    trajectories = property(lambda self: list(self.runs.values()))
    solvers = property(lambda self: list(self.runs))
    t = property(lambda self: next(iter(self.runs.values())).t)
    ok = property(lambda self: all(tr.status == "ok" for tr in self.runs.values()))
    disagreements = property(lambda self: [c for c in self.comparisons
                                           if c.verdict == Verdict.DISAGREE])

    def __getitem__(self, solver):
        try:
            return self.runs[solver]
        except KeyError:
            raise KeyError(f"no run of {solver!r} (ran: {', '.join(self.runs)})") from None

    def final(self, channel: str) -> dict:
        """The last value of `channel` per solver."""
        return {s: float(tr.channels[channel][-1]) for s, tr in self.runs.items()}

    # --- JSON and files ----------------------------------------------------------------------

    def to_json(self) -> dict:
        """What `xval run --json` prints (contract.md) and result.json holds."""
        energy = self.scene.energy_channel
        runs = []
        for tr in self.trajectories:
            r = {"solver": tr.solver, "status": tr.status, "wall_s": round(tr.wall_s, 6),
                 "settings": tr.settings,
                 "stats": {k: v for k, v in tr.stats.items() if k != "traceback"},
                 "final": tr.final(),
                 # the run's own error bar at t_end, per channel (null: no estimate)
                 "final_error": ({c: float(np.asarray(e)[-1]) if np.ndim(e) else float(e)
                                  for c, e in tr.errors.items()} if tr.errors else None),
                 "energy_residual": metrics.energy_residual(tr, energy) if energy else None,
                 "invariants": tr.invariants,
                 "trajectory": str(self.files.get(tr.solver, ""))}
            if tr.status != "ok":
                r["t_fail"], r["reason"] = tr.t_fail, tr.reason
                if tr.status == "error":
                    r["message"] = tr.reason
            runs.append(r)
        out = {"result": self.TYPE, "scene": self.scene_name, "params": self.params,
               "runs": runs, "comparisons": [c.as_dict() for c in self.comparisons],
               "findings": [f.__dict__ for f in self.findings]}
        if self.power is not None:
            out["power"], out["power_summary"] = self.power["rows"], self.power["summary"]
        for k in ("recording", "report"):
            if k in self.files:
                out[k] = str(self.files[k])
        if "iftomm" in self.files:     # a benchmark problem's results files, one per solver
            out["files"] = {"iftomm": {s: str(f) for s, f in self.files["iftomm"].items()}}
        return out

    @classmethod
    def from_json(cls, obj: dict, folder=None) -> TimeResult:
        """The run `obj` describes, its trajectories read from `folder` (else from the paths
        the JSON names)."""
        trs, files = [], {}
        for r in obj["runs"]:
            path = Path(folder) / f"{r['solver']}.npz" if folder else Path(r["trajectory"])
            with readable(path):
                trs.append(Trajectory.load(path))
            files[r["solver"]] = path
        files.update({k: Path(folder) / Path(obj[k]).name if folder else Path(obj[k])
                      for k in ("recording", "report") if obj.get(k)})
        if "iftomm" in obj.get("files", {}):
            files["iftomm"] = {s: Path(folder) / "iftomm" / Path(f).name if folder else Path(f)
                               for s, f in obj["files"]["iftomm"].items()}
        return cls(obj["scene"], obj["params"], trs, comparisons_from_json(obj["comparisons"]),
                   [Finding(**f) for f in obj.get("findings", [])], folder, files,
                   {"rows": obj["power"], "summary": obj.get("power_summary", "")}
                   if "power" in obj else None)

    def save(self, path, record: bool = True, report: bool = True) -> Path:
        """Write what `xval run --out` writes into the folder `path` (made if missing): one
        .npz per solver, run.rrd, report.md with its plots, result.json; `out_dir` and `files`
        name the copy from then on."""
        from ..output import guard, run_folder
        from ..output.folders import make_out
        make_out(str(path))
        path = Path(path)
        with guard.incomplete(path):          # as a run folder: marked until result.json
            files = {tr.solver: run_folder.write_trajectory(path, tr)
                     for tr in self.trajectories}
            self.out_dir, self.files = path, files
            self.write_outputs(record, report)
        return path

    def write_outputs(self, record: bool = True, report: bool = True):
        """The recording, the report and result.json into `out_dir`, whose trajectories are
        written already (`xval run` writes each as soon as it exists)."""
        from ..output import run_folder
        run_folder.write_run_files(self, record, report)

    # --- views ---------------------------------------------------------------------------

    def title(self):
        return (f"{self.scene_name}: {len(self.runs)} solvers, "
                + agree_text(c.verdict for c in self.comparisons))

    def tables(self):
        return [self._solver_table(), (tables.VERDICT_HEADER,
                                       tables.verdict_rows(self.comparisons))]

    def _solver_table(self):
        chs = list(self.scene.channels)
        rows = [[s, tr.status, tables.num(tr.wall_s)]
                + [tables.num(tr.channels[c][-1], ".6g") if c in tr.channels else "—"
                   for c in chs] for s, tr in self.runs.items()]
        return ["solver", "status", "wall [s]"] + [f"{c} (end)" for c in chs], rows

    def figure(self, channels=None):
        """A matplotlib Figure: each channel (default: all) per solver, the closed form dashed
        where the scene has one — the report's channel plot."""
        from ..output.report import channels_figure
        known = self.scene.channels
        for c in channels or ():
            if c not in known:
                raise BadInput(f"channel {c!r}: not a channel of {self.scene_name} "
                               f"(channels: {', '.join(known)})")
        return channels_figure(self, channels)

    plot = figure

    def to_arrow(self, what: str = "trajectories"):
        """"trajectories": one row per solver and time (`solver`, `t`, each channel, and
        `error.<channel>` where the solver's error was estimated, else null);
        "comparisons": one row per comparison."""
        if what == "comparisons":
            return tables.arrow_rows([c.as_dict() for c in self.comparisons])
        if what != "trajectories":
            raise BadInput(f"to_arrow: {what!r} is not 'trajectories' or 'comparisons'")
        import pyarrow as pa
        chs = list(self.scene.channels)
        errs = [c for c in chs if any(c in tr.errors for tr in self.runs.values())]
        parts = []
        for s, tr in self.runs.items():
            n = len(tr.t)
            cols = {"solver": pa.array([s] * n), "t": pa.array(tr.t)}
            cols.update({c: pa.array(tr.channels[c]) for c in chs})
            cols.update({f"error.{c}": pa.array(tr.errors[c]) if c in tr.errors
                         else pa.nulls(n, pa.float64()) for c in errs})
            parts.append(pa.table(cols))
        return pa.concat_tables(parts)

    def to_pandas(self, what: str = "trajectories"):
        return tables.pandas(self.to_arrow(what))

    def side(self) -> Side:
        runs = {tr.solver: trajectory_run(tr) for tr in self.trajectories}
        case = CaseRec(self.scene_name, self.scene_name, "time", self.params, runs,
                       verdicts({"comparisons": [c.as_dict() for c in self.comparisons]}))
        return Side(self.where(), "run", {self.scene_name: case})
