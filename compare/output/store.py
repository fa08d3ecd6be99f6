"""The job stores of campaigns and maps — results kept under the digest of their inputs, so a
rerun (or a stopped run resumed) reuses them — and the campaign's case folders, which link
the stored files (hard links where the file system allows)."""
from __future__ import annotations

from pathlib import Path

from ..atomic import publish, write_json, write_text
from .run_folder import write_npz


def store_trajectory(store: Path, key: str, tr) -> Path:
    """A time job's trajectory, under its key (written atomically: a stopped job leaves no
    result file)."""
    return write_npz(tr, Path(store) / f"{key}.npz")


def store_modes(folder: Path, result) -> Path:
    """A frequency job: its result's folder (report, result.json, figures), then modes.json —
    the job's done-marker, written last."""
    result.save(folder)
    write_json(Path(folder) / "modes.json", result.to_json())
    return Path(folder)


def store_sensitivity(store: Path, key: str, obj: dict) -> Path:
    """A case's sensitivity job (one solver's response to each physical parameter)."""
    path = Path(store) / f"{key}.sensitivity.json"
    write_json(path, obj)
    return path


def store_calibration(store: Path, key: str, obj: dict) -> Path:
    """A campaign's calibration job (`xval calibrate`'s JSON, with its input digest)."""
    path = Path(store) / f"{key}.calibration.json"
    write_json(path, obj)
    return path


def store_point(store: Path, key: str, row: dict) -> None:
    """A map point's result, under its key."""
    write_json(Path(store) / f"{key}.json", row)


def link(src: Path, dst: Path) -> Path:
    """A stored file into a case folder."""
    return publish(src, dst)


def mark_case(case_dir: Path, jobs_key: str, digests: dict) -> None:
    """case.json, written last: the case's report is that of these jobs."""
    write_json(Path(case_dir) / "case.json", {"jobs": jobs_key, "digests": digests})


def case_failed(case_dir: Path, text: str) -> Path:
    """report.log of a case whose comparison or report failed (the traceback)."""
    path = Path(case_dir) / "report.log"
    write_text(path, text)
    return path
