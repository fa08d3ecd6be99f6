"""The tables every result prints — as text (`str`), Markdown and HTML (Jupyter) — from one
header and rows of strings; the verdict table shared by run and modes results."""
from __future__ import annotations

import html

import numpy as np

from ..analysis.metrics import Comparison, ratio_text
from ..errors import BadInput


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


VERDICT_HEADER = ["a", "b", "channel", "max|Δ|", "error est.", "allowance", "max rel",
                  "Δ/bound", "verdict"]


def verdict_rows(comparisons: list[Comparison]) -> list[list[str]]:
    """One row per comparison: the deviation against what explains it (both solvers' error
    estimates, the scene's allowance), in SI units, and the verdict."""
    return [[c.a, c.b, c.channel, num(c.deviation), num(c.error_estimate),
             num(c.allowance), num(c.max_rel, ".2e"), ratio_text(c.ratio), c.shown]
            for c in comparisons]


def disagreement_message(result, channels=None) -> str | None:
    """The verdict table of the comparisons on `channels` (default: all) that do not agree
    (disagree, or skipped because a solver failed), or None when every one agrees. A solver
    that failed, or a run with nothing compared, is never agreement: the message says so."""
    chosen = [c for c in result.comparisons if channels is None or c.channel in channels]
    if channels is not None:
        compared = list(dict.fromkeys(c.channel for c in result.comparisons))
        unknown = sorted(set(channels) - set(compared))
        if unknown:
            raise BadInput(f"channels: {', '.join(unknown)} not compared in this run "
                           f"(compared: {', '.join(compared)})")
    bad = [c for c in chosen if c.verdict != "agree"]
    missing = [f"{s} {r.status}" + (f" ({r.reason})" if r.reason else "")
               for s, r in result.runs.items() if r.status != "ok"]
    if not bad and not missing and chosen:
        return None
    head = f"{len(bad)} of {len(chosen)} comparisons of {result.scene_name} do not agree"
    if missing:
        head += "; incomplete: " + ", ".join(missing)
    if not chosen:
        head += "; nothing was compared"
    rows = [r + [c.decided_by] for r, c in zip(verdict_rows(bad), bad)]
    return head + (":\n" + text(VERDICT_HEADER + ["decided by"], rows) if bad else "")


def arrow_rows(rows: list[dict]):
    import pyarrow as pa
    return pa.Table.from_pylist(rows)


def pandas(table):
    try:
        import pandas  # noqa: F401
    except ImportError:
        raise ImportError("to_pandas() needs pandas, an optional extra: pip install "
                          "'xval[pandas]' (or use to_arrow())") from None
    return table.to_pandas()
