"""A map's verdicts: what each solver read where (`readings`), the solver pairs' boundaries
compared (`compare_boundaries`: matched crossings within resolution + error estimates +
half-brackets; an unmatched crossing judged against the other solver's own runs) and the map's
status (`verdict_status`, over `MAP_VERDICTS`)."""
from __future__ import annotations

import numpy as np

from ..analysis.verdict import Verdict
from .map_run import NONE


def readings(points, x_name, y_name, level=None):
    """Every run of the map as {solver: {row: [(x, label, status, reason)] sorted by x}}: what
    each solver read where, so a crossing without a counterpart can be judged against the other
    solver's own runs around it."""
    out = {}
    for p in points:
        if "regime" in p:
            label = p["regime"]
        else:
            v = p["value"]
            label = NONE if v is None else ("value" if level is None else
                                            "above" if v >= level else "below")
        row = p["params"].get(y_name) if y_name else None
        out.setdefault(p["solver"], {}).setdefault(row, []).append(
            (p["params"][x_name], label, p["status"], p.get("reason")))
    for rows in out.values():
        for r in rows.values():
            r.sort(key=lambda t: t[0])
    return out


def _failed(r):
    return f"{r[2]} at x = {r[0]:.6g}" + (f" ({r[3]})" if r[3] else "")


def _unmatched(c, a, b, seen):
    """A crossing of `a` with no crossing of the same regimes in `b` on its row: disagree
    (b's own runs around it read no such crossing), incomplete (a run on either side failed,
    or b ran nothing), or None (outside the region b mapped: not compared); with the line that
    says why."""
    what = f"{a}'s crossing {c['from']}→{c['to']} at x = {c['x']:.6g}{_row(c)}"
    if seen is None:                      # nothing known of the runs: b's rows are mapped
        return Verdict.DISAGREE, f"{what} has no counterpart in {b}"
    mine = [r for r in seen.get(a, {}).get(c["y"], []) if r[0] in c["bracket"] and r[2] != "ok"]
    if mine:
        return Verdict.INCOMPLETE, f"{what}: a failed run of {a}, no regime ({_failed(mine[0])})"
    if not seen.get(b):
        return Verdict.INCOMPLETE, f"{what}: {b} ran no points"
    rb = seen[b].get(c["y"], [])
    if not rb or not rb[0][0] <= c["x"] <= rb[-1][0]:
        return None, f"{what}: outside the region {b} mapped (not compared)"
    left = [r for r in rb if r[0] <= c["x"]][-1]
    right = next(r for r in rb if r[0] >= c["x"])
    bad = [r for r in (left, right) if r[2] != "ok"]
    if bad:
        return Verdict.INCOMPLETE, f"{what}: {b}'s run failed there ({_failed(bad[0])})"
    same = {r[1] for r in rb} == {left[1]}
    return Verdict.DISAGREE, (f"{what} has no counterpart in {b}: {b} reads {left[1]} at "
                   f"{left[0]:.6g} and {right[1]} at {right[0]:.6g}"
                   + (f" (and at all its {len(rb)} runs on the row, {rb[0][0]:.6g} to "
                      f"{rb[-1][0]:.6g})" if same else ""))


def _no_crossings(a, b, seen):
    """Neither solver finds a crossing: their regimes at the points both ran decide (None:
    nothing known of the runs)."""
    if seen is None:
        return None, "no crossing on a common row"
    for s in (a, b):
        if not seen.get(s):
            return Verdict.INCOMPLETE, f"{s} ran no points"
    ra = {(y, r[0]): r for y, rs in seen[a].items() for r in rs}
    common = [(ra[k], r) for y, rs in seen[b].items() for r in rs if (k := (y, r[0])) in ra]
    if not common:
        return (Verdict.INCOMPLETE,
                f"neither finds a crossing, and {a} and {b} ran no common point")
    for p, q in common:
        for s, r in ((a, p), (b, q)):
            if r[2] != "ok":
                return Verdict.INCOMPLETE, f"{s}'s run failed ({_failed(r)})"
    diff = [(p, q) for p, q in common if p[1] != q[1]]
    if diff:
        p, q = diff[0]
        return Verdict.DISAGREE, (f"neither finds a crossing, but at x = {p[0]:.6g} {a} reads "
                                  f"{p[1]} and {b} reads {q[1]} ({len(diff)} of {len(common)} "
                                  "common points differ)")
    labels = ", ".join(sorted({p[1] for p, _ in common}))
    return Verdict.AGREE, (f"neither finds a crossing; both read {labels} at all "
                           f"{len(common)} common points")


