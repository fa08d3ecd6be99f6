"""report.html beside report.md — for a run, a modes result, the other studies written by
study.py, and a campaign: a header (scene, parameters that differ from the defaults, solvers),
the verdict table (one row per comparison, sorted by clicking a header, filtered by a text box
and a verdict select), the counts of each verdict, interactive plotly figures of what the PNGs
show (html_figures.py), links to the rerun recordings, and report.md itself below (the page's
style, script and Markdown rendering: html_page.py).

Offline: no CDN. plotly.js is the file plotly.min.js beside each page, a hard link to the
installed plotly package's copy (or, across file systems, to one copy at the campaign's root),
so a campaign of ~40 case pages stores its 4.8 MB once; a plain copy only where no link can
be made. The page's own script is a few lines of vanilla JS.

Stable hooks for tests and scripts: table#verdict-table (tbody rows carry data-verdict),
#verdict-counts (span[data-verdict][data-count] per verdict, data-total on the element),
input#verdict-filter, select#verdict-select, #verdict-shown (the rows now visible),
div.xval-figure per figure."""
from __future__ import annotations

import html
import os
import shutil
from pathlib import Path

import numpy as np

from ..analysis.verdict import Verdict, agree_text
from ..atomic import atomic_path, write_text
from .html_figures import bound_figure, modes_figures, run_figures
from .html_page import PLOTLY_JS, markdown_html, page
from .tables import VERDICT_HEADER, verdict_rows

_esc = html.escape


# --- plotly.js beside the page ------------------------------------------------------------

def _plotly_source() -> Path:
    import plotly
    return Path(plotly.__file__).parent / "package_data" / PLOTLY_JS


def _link_or_copy(src: Path, dst: Path) -> None:
    try:
        os.link(src, dst)
    except FileExistsError:
        pass
    except OSError:
        with atomic_path(dst) as tmp:
            shutil.copyfile(src, tmp)


def place_plotly(folder: Path) -> Path:
    """plotly.min.js in `folder` (kept if there): linked to the package's file; across file
    systems linked to one copy at the nearest campaign root above (the folder holding jobs/),
    made there once."""
    dst = Path(folder) / PLOTLY_JS
    if dst.exists():
        return dst
    src = _plotly_source()
    try:
        os.link(src, dst)
        return dst
    except FileExistsError:
        return dst
    except OSError:
        pass
    root = next((a for a in list(Path(folder).resolve().parents)[:4]
                 if (a / "jobs").is_dir()), None)
    if root is not None:
        shared = root / PLOTLY_JS
        if not shared.exists():
            _link_or_copy(src, shared)
        src = shared
    _link_or_copy(src, dst)
    return dst


# --- pieces of a page ---------------------------------------------------------------------

def changed_params(scene, params: dict) -> str:
    """"name = value unit, …" of the parameters that differ from the scene's defaults."""
    from .report import fmt_value
    out = [f"{p.name} = {fmt_value(params[p.name])}{' ' + p.unit if p.unit else ''}"
           for p in scene.params if p.name in params
           and not np.array_equal(np.asarray(params[p.name]), np.asarray(p.default))]
    return ", ".join(out) or "defaults"


def _header(title, facts: list[tuple[str, str]]) -> str:
    rows = "".join(f"<tr><th>{_esc(k)}</th><td>{v}</td></tr>" for k, v in facts)
    return f"<h1>{_esc(title)}</h1><table class='facts'>{rows}</table>"


def _counts(verdicts: list[str]) -> str:
    n = Verdict.tally(verdicts)
    spans = "".join(f"<span class='count v-{v.name.lower()}' data-verdict='{_esc(v.value)}' "
                    f"data-count='{n[v]}'>{n[v]} {_esc(v.value)}</span>"
                    for v in Verdict.by_rank() if n[v])
    return (f"<p id='verdict-counts' data-total='{len(verdicts)}'>{_esc(agree_text(verdicts))}"
            f": {spans}</p>")


