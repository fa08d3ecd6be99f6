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
    write_text(report, "\n".join(_with_header(md, obj)) + "\n")
    from .html_report import write_study_html
    write_study_html(out_dir, obj)               # report.html beside report.md
    if report_in_json:
        obj["report"] = str(report)
    write_json(Path(out_dir) / json_name, obj)
    obj["report"] = str(report)
    return obj


def _with_header(md: list[str], obj: dict) -> list[str]:
    """A study of one scene at one parameter set whose report has no header yet (the bench's,
    composed where the defaults are not at hand) gets it under its title: the source papers
    and the parameters that differ from the defaults (`report.header_lines`)."""
    if not (md and isinstance(obj.get("scene"), str) and isinstance(obj.get("params"), dict)) \
            or any(line.startswith("Parameters:") for line in md):
        return md
    from ..scenes import get_scene
    from .report import header_lines
    try:
        scene = get_scene(obj["scene"])
    except Exception:                   # a scene no longer registered: the report as it is
        return md
    return [md[0], "", *header_lines(scene, obj["params"])[:-1], *md[1:]]


def _num(v):
    return "" if v is None else f"{v:.3g}"


def _pairs(d: dict) -> str:
    return ", ".join(f"{k}={v}" for k, v in d.items())


def extremes_markdown(data: dict) -> list[str]:
    """`xval extremes`' report: per case and solver the outcome, its number and why; each
    case's parameters, settings and reason."""
    md = [f"# Extremes: {data['scene']}", "", "| case | solver | outcome | number | detail |",
          "|---|---|---|---|---|"]
    md += [f"| {r['case']} | {r['solver']} | **{r['outcome']}"
           f"{' (marginal)' if r.get('marginal') else ''}** | {_num(r.get('value'))} | "
           f"{r['detail']} |" for r in data["results"]]
    md += ["", "Cases:", ""] + [
        f"- **{c['name']}** ({_pairs(c['set'])}{'; ' if c['settings'] else ''}"
        f"{_pairs(c['settings'])}): {c['why']}" for c in data["cases"]]
    return md
