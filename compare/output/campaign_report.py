"""The campaign report a reviewer reads: per case the comparisons with their deviation and
tolerance, the findings with their numbers, the engine messages, links to the case reports;
per swept case a plot of the key channel's final value against the swept parameter."""
from pathlib import Path

import numpy as np

from ..analysis.verdict import Verdict
from ..atomic import write_json, write_text
from .citations import papers_in
from .joblog import distinct_lines
from .map_plot import markdown as map_markdown
from .report import fmt_value, plot_style
from .tables import CALIBRATION_HEADER, VERDICT_HEADER, calibration_tables, markdown, verdict_rows


def _num(x, spec=".3g"):
    if x is None or (isinstance(x, float) and not np.isfinite(x)):
        return "—"
    return format(x, spec)


def _changed(case):
    out = []
    for p in case.scene.params:
        v, d = case.params[p.name], p.default
        if not np.array_equal(np.asarray(v), np.asarray(d)):
            out.append(f"{p.name} = {fmt_value(v)}{' ' + p.unit if p.unit else ''}")
    return ", ".join(out) or "defaults"


def _verdicts(obj):
    n = Verdict.tally(c["verdict"] for c in obj.get("comparisons", []))
    return f"{n[Verdict.AGREE]} agree, {n[Verdict.DISAGREE]} disagree" + "".join(
        f", {n[k]} {k}" for k in (Verdict.INCONCLUSIVE, Verdict.SKIPPED) if n[k])


def _worst(obj):
    """The comparison closest to (or furthest over) its tolerance."""
    cs = [c for c in obj.get("comparisons", []) if c.get("verdict") != Verdict.SKIPPED
          and c.get("max_rel") is not None and c.get("tolerance")]
    return max(cs, key=lambda c: c["max_rel"] / c["tolerance"]) if cs else None


def _worst_power(obj):
    """The case's least visible (parameter, solver) and its ε*, and the parameters it does
    not verify in some solver; — where the case measured no power."""
    rows = obj.get("power")
    if rows is None:
        return "—"
    found = [r for r in rows if r["epsilon"] is not None]
    blind = sorted({r["parameter"] for r in rows if r["epsilon"] is None})
    text = (f"{max(r['epsilon'] for r in found):.1g} "
            f"(`{max(found, key=lambda r: r['epsilon'])['parameter']}`)" if found
            else "none")
    return text + (f"; not verified: {', '.join(blind)}" if blind else "")


def _comparison_rows(obj, full_up_to=12):
    """Every comparison when there are few; else one row per channel with its worst pair
    (closest to or furthest over the tolerance) and the verdict counts (the case report has
    every pair)."""
    cs = obj.get("comparisons", [])
    if len(cs) <= full_up_to:
        return markdown(VERDICT_HEADER, verdict_rows(cs)).splitlines()
    rows = []
    for ch in dict.fromkeys(c["channel"] for c in cs):
        mine = [c for c in cs if c["channel"] == ch]
        w = _worst({"comparisons": mine}) or mine[0]
        rows.append(verdict_rows([w])[0][:-2] + [_verdicts({"comparisons": mine})])
    # the verdict table's columns for each channel's worst pair, and the verdicts of all pairs
    return markdown(VERDICT_HEADER[:-2] + ["verdicts of all pairs"], rows).splitlines()


def _run_rows(case, obj):
    key = case.scene.key_channel
    rows = [f"| solver | status | wall [s] | final {key} | energy residual [J] |"
            if key else "| solver | status | wall [s] | frequencies [Hz] |",
            "|---|---|---|---|---|" if key else "|---|---|---|---|"]
    for r in obj.get("runs", []):
        st = r["status"] + (f" at t = {_num(r.get('t_fail'), '.4g')} s: {r.get('reason')}"
                            if r["status"] != "ok" and r.get("reason") else "")
        if key:
            fin = (r.get("final") or {}).get(key)
            rows.append(f"| {r['solver']} | {st} | {_num(r.get('wall_s'))} | "
                        f"{_num(fin, '.8g')} | {_num(r.get('energy_residual'), '.2e')} |")
        else:
            rows.append(f"| {r['solver']} | {st} | {_num(r.get('wall_s'))} | "
                        + ", ".join(_num(f, ".8g") for f in r.get("frequencies_hz", [])) + " |")
    return rows


