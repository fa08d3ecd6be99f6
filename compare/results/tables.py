"""The tables of results: the shared builders (compare/output/tables.py), the message of
`assert_agree`, and the Arrow/pandas views."""
from __future__ import annotations

from ..errors import BadInput
from ..output.tables import (  # noqa: F401  (the results' tables)
    VERDICT_HEADER,
    html_table,
    markdown,
    num,
    text,
    verdict_rows,
)


def disagreement_message(result, channels=None) -> str | None:
    """The verdict table of the comparisons on `channels` (default: all) that do not agree
    (disagree, inconclusive, or skipped because a solver failed), or None where
    `result.problems(channels)` finds nothing. A solver that failed, or a run with nothing
    compared, is never agreement: the message says so."""
    chosen = [c for c in result.comparisons if channels is None or c.channel in channels]
    if channels is not None:
        compared = list(dict.fromkeys(c.channel for c in result.comparisons))
        unknown = sorted(set(channels) - set(compared))
        if unknown:
            raise BadInput(f"channels: {', '.join(unknown)} not compared in this run "
                           f"(compared: {', '.join(compared)})")
    if not result.problems(channels):
        return None
    bad = [c for c in chosen if not c.verdict.agrees]
    missing = [f"{s} {r.status}" + (f" ({r.reason})" if r.reason else "")
               for s, r in result.runs.items() if r.status != "ok"]
    head = f"{len(bad)} of {len(chosen)} comparisons of {result.scene_name} do not agree"
    if missing:
        head += "; incomplete: " + ", ".join(missing)
    if not chosen:
        head += "; nothing was compared"
    return head + (":\n" + text(VERDICT_HEADER, verdict_rows(bad)) if bad else "")


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
