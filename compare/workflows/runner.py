"""One run of a scene: every requested solver, compared, recorded and reported.

Used by `xval run` and by the campaign jobs. Solvers run one after another in this process;
each trajectory is written atomically as soon as it exists, so a later crash loses nothing.
"""
from __future__ import annotations

import datetime
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from .. import solvers
from ..analysis import metrics
from ..analysis.trajectory import Trajectory
from ..atomic import write_json
from ..scenes import Scene
from ..solvers import Solver
from . import guard


@dataclass
class RunResult:
    scene: object
    params: dict
    trajectories: list
    comparisons: list
    findings: list
    out_dir: Path
    files: dict = field(default_factory=dict)      # solver -> .npz path
    # detection power estimated for the run's verdicts: {"rows": [Power dicts], "summary"}
    power: dict | None = None

    def as_json(self):
        runs = []
        for tr in self.trajectories:
            r = {"solver": tr.solver, "status": tr.status, "wall_s": round(tr.wall_s, 6),
                 "settings": tr.settings,
                 "stats": {k: v for k, v in tr.stats.items() if k != "traceback"},
                 "final": tr.final(),
                 "energy_residual": metrics.energy_residual(tr, self.scene.energy_channel)
                 if self.scene.energy_channel else None,
                 "invariants": tr.invariants,
                 "trajectory": str(self.files.get(tr.solver, ""))}
            if tr.status != "ok":
                r["t_fail"], r["reason"] = tr.t_fail, tr.reason
                if tr.status == "error":
                    r["message"] = tr.reason
            runs.append(r)
        out = {"scene": self.scene.name, "params": self.params, "runs": runs,
               "comparisons": [c.as_dict() for c in self.comparisons],
               "findings": [f.__dict__ for f in self.findings]}
        if self.power is not None:
            out["power"], out["power_summary"] = self.power["rows"], self.power["summary"]
        if "recording" in self.files:
            out["recording"] = str(self.files["recording"])
        if "report" in self.files:
            out["report"] = str(self.files["report"])
        return out


def new_run_dir(out: str | Path, scene_name: str) -> Path:
    stamp = datetime.datetime.now().strftime("%Y%m%d-%H%M%S")
    return Path(out) / "runs" / f"{scene_name}-{stamp}-{os.getpid()}"


def execute(plan, out_dir: str | Path, record: bool = True, report: bool = True,
            log: Callable | None = None) -> RunResult:
    """Run a time scene's `Plan` (compare/workflows/plan.py): every solver at its planned
    settings on the planned grid, compared, recorded and reported."""
    return run_scene(plan.scene, plan.params, list(plan.solvers),
                     lambda s: plan.settings[s.name], out_dir, record, report, log,
                     plan.timeout_s, plan.estimate_errors, plan.t_out)


def run_scene(scene: Scene, params: dict, chosen: list[Solver], settings_for: Callable,
              out_dir: str | Path, record: bool = True, report: bool = True,
              log: Callable | None = None, timeout_s: float | None = None,
              estimate_errors: bool = True, t_out=None) -> RunResult:
    """Simulate `scene` with each solver in `chosen`; `settings_for(solver)` gives settings;
    `timeout_s` bounds each solver's wall time; `estimate_errors` reruns each solver tighter
    (where the scene allows) so the verdicts weigh its own error; `t_out`: the planned grid."""
    out_dir = Path(out_dir)
    marker = guard.mark_incomplete(out_dir)      # removed after result.json, the last file
    trajectories, files = [], {}
    for s in chosen:
        if log:
            log(f"{scene.name}: running {s.name} …")
        tr = solvers.simulate(scene, s, params, settings_for(s), timeout_s,
                              estimate_errors and scene.error_estimate, t_out=t_out)
        files[s.name] = tr.save(out_dir / f"{s.name}.npz")
        if log:
            log(f"{scene.name}: {s.name} {tr.status} in {tr.wall_s:.3g} s"
                + (f" ({tr.reason})" if tr.reason else ""))
        trajectories.append(tr)
    result = finish_run(scene, params, trajectories, files, out_dir, record, report)
    marker.unlink()
    return result


def finish_run(scene: Scene, params: dict, trajectories: list[Trajectory], files: dict,
               out_dir: str | Path, record: bool = True, report: bool = True,
               power: Callable | None = None) -> RunResult:
    """Compare, find, then record and report. `power(comparisons) -> (rows, summary)`: the
    detection power of these verdicts (a campaign case that measured its sensitivities)."""
    comparisons = scene.verdicts(params, trajectories)
    findings = scene.findings(params, trajectories) if scene.findings else []
    result = RunResult(scene, params, trajectories, comparisons, findings, Path(out_dir), files)
    if power is not None:
        rows, text = power(comparisons)
        result.power = {"rows": rows, "summary": text}
    return write_outputs(result, record, report)


def write_outputs(result: RunResult, record: bool = True, report: bool = True) -> RunResult:
    """The recording, the report and result.json into `result.out_dir` (the trajectories are
    in `result.files` already); `xval run` and the API's `.save()` write the same files."""
    out_dir, files = result.out_dir, result.files
    if record:
        from ..output.recording import write_run_recording
        files["recording"] = write_run_recording(out_dir / "run.rrd", result)
    if report:
        from ..output.report import write_run_report
        files["report"] = write_run_report(out_dir, result)
    write_json(out_dir / "result.json", result.as_json())
    return result
