"""A run folder (`xval run --out`, a campaign case, `TimeResult.save`): one .npz per solver,
run.rrd, report.md with its plots, result.json — the last file; until it is written the
folder is marked incomplete (guard.py)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..atomic import atomic_path, write_json


def write_trajectory(folder, tr, name: str | None = None) -> Path:
    """A trajectory as `name`.npz (default: its solver's name), atomically, as soon as it
    exists (a later crash loses nothing)."""
    return write_npz(tr, Path(folder) / f"{name or tr.solver}.npz")


def write_npz(tr, path) -> Path:
    """A trajectory's arrays (`Trajectory.arrays`) as one .npz, atomically."""
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as f:
            np.savez(f, **tr.arrays())
    return path


def write_run_files(result, record: bool = True, report: bool = True) -> dict:
    """The recording, the report, a benchmark problem's results files (iftomm/) and result.json
    into `result.out_dir` (its trajectories are in `result.files` already); returns
    `result.files`, which names them too."""
    out_dir, files = result.out_dir, result.files
    if record:
        from .recording import write_run_recording
        files["recording"] = write_run_recording(out_dir / "run.rrd", result)
    if report:
        from .report import write_run_report
        files["report"] = write_run_report(out_dir, result)
        from .html_report import write_run_html
        write_run_html(out_dir, result)          # report.html beside report.md
    if result.scene.benchmark is not None:       # an IFToMM problem: its results files
        from .iftomm import write_results
        files["iftomm"] = write_results(out_dir, result.scene, result.params,
                                        result.trajectories)
    write_json(out_dir / "result.json", result.to_json())
    return files