def compare_boundaries(boundaries, width, seen=None):
    """Per solver pair: each crossing of the first matched to the nearest of the second on the
    same row with the same regimes; `agree` when every matched distance is within
    width + both error estimates + both half-brackets; `unconfirmed` where a crossing within
    that vanishes at its solver's tighter setting (it has no error bar). A crossing of either
    with no counterpart is judged against the other's own runs around it (`seen`, from
    `readings`): `disagree` where they read no such crossing, `incomplete` where a run there
    failed or the other ran nothing; where neither finds a crossing, their regimes at the
    points both ran decide. Never silently dropped: every such crossing is in `why` and in
    `unmatched`. Worst first: disagree, incomplete, unconfirmed, agree; `no data` only where
    nothing could be compared (crossings outside the region the other mapped)."""
    names = list(boundaries)
    out = []
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            pairs, lines, unmatched, matched = [], [], [], 0
            for one, other in ((a, b), (b, a)):
                for ca in boundaries[one]:
                    cands = [cb for cb in boundaries[other] if cb["y"] == ca["y"]
                             and cb["from"] == ca["from"] and cb["to"] == ca["to"]]
                    if not cands:
                        got, line = _unmatched(ca, one, other, seen)
                        if got is not None:
                            pairs.append(got)
                        lines.append(line)
                        unmatched.append({"solver": one, "x": ca["x"], "y": ca["y"],
                                          "outcome": got or "outside"})
                        continue
                    if one == b:          # matched from a's side already
                        continue
                    matched += 1
                    cb = min(cands, key=lambda c: abs(c["x"] - ca["x"]))
                    d = abs(cb["x"] - ca["x"])
                    bound = (width + (ca.get("error") or 0) + (cb.get("error") or 0)
                             + 0.5 * (np.ptp(ca["bracket"]) + np.ptp(cb["bracket"])))
                    got = Verdict.AGREE if d <= bound * (1 + 1e-9) else Verdict.DISAGREE
                    if got == Verdict.AGREE and (ca.get("unconfirmed")
                                                 or cb.get("unconfirmed")):
                        got = Verdict.UNCONFIRMED
                        gone = ca if ca.get("unconfirmed") else cb
                        lines.append(f"{ca['from']}→{ca['to']}{_row(ca)}: unconfirmed — "
                                     f"{a if gone is ca else b}'s " + gone.get(
                                         "unconfirmed_why",
                                         "crossing vanishes at its tighter setting"))
                    pairs.append(got)
                    if got == Verdict.DISAGREE:
                        lines.append(f"{ca['from']}→{ca['to']}{_row(ca)}: {a} at "
                                     f"{ca['x']:.6g} {_bracket(ca)}, {b} at {cb['x']:.6g} "
                                     f"{_bracket(cb)}: {d:.3g} apart > {bound:.3g} "
                                     "(resolution + error estimates + half-brackets)")
            if not boundaries[a] and not boundaries[b]:
                got, line = _no_crossings(a, b, seen)
                if got is not None:
                    pairs.append(got)
                lines.append(line)
            verdict = Verdict.worst(pairs, default=Verdict.NO_DATA)
            why = lines or ([f"all {matched} crossings within resolution + error "
                             "estimates + half-brackets"] if pairs else ["nothing compared"])
            out.append({"a": a, "b": b, "verdict": verdict, "matched": matched, "why": why,
                        "unmatched": unmatched})
    return out


# what a map's pair can be, worst first (the status counts each)
MAP_VERDICTS = (Verdict.DISAGREE, Verdict.INCOMPLETE, Verdict.UNCONFIRMED, Verdict.NO_DATA,
                Verdict.AGREE)


def verdict_status(verdicts):
    """The map's status for a CI: counts per verdict, and the worst verdict over its pairs
    (`no comparison` for a map of one solver)."""
    n = Verdict.tally(x["verdict"] for x in verdicts)
    worst = Verdict.worst((x["verdict"] for x in verdicts), default="no comparison")
    return {"status": worst, "pairs": len(verdicts), **{v: n[v] for v in MAP_VERDICTS}}


def _row(c):
    return "" if c["y"] is None else f" (row {c['y']:.6g})"


def _bracket(c):
    e = c.get("error")
    return f"[{c['bracket'][0]:.6g}, {c['bracket'][1]:.6g}]" + (f" ± {e:.2g}" if e else "")
