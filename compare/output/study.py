"""A study's two files — report.md (its Markdown lines) and its JSON — written atomically for
`xval modes`, `xval extremes` and `xval bench` (orchestration composes them, writes nothing)."""
from __future__ import annotations

from pathlib import Path

from ..atomic import write_json, write_text


def write_study(out_dir: Path, md: list[str], obj: dict, json_name: str = "result.json",
                report_in_json: bool = True) -> dict:
    """report.md, then `json_name`; `obj["report"]` is the report's path (in the JSON too
    unless `report_in_json` is False: bench.json never held it). Returns `obj`."""
    report = Path(out_dir) / "report.md"
    write_text(report, "\n".join(md) + "\n")
    if report_in_json:
        obj["report"] = str(report)
    write_json(Path(out_dir) / json_name, obj)
    obj["report"] = str(report)
    return obj