def _messages(case, jobs, out_dir):
    lines = []
    for j in jobs:
        if j.case != case.name:
            continue
        log = out_dir / "jobs" / f"{j.key}.log"
        text = log.read_text(errors="replace") if log.exists() else ""
        lines += [f"    {j.solver or 'modes'}: {ln}" for ln in distinct_lines(text, 8)]
    return lines


def sweep_plot(parent, points, outcome, path):
    """Final value of the key channel against the first swept parameter, one line per solver
    (and per value of any further swept parameter)."""
    plt = plot_style()
    sc = points[0].scene
    key, names = sc.key_channel, list(points[0].point)
    x_name = names[0]
    unit = sc.param(x_name).unit
    fig, ax = plt.subplots(figsize=(7, 4.2))
    series = {}
    for c in points:
        rest = ", ".join(f"{k}={fmt_value(c.point[k])}" for k in names[1:])
        for r in outcome.get(c.name, {}).get("runs", []):
            v = (r.get("final") or {}).get(key) if r["status"] == "ok" else None
            series.setdefault((r["solver"], rest), []).append(
                (float(c.point[x_name]), np.nan if v is None else v))
    markers = "osD^vx+*"
    for i, ((solver, rest), pts) in enumerate(series.items()):
        x, y = zip(*sorted(pts))
        ax.plot(x, y, marker=markers[i % len(markers)], ms=5, lw=1, mfc="none",
                label=solver + (f" ({rest})" if rest else ""))
    from .report import channel_label
    ax.set_xlabel(f"{x_name} [{unit}]" if unit else x_name)
    ax.set_ylabel(f"final {channel_label(sc, key)}")
    ax.set_title(f"{parent}: final {key} over the sweep")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    from .report import save_figure
    return save_figure(fig, path)


