"""The tables every report and result prints — as text, Markdown and HTML — from one header
and rows of strings, and the one verdict table (run, modes, campaign, recording, assert_agree
all print it): deviation, error estimate, allowance, bound, ratio, verdict, decided by."""
from __future__ import annotations

import html
from dataclasses import fields

import numpy as np

from ..analysis.metrics import Comparison, ratio_text


def num(x, spec=".3g"):
    """A number as tables print it; "—" for none or a non-finite one."""
    if x is None or (isinstance(x, float) and not np.isfinite(x)):
        return "—"
    return format(x, spec)


def text(header, rows):
    cols = [header] + rows
    width = [max(len(str(r[i])) for r in cols) for i in range(len(header))]
    line = lambda r: "  ".join(str(v).ljust(w) for v, w in zip(r, width)).rstrip()
    return "\n".join([line(header), line(["-" * w for w in width])] + [line(r) for r in rows])


def markdown(header, rows):
    esc = lambda v: str(v).replace("|", "\\|")
    return "\n".join(["| " + " | ".join(map(esc, header)) + " |",
                      "|" + "---|" * len(header)]
                     + ["| " + " | ".join(map(esc, r)) + " |" for r in rows])


def html_table(header, rows):
    cell = lambda tag, v: f"<{tag}>{html.escape(str(v))}</{tag}>"
    return ("<table><thead><tr>" + "".join(cell("th", h) for h in header) + "</tr></thead>"
            "<tbody>" + "".join("<tr>" + "".join(cell("td", v) for v in r) + "</tr>"
                                for r in rows) + "</tbody></table>")


VERDICT_HEADER = ["a", "b", "channel", "max|Δ|", "error est.", "allowance", "bound",
                  "Δ/bound", "verdict", "decided by"]


def verdict_rows(comparisons) -> list[list[str]]:
    """One row per comparison (a `Comparison`, or its JSON dict from a stored result): the
    deviation against what explains it — both solvers' error estimates and the scene's
    allowance, whose sum is the bound — in SI units, the ratio, the verdict and what decided."""
    keys = {f.name for f in fields(Comparison)}
    cs = [c if isinstance(c, Comparison) else Comparison(**{k: v for k, v in c.items()
                                                            if k in keys})
          for c in comparisons]
    return [[c.a, c.b, c.channel, num(c.deviation), num(c.error_estimate),
             num(c.allowance), num(c.tolerance * c.scale), ratio_text(c.ratio), c.shown,
             c.decided_by] for c in cs]


def _g(x, fmt=".3g"):
    return "—" if x is None else format(x, fmt)


CALIBRATION_HEADER = ["scene", "samples", "comparisons", "disagree", "coverage", "sharpness",
                      "widest window", "skipped"]


def _widest_cell(d: dict) -> str:
    """The widest window, where it is, how the windows spread and the widest typical one."""
    at, w = d.get("widest_at") or {}, d.get("windows") or {}
    cell = _g(d["widest_window"])
    if at:
        cell += f" ({at['a']} vs {at['b']} {at['channel']}, set {at['sample']})"
    if w.get("opened"):
        cell += f"; {w['over_100']} of {w['opened']} > 100×, p95 {_g(w['p95'])}"
    if top := (w.get("typical") or {}).get("widest"):
        pair = top["pair"].replace("|", " vs ")
        cell += f"; typical {_g(top['median'])} ({pair} {top['channel']})"
    return cell


def calibration_summary(d: dict) -> str:
    """`xval calibrate`'s JSON in one line: comparisons, disagreements, stops, the error bars'
    coverage and sharpness, the widest window."""
    n = len(d["skipped"])
    skipped = f", {n} solver run{'s' * (n != 1)} skipped" if n else ""
    sweep = d.get("campbell")
    campbell = (f" (and the Campbell sweeps' {sweep['comparisons']} over {sweep['sets']} sets, "
                f"{sweep['unconfirmed']} critical speeds unconfirmed)" if sweep else "")
    return (f"{d['comparisons']} comparisons over {d['samples']} sets{campbell}, "
            f"{len(d['disagree'])} disagree{skipped}; coverage {_g(d['coverage'])}, sharpness "
            f"{_g(d['sharpness'], '.2g')}, widest window {_g(d['widest_window'])}")


def calibration_tables(d: dict) -> list:
    """`xval calibrate`'s JSON as its two tables: the scene's row, and one row per solver."""
    rows = [[d["scene"], str(d["samples"]), str(d["comparisons"]), str(len(d["disagree"])),
             _g(d["coverage"]), _g(d["sharpness"]), _widest_cell(d), str(len(d["skipped"]))]]
    per = [[s, str(o["pairs"]), str(o.get("unresolved", 0)), _g(o["coverage"]),
            _g(o["sharpness"]),
            "; ".join(f"{n}× {why}" for why, n in o["left_out"].items()) or "—"]
           for s, o in d.get("by_solver", {}).items()]
    return [(CALIBRATION_HEADER, rows),
            (["solver", "pairs", "at round-off", "coverage", "sharpness", "left out"], per)]