def verdict_table(comparisons: list[dict], case_of=None) -> str:
    """The verdict table (one <tr> per comparison; `case_of(c)`: a leading case column),
    its counts, the filter box and verdict select."""
    if not comparisons:
        return "<p id='verdict-counts' data-total='0'>No comparisons.</p>"
    head = (["case"] if case_of else []) + VERDICT_HEADER
    rows = verdict_rows(comparisons)
    body = []
    for c, r in zip(comparisons, rows):
        cells = ([case_of(c)] if case_of else []) + [_esc(str(v)) for v in r]
        body.append(f"<tr data-verdict='{_esc(str(c['verdict']))}'>"
                    + "".join(f"<td>{v}</td>" for v in cells) + "</tr>")
    present = [v for v in Verdict.by_rank() if any(c["verdict"] == v for c in comparisons)]
    options = "<option value=''>every verdict</option>" + "".join(
        f"<option value='{_esc(v.value)}'>{_esc(v.value)}</option>" for v in present)
    return (_counts([c["verdict"] for c in comparisons])
            + "<p class='controls'><input id='verdict-filter' type='search' "
              "placeholder='filter rows (solver, channel, …)'> "
              f"<select id='verdict-select'>{options}</select> "
              f"<span id='verdict-shown'>{len(rows)}</span> of {len(rows)} rows shown; "
              "click a column header to sort</p>"
            + "<div class='scroll vscroll'><table id='verdict-table'><thead><tr>"
            + "".join(f"<th data-col='{i}'>{_esc(h)}</th>" for i, h in enumerate(head))
            + "</tr></thead><tbody>" + "".join(body) + "</tbody></table></div>")


def _links(folder: Path, names) -> str:
    found = [n for n in names if (Path(folder) / n).exists()]
    if not found:
        return ""
    items = "".join(f"<li><a href='{_esc(n)}'>{_esc(n)}</a></li>" for n in found)
    return ("<h2>Recordings</h2><p>Open with the rerun viewer (<code>rerun FILE</code>).</p>"
            f"<ul id='recordings'>{items}</ul>")


def _write(folder: Path, title: str, parts: list[str], figures: list[dict]) -> Path:
    folder = Path(folder)
    place_plotly(folder)
    path = folder / "report.html"
    write_text(path, page(title, parts, figures, _report_md(folder)))
    return path


def _report_md(folder: Path) -> str:
    md = Path(folder) / "report.md"
    if not md.exists():
        return ""
    return ("<h2>Report</h2><p><a href='report.md'>report.md</a>, as written:</p>"
            + markdown_html(md.read_text()))


def _scene_facts(scene, params, solvers) -> list[tuple[str, str]]:
    return [("scene", f"<code>{_esc(scene.name)}</code> — {_esc(scene.title)}"),
            ("parameters", _esc(changed_params(scene, params))),
            ("solvers", _esc(", ".join(solvers) or "—"))]


# --- the writers' one call each -----------------------------------------------------------

def write_run_html(out_dir, result) -> Path:
    """report.html of a time run (the trajectories in memory), beside its report.md."""
    from .report import _flat, analytic_curve
    comps = [c.as_dict() for c in result.comparisons]
    parts = [_header(f"{result.scene.name}: {agree_text(c['verdict'] for c in comps)}",
                     _scene_facts(result.scene, result.params, result.solvers)),
             "<h2>Verdicts</h2>", verdict_table(comps),
             _links(out_dir, ["run.rrd"])]
    figs = run_figures(result, analytic_curve, _flat) + [bound_figure(comps)]
    return _write(out_dir, f"xval run {result.scene.name}", parts, figs)


_REQUIRED = {"a", "b", "channel", "max_abs", "rms", "max_rel", "scale", "tolerance", "verdict",
             "decided_by"}


def _is_comparison(c) -> bool:
    """A `Comparison.as_dict()`: what the verdict table shows (a study's other rows are not)."""
    return isinstance(c, dict) and _REQUIRED <= c.keys()


def write_study_html(out_dir, obj: dict) -> Path:
    """report.html of a study from its JSON (a modes result, bench, extremes, response, …)."""
    from ..scenes import get_scene
    rows = obj.get("comparisons")        # a calibration's is a count
    comps = [c for c in rows if _is_comparison(c)] if isinstance(rows, list) else []
    name = obj.get("scene")
    kind = obj.get("result") or "study"
    facts, unit = [], lambda p: ""
    if isinstance(name, str):
        try:
            sc = get_scene(name)
            unit = lambda p: next((q.unit for q in sc.params if q.name == p), "")
            facts = _scene_facts(sc, obj.get("params") or {},
                                 [r["solver"] for r in obj.get("runs", [])
                                  if isinstance(r, dict) and "solver" in r])
        except Exception:                 # a scene no longer registered: name it only
            facts = [("scene", f"<code>{_esc(name)}</code>")]
    summary = obj.get("summary")         # a study's line (a bench's is its table: a dict)
    title = f"{name or kind}: " + (summary if isinstance(summary, str) else
                                   agree_text(c["verdict"] for c in comps))
    parts = [_header(title, [("study", _esc(kind))] + facts)]
    if comps:
        parts += ["<h2>Verdicts</h2>", verdict_table(comps)]
    parts.append(_links(out_dir, ["campbell.rrd", "mode_shapes.rrd", "run.rrd", "map.rrd"]))
    figs = modes_figures(obj, unit) + [bound_figure(comps)]
    return _write(out_dir, f"xval {kind} {name or ''}", parts, figs)