def write_campaign_report(camp, cases, jobs, outcome, out_dir, reused, crashed, wall_s,
                          maps=(), calibrations=()):
    out_dir = Path(out_dir)
    name = camp.get("name")
    n_failed = sum(any(r["status"] != "ok" for r in outcome.get(c.name, {}).get("runs", []))
                   or "error" in outcome.get(c.name, {}) for c in cases)
    # "result": the type `Result.load` reads it as (compare/results/studies.py)
    summary = {"result": "campaign", "name": name, "n_jobs": len(jobs),
               "n_skipped": len(reused),
               "n_reused": len(reused), "n_run": len(jobs) - len(reused),
               "n_failed": n_failed, "n_crashed": len(crashed), "wall_s": round(wall_s, 3),
               "reused": sorted(reused), "crashed": crashed, "cases": []}
    refs = list(dict.fromkeys(r for c in cases for r in (papers_in(c.scene.source)
                                                         or [c.scene.source])))
    md = [f"# Campaign `{name}`", "",
          f"{len(jobs)} jobs in {len(cases)} cases: {len(jobs) - len(reused)} run now, "
          f"{len(reused)} reused from an earlier run (same inputs digest: scene, parameters, "
          f"solver, settings, package versions, model code), {len(crashed)} crashed; "
          f"{wall_s:.1f} s.", "", "Sources:", ""] + [f"- {r}" for r in refs]
    md += ["", "## Overview", "",
           "Worst ε*: the largest of the smallest relative changes of one physical parameter "
           "in one solver that the case's verdicts detect (estimated from one solver's "
           "sensitivities; `xval power` confirms with runs) — what the case's `agree` is "
           "worth.", "",
           "| case | scene | solvers ok | failed | verdicts | worst deviation / tolerance | "
           "worst ε* | report |", "|---|---|---|---|---|---|---|---|"]
    sweeps = {}
    for c in cases:
        obj = outcome.get(c.name, {"runs": [], "comparisons": [], "error": "not finished"})
        ok = [r["solver"] for r in obj.get("runs", []) if r["status"] == "ok"]
        bad = [f"{r['solver']} ({r['status']})" for r in obj.get("runs", [])
               if r["status"] != "ok"] + ([obj["error"]] if "error" in obj else [])
        w = _worst(obj)
        worst = (f"{w['channel']} {w['a']}–{w['b']}: {_num(w['max_rel'], '.1e')} / "
                 f"{_num(w['tolerance'], '.0e')}" if w else "—")
        md.append(f"| {c.name} | {c.scene.name} | {', '.join(ok) or '—'} | "
                  f"{', '.join(bad) or '—'} | {_verdicts(obj)} | {worst} | "
                  f"{_worst_power(obj)} | [report]({c.name}/report.md) |")
        mine_reused = sorted(j.solver or "modes" for j in jobs
                             if j.case == c.name and j.label in reused)
        summary["cases"].append({"case": c.name, "sweep": c.sweep_parent,
                                 "point": c.point, "reused": mine_reused, **obj})
        if c.sweep_parent:
            sweeps.setdefault(c.sweep_parent, []).append(c)
    for c in cases:
        if c.sweep_parent:
            continue
        obj = outcome.get(c.name, {})
        md += ["", f"## {c.name}", "", f"Scene `{c.scene.name}` ({c.scene.title}); "
               f"parameters: {_changed(c)}. [Case report]({c.name}/report.md)", ""]
        md += _run_rows(c, obj)
        if obj.get("comparisons"):
            md += ["", "Agreement (max |Δ| relative to the channel's scale, against the "
                   "scene's tolerance; every pair in the case report):", ""]
            md += _comparison_rows(obj)
        md += _findings(obj)
        if "power_summary" in obj:
            md += ["", f"Detection power: {obj['power_summary']} (table in the case report)."]
        md += _reuse_and_messages(c, jobs, reused, out_dir)
    for parent, points in sweeps.items():
        png = sweep_plot(parent, points, outcome, out_dir / parent / "sweep.png")
        sc = points[0].scene
        key = sc.key_channel
        solvers_ = list(dict.fromkeys(r["solver"] for p in points
                                      for r in outcome.get(p.name, {}).get("runs", [])))
        md += ["", f"## Sweep {parent}", "",
               f"Scene `{sc.name}`; swept: {', '.join(points[0].point)}; fixed: "
               f"{_changed_fixed(points)}.", "", f"![sweep]({parent}/{png})", "",
               "| point | " + " | ".join(f"{s} final {key}" for s in solvers_)
               + " | verdicts | worst deviation / tolerance | report |",
               "|---|" + "---|" * (len(solvers_) + 3)]
        for p in points:
            obj = outcome.get(p.name, {})
            fin = {r["solver"]: ((r.get("final") or {}).get(key) if r["status"] == "ok"
                                 else r["status"]) for r in obj.get("runs", [])}
            w = _worst(obj)
            md.append(f"| {p.name.split('/', 1)[1]} | "
                      + " | ".join(_num(fin.get(s), ".8g") if not isinstance(fin.get(s), str)
                                   else fin[s] for s in solvers_)
                      + f" | {_verdicts(obj)} | "
                      + (f"{w['channel']} {_num(w['max_rel'], '.1e')} / "
                         f"{_num(w['tolerance'], '.0e')}" if w else "—")
                      + f" | [report]({p.name}/report.md) |")
        md += _findings_table(points, outcome)
        for p in points:
            md += _reuse_and_messages(p, jobs, reused, out_dir)
    summary["maps"] = []
    for m in maps:                       # the campaign's maps: each folder has its own files
        rel = Path(m["folder"]).relative_to(out_dir)
        md += ["", *[line.replace("](map.png)", f"]({rel}/map.png)")
                     for line in map_markdown(m)]]
        summary["maps"].append({"map": m["name"], "scene": m["scene"], "folder": str(rel),
                                "runs": m["runs"], "reused": m["reused"],
                                "boundaries": m["boundaries"], "verdicts": m["verdicts"],
                                "status": m.get("status")})
    summary["calibration"] = list(calibrations)
    md += _calibration_section(calibrations)
    report = out_dir / "report.md"
    write_text(report, "\n".join(md) + "\n")
    summary["report"] = str(report)
    from .html_report import write_campaign_html
    write_campaign_html(out_dir, summary)        # report.html beside report.md
    write_json(out_dir / "summary.json", summary)
    return summary


