"""The diff report: a summary table (changed / unchanged / new / gone) first, the one-line
changes, then per case its runs and channels; `diff.json`; one plot per changed channel (old
and new overlaid above, their difference with the error band below)."""
from pathlib import Path

import numpy as np

from ..atomic import clean_json, write_json, write_text
from .report import plot_style, save_figure

MAX_PLOTS = 80           # a parameter change moves every channel: plot the worst ones


def _g(x, spec=".3g"):
    if x is None:
        return "—"
    if isinstance(x, float) and not np.isfinite(x):
        return "∞"
    return format(x, spec) if isinstance(x, (int, float)) else str(x)


def _safe(name):
    return "".join(ch if ch.isalnum() or ch in "-_." else "_" for ch in name)


def plot_channel(path, title, unit, t, x_old, x_new, delta, bound):
    plt = plot_style()
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(7, 5), sharex=True)
    u = f" [{unit}]" if unit else ""
    a1.plot(t, x_old, lw=1.6, label="old")
    a1.plot(t, x_new, lw=1, ls="--", label="new")
    a1.set_ylabel(f"value{u}")
    a1.legend(fontsize=8)
    a1.grid(alpha=0.3)
    a1.set_title(title, fontsize=9)
    fin = np.isfinite(delta)
    a2.fill_between(t, -bound, bound, color="0.8", label="error bars (both runs)")
    a2.plot(t[fin], delta[fin], lw=1, color="C3", label="new − old")
    a2.set_xlabel("t [s]")
    a2.set_ylabel(f"difference{u}")
    a2.legend(fontsize=8)
    a2.grid(alpha=0.3)
    fig.tight_layout()
    return save_figure(fig, path)


def write_diff_report(out_dir: Path, obj, arrays):
    out_dir = Path(out_dir)
    s = obj["summary"]
    md = ["# xval diff", "", f"- old: `{obj['old']}` ({obj['old_kind']})",
          f"- new: `{obj['new']}` ({obj['new_kind']})", "", f"Rule: {obj['rule']}.", "",
          "| runs (case × solver) | changed | unchanged | new | gone |", "|---|---|---|---|---|",
          f"| count | {s['changed']} | {s['unchanged']} | {s['new']} | {s['gone']} |", "",
          f"Channels: {s['channels_changed']} changed, {s['channels_unchanged']} unchanged; "
          f"cases new {s['cases_new']}, gone {s['cases_gone']}; verdicts flipped "
          f"{s['verdicts_flipped']}.", ""]
    md += (["## Changes", ""] + [f"- {ln}" for ln in obj["lines"]] if obj["lines"]
           else ["Nothing changed beyond the error bars."])
    if obj.get("notes"):
        md += ["", "Inputs that differ while the results stayed within their error bars:", ""]
        md += [f"- {ln}" for ln in obj["notes"]]
    worst = sorted(arrays, key=lambda k: -_ratio(obj, k))[:MAX_PLOTS]
    pngs = {}
    for case, solver, ch in worst:
        unit = _unit(obj, case, solver, ch)
        name = f"{_safe(case)}__{_safe(solver)}__{_safe(ch)}.png"
        pngs[(case, solver, ch)] = plot_channel(out_dir / name, f"{case} {solver} {ch}", unit,
                                                *arrays[(case, solver, ch)])
    for c in obj["cases"]:
        md += ["", f"## {c['case']} ({c['scene']}): {c['state']}", ""]
        if c.get("inputs"):
            md += [f"Parameters: {', '.join(c['inputs'])}.", ""]
        if not c["runs"]:
            continue
        md += ["| solver | channel | state | max abs Δ | at worst: Δ | error bars | Δ / bars "
               "| t [s] | note |", "|---|---|---|---|---|---|---|---|---|"]
        for r in c["runs"]:
            if r["state"] in ("new", "gone"):
                md.append(f"| {r['solver']} | | **{r['state']}** | | | | | | |")
                continue
            rows = r["channels"] if r["state"] == "changed" else []
            if r["state"] == "unchanged":
                big = max((ch.get("ratio", 0) for ch in r["channels"]), default=0)
                md.append(f"| {r['solver']} | all {len(r['channels'])} | unchanged | | | | "
                          f"≤ {_g(big, '.2g')} | | |")
            for ch in rows:
                u = f" {ch['unit']}" if ch.get("unit") else ""
                md.append(f"| {r['solver']} | {ch['channel']} | "
                          f"{'**changed**' if ch['state'] == 'changed' else 'unchanged'} | "
                          f"{_g(ch.get('max_abs'))}{u} | {_g(ch.get('delta'))} | "
                          f"{_g(ch.get('bound'), '.2g')} ({ch.get('error_bars', '')}) | "
                          f"{_g(ch.get('ratio'), '.3g')} | {_g(ch.get('t'), '.6g')} | "
                          f"{ch.get('note', '')}"
                          + (f" {_g(ch.get('old'))} → {_g(ch.get('new'))}"
                             if "old" in ch else "") + " |")
            if r.get("inputs"):
                md.append(f"| {r['solver']} | inputs | {', '.join(r['inputs'])} | | | | | | |")
        for f in c.get("verdicts_flipped", []):
            md.append(f"\nVerdict {f['a']}–{f['b']} {f['channel']}: {f['old']} → {f['new']}")
        for (case, solver, ch), png in pngs.items():
            if case == c["case"]:
                md += ["", f"![{solver} {ch}]({png})"]
    if obj["maps"]:
        md += ["", "## Maps", "", "| map | solver | state | crossing | old | new | bracket "
               "half-widths |", "|---|---|---|---|---|---|---|"]
        for m in obj["maps"]:
            for ch in m.get("channels") or [{}]:
                md.append(f"| {m['map']} | {m.get('solver', '')} | {m['state']} | "
                          f"{ch.get('channel', '')} | {_g(ch.get('old'))} | {_g(ch.get('new'))}"
                          f" | {_g(ch.get('bound'))} |")
    write_text(out_dir / "report.md", "\n".join(md) + "\n")
    obj["report"] = str(out_dir / "report.md")
    obj["plots"] = [str(out_dir / p) for p in pngs.values()]
    write_json(out_dir / "diff.json", clean_json(obj))
    return obj


def _ratio(obj, key):
    case, solver, ch = key
    for c in obj["cases"]:
        for r in c["runs"]:
            if c["case"] == case and r["solver"] == solver:
                for x in r["channels"]:
                    if x["channel"] == ch:
                        return x.get("ratio", 0)
    return 0


def _unit(obj, case, solver, ch):
    for c in obj["cases"]:
        for r in c["runs"]:
            if c["case"] == case and r["solver"] == solver:
                for x in r["channels"]:
                    if x["channel"] == ch:
                        return x.get("unit", "")
    return ""


def diff_table(obj):
    """The changes as a plain-text table (for a failing test's message)."""
    rows = [("case", "solver", "channel", "Δ at worst", "error bars", "Δ / bars", "t [s]")]
    for c in obj["cases"]:
        for r in c.get("runs", []):
            for ch in r.get("channels", []):
                if ch["state"] == "changed":
                    rows.append((c["case"], r["solver"], ch["channel"], _g(ch.get("delta")),
                                 _g(ch.get("bound"), ".2g"), _g(ch.get("ratio"), ".3g"),
                                 _g(ch.get("t"), ".6g")))
    widths = [max(len(str(row[i])) for row in rows) for i in range(len(rows[0]))]
    text = ["  ".join(str(v).ljust(w) for v, w in zip(row, widths)) for row in rows]
    return "\n".join(obj["lines"] + [""] + text)