def campaign_verdict_line(summary: dict) -> str:
    """The campaign's overall verdict: the worst of every comparison's, and `incomplete`
    where a case failed, a job crashed or nothing was compared (never `agree` then)."""
    verdicts = [x["verdict"] for c in summary.get("cases", []) for x in c.get("comparisons", [])]
    broken = (summary.get("n_failed") or summary.get("n_crashed")
              or any("error" in c for c in summary.get("cases", [])) or not verdicts)
    worst = Verdict.worst(verdicts, Verdict.INCOMPLETE)
    overall = Verdict.worst([worst, Verdict.INCOMPLETE]) if broken else worst
    return (f"overall: {overall} — {agree_text(verdicts)} in {len(summary.get('cases', []))} "
            f"cases; {summary.get('n_failed', 0)} cases with a failed solver, "
            f"{summary.get('n_crashed', 0)} crashed jobs")


def write_campaign_html(out_dir, summary: dict) -> Path:
    """The campaign's report.html: the overall verdict line, one row per case (its verdicts,
    links to its page and recording), the verdict table over every case's comparisons."""
    out_dir = Path(out_dir)
    cases = summary.get("cases", [])
    line = campaign_verdict_line(summary)
    rows = []
    for c in cases:
        name = c["case"]
        vs = [x["verdict"] for x in c.get("comparisons", [])]
        rec = next((f"{name}/{f}" for f in ("run.rrd", "campbell.rrd", "mode_shapes.rrd")
                    if (out_dir / name / f).exists()), None)
        bad = [f"{r['solver']} ({r['status']})" for r in c.get("runs", [])
               if r.get("status") != "ok"] + ([c["error"]] if "error" in c else [])
        page = (f"<a href='{_esc(name)}/report.html'>{_esc(name)}</a>"
                if (out_dir / name / "report.html").exists() else _esc(name))
        rows.append(f"<tr data-case='{_esc(name)}'><td>{page}</td>"
                    f"<td>{_esc(str(c.get('scene', '')))}</td>"
                    f"<td>{_esc(agree_text(vs))}</td><td>{_esc(', '.join(bad) or '—')}</td>"
                    f"<td>{_esc(str(Verdict.worst(vs, '—')))}</td><td>"
                    + (f"<a href='{_esc(rec)}'>{_esc(rec.rsplit('/', 1)[1])}</a>" if rec else "—")
                    + "</td></tr>")
    comps, label = [], {}
    for c in cases:
        for x in c.get("comparisons", []):
            if not _is_comparison(x):
                continue
            comps.append(x)
            label[id(x)] = c["case"]
    case_cell = lambda x: f"<a href='{_esc(label[id(x)])}/report.html'>{_esc(label[id(x)])}</a>"
    parts = [_header(f"Campaign {summary.get('name')}", [
                 ("verdict", f"<b id='campaign-verdict'>{_esc(line)}</b>"),
                 ("jobs", _esc(f"{summary.get('n_jobs')} ({summary.get('n_run')} run, "
                               f"{summary.get('n_reused')} reused), "
                               f"{summary.get('wall_s', 0):.1f} s")),
                 ("scenes", _esc(", ".join(dict.fromkeys(str(c.get("scene", ""))
                                                           for c in cases))))]),
             "<h2>Cases</h2><div class='scroll'><table id='case-table'><thead><tr><th>case</th>"
             "<th>scene</th><th>verdicts</th><th>failed</th><th>worst</th><th>recording</th>"
             "</tr></thead><tbody>" + "".join(rows) + "</tbody></table></div>",
             "<h2>Verdicts of every case</h2>", verdict_table(comps, case_cell)]
    fig = bound_figure(comps, lambda x: f"{label[id(x)]}: ")
    return _write(out_dir, f"xval campaign {summary.get('name')}", parts, [fig])