def _calibration_section(calibrations):
    """The verdicts' false-alarm rate: each scene's `xval calibrate` over sets drawn off the
    defaults (the detection power, the other rate, is each case's worst ε*)."""
    if not calibrations:
        return []
    rows = []
    for c in calibrations:
        rows += ([[c["scene"], str(c["samples"]), f"not measured: {c['error']}"] + ["—"] * 5]
                 if "error" in c else calibration_tables(c)[0][1])
    return ["", "## Calibration", "",
            "False alarms over parameter sets drawn off the defaults (`xval calibrate SCENE "
            "--samples N`): comparisons, those that disagree (none expected: the solvers are "
            "correct), the error bars' coverage (true error ≤ estimate) and sharpness (median "
            "true / estimate), the widest window (bound / deviation).", "",
            *markdown(CALIBRATION_HEADER, rows).splitlines()]


def _findings_table(points, outcome):
    """The findings' numbers (first solver's value, as the scene states them) per point in
    one table; the sentences with every solver's number in a collapsible list."""
    names = list(dict.fromkeys(f["name"] for p in points
                               for f in outcome.get(p.name, {}).get("findings", [])
                               if isinstance(f.get("value"), (int, float))))
    if not names:
        return []
    units = {f["name"]: f.get("unit") for p in points
             for f in outcome.get(p.name, {}).get("findings", [])}
    md = ["", "Findings per point (the number of the first solver; the sentences below give "
          "every solver's):", "",
          "| point | " + " | ".join(n + (f" [{units[n]}]" if units.get(n) else "")
                                   for n in names) + " |",
          "|---|" + "---|" * len(names)]
    for p in points:
        vals = {f["name"]: f.get("value") for f in outcome.get(p.name, {}).get("findings", [])}
        md.append(f"| {p.name.split('/', 1)[1]} | "
                  + " | ".join(_num(vals.get(n), ".6g") for n in names) + " |")
    md += ["", "<details><summary>Findings as sentences</summary>", ""]
    for p in points:
        for f in outcome.get(p.name, {}).get("findings", []):
            md.append(f"- **{p.name.split('/', 1)[1]}** {f['text']}")
    return md + ["", "</details>"]


def _changed_fixed(points):
    c = points[0]
    swept = set(c.point)
    out = [x for x in _changed(c).split(", ") if x.split(" = ")[0] not in swept]
    return ", ".join(out) or "defaults"


def _findings(obj):
    fs = obj.get("findings", [])
    if not fs:
        return []
    return ["", "Findings:", ""] + [f"- {f['text']}" for f in fs]


def _reuse_and_messages(case, jobs, reused, out_dir):
    out = []
    mine = [j for j in jobs if j.case == case.name and j.label in reused]
    if mine:
        out += ["", f"Reused stored results for {case.name}: "
                + ", ".join(f"{j.solver or 'modes'} (inputs {j.digest[:12]})" for j in mine)
                + "."]
    msgs = _messages(case, jobs, out_dir)
    if msgs:
        out += ["", f"<details><summary>Engine messages of {case.name} "
                f"({len(msgs)} distinct line{'s' if len(msgs) != 1 else ''})</summary>", "", "```"]
        out += [m.strip() for m in msgs] + ["```", "", "</details>"]
    return out
