"""One run of a scene: every requested solver, compared — a `TimeResult`.

Used by `xval run`, the Python API and the campaign jobs. Solvers run one after another in
this process. With an output folder each trajectory is written atomically as soon as it
exists (a later crash loses nothing), then the recording, the report and result.json; without
one nothing is written (`TimeResult.save` writes the same files later).
"""
from __future__ import annotations

import contextlib
import datetime
import os
from collections.abc import Callable
from pathlib import Path

from .. import solvers
from ..analysis.trajectory import Trajectory
from ..output import guard
from ..output.run_folder import write_trajectory
from ..results import TimeResult
from ..scenes import Scene
from ..solvers import Solver


def new_run_dir(out: str | Path, scene_name: str) -> Path:
    stamp = datetime.datetime.now().strftime("%Y%m%d-%H%M%S")
    return Path(out) / "runs" / f"{scene_name}-{stamp}-{os.getpid()}"


def execute(plan, out_dir: str | Path | None = None, record: bool = True, report: bool = True,
            log: Callable | None = None) -> TimeResult:
    """Run a time scene's `Plan` (compare/workflows/plan.py): every solver at its planned
    settings on the planned grid, compared; recorded and reported into `out_dir` if given."""
    return run_scene(plan.scene, plan.params, list(plan.solvers),
                     lambda s: plan.settings[s.name], out_dir, record, report, log,
                     plan.timeout_s, plan.estimate_errors, plan.t_out)


def run_scene(scene: Scene, params: dict, chosen: list[Solver], settings_for: Callable,
              out_dir: str | Path | None = None, record: bool = True, report: bool = True,
              log: Callable | None = None, timeout_s: float | None = None,
              estimate_errors: bool = True, t_out=None) -> TimeResult:
    """Simulate `scene` with each solver in `chosen`; `settings_for(solver)` gives settings;
    `timeout_s` bounds each solver's wall time; `estimate_errors` reruns each solver tighter
    (where the scene allows) so the verdicts weigh its own error; `t_out`: the planned grid.
    `out_dir`: the run folder, marked incomplete until its result.json is written."""
    out_dir = Path(out_dir) if out_dir is not None else None
    trajectories, files = [], {}
    with guard.incomplete(out_dir) if out_dir else contextlib.nullcontext():
        for s in chosen:
            if log:
                log(f"{scene.name}: running {s.name} …")
            tr = solvers.simulate(scene, s, params, settings_for(s), timeout_s,
                                  estimate_errors and scene.error_estimate, t_out=t_out)
            if out_dir:
                files[s.name] = write_trajectory(out_dir, tr)
            if log:
                log(f"{scene.name}: {s.name} {tr.status} in {tr.wall_s:.3g} s"
                    + (f" ({tr.reason})" if tr.reason else ""))
            trajectories.append(tr)
        return finish_run(scene, params, trajectories, files, out_dir, record, report)


def finish_run(scene: Scene, params: dict, trajectories: list[Trajectory], files: dict,
               out_dir: str | Path | None, record: bool = True,
               report: bool = True, power: Callable | None = None) -> TimeResult:
    """The verdicts and findings of the trajectories; with `out_dir` (holding them in
    `files`), its recording, report and result.json. `power(comparisons) -> (rows, summary)`:
    the detection power of these verdicts (a campaign case that measured its sensitivities)."""
    comparisons = scene.verdicts(params, trajectories)
    findings = scene.findings(params, trajectories) if scene.findings else []
    result = TimeResult(scene, params, trajectories, comparisons, findings, out_dir, files)
    if power is not None:
        rows, text = power(comparisons)
        result.power = {"rows": rows, "summary": text}
    if out_dir:
        result.write_outputs(record, report)
    return result
