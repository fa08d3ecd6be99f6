"""`xval diff OLD NEW`: which results moved between two campaign folders, run folders or
baselines, by how much against their own error bars, and what differs in their inputs.

For every case × solver × channel the largest change over the whole trajectory is weighed
against the error bars at each instant:

    bound(t) = e_old(t) + e_new(t) + recon_old(t) + recon_new(t) + FLOOR_REL × scale

e = the run's own error estimate (a tighter rerun; 0 where the run has none), recon = how far
a baseline's interpolation may be off (compare/results/baseline.py; 0 for a full
trajectory), scale = the channel's largest |value| on either side. `changed` when
|Δ(t)| > bound(t) anywhere.

Where a run has no error estimate (a scene or solver with error_estimate off, frequencies,
critical speeds, map boundaries) nothing excuses a change but round-off: FLOOR_REL = 1e-9 of
the channel's scale. Identical inputs rerun give bit-identical results here (the default
campaign run twice: every channel Δ = 0), so the floor only has to absorb a different
machine's last bits — ~1e-13 after 1e4 steps of 1e-16 rounding; 1e-9 leaves room for that and
stays 1e3 below the 1e-6 relative change a diff must catch. Frequencies and critical speeds
use FREQ_REL = 1e-8 (the critical speeds are located to 1e-9 relative, brentq). A map
boundary moved when its crossing moved by more than the two brackets' half-widths.

Verdicts that flipped, runs whose status changed, cases / solvers / map boundaries that
appeared or are gone count as changes. Exit status: 0 nothing changed, 1 changes, 2 bad input.
"""
from __future__ import annotations

import datetime
import os
import time
from pathlib import Path

import numpy as np

from ..errors import BadInput
from ..results import DiffResult, Result
from ..results.records import Series, Side

FLOOR_REL = 1e-9
FREQ_REL = 1e-8


# --- inputs ---------------------------------------------------------------------------------

def _fmt(v):
    from ..output.report import fmt_value
    return fmt_value(v, 10)


def _same(a, b):
    try:
        return np.array_equal(np.asarray(a), np.asarray(b))
    except (TypeError, ValueError):
        return a == b


def dict_changes(old, new, absent="absent"):
    return [f"{k} {_fmt(old[k]) if k in old else absent} → {_fmt(new[k]) if k in new else absent}"
            for k in sorted(set(old) | set(new), key=str)
            if not (k in old and k in new and _same(old[k], new[k]))]


def run_inputs(ro, rn):
    """What differs between two runs' inputs besides the case's parameters."""
    out = [f"{s} setting {x}" for s, x in [(rn.solver, c) for c in
                                           dict_changes(ro.settings, rn.settings)]]
    out += dict_changes(ro.versions, rn.versions, "not installed")
    if ro.code and rn.code and ro.code != rn.code:
        out.append(f"model code {ro.code[:10]} → {rn.code[:10]}")
    return out


# --- comparisons ------------------------------------------------------------------------------

def compare_series(so: Series, sn: Series):
    """Largest change of a channel against its error bars; the arrays for a plot."""
    ref, oth, flip = (sn, so, True) if so.recon is not None and sn.recon is None \
        else (so, sn, False)
    inside = (ref.t >= oth.t[0]) & (ref.t <= oth.t[-1])
    t = ref.t[inside]
    same = len(oth.t) == len(ref.t) and np.array_equal(oth.t, ref.t)

    def on_grid(s, arr):
        if arr is None:
            return np.zeros(len(t))
        arr = np.asarray(arr, float)
        if s is ref:
            return arr[inside]
        return arr if same else np.interp(t, s.t, arr)

    x_ref, x_oth = on_grid(ref, ref.x), on_grid(oth, oth.x)
    x_old, x_new = (x_oth, x_ref) if flip else (x_ref, x_oth)
    delta = x_new - x_old
    nan_o, nan_n = np.isnan(x_old), np.isnan(x_new)
    delta = np.where(nan_o & nan_n, 0.0, np.where(nan_o | nan_n, np.inf, delta))
    fin = np.abs(np.r_[x_old[~nan_o], x_new[~nan_n]])
    scale = float(fin.max()) if fin.size else 0.0
    bars = sum(np.abs(np.nan_to_num(on_grid(s, a), nan=0.0))
               for s in (ref, oth) for a in (s.err, s.recon))
    bound = bars + max(FLOOR_REL * scale, 1e-300)
    ratio = np.abs(delta) / bound
    if not len(t):
        return {"state": "changed", "note": "no overlap in time"}, None
    k = int(np.argmax(ratio))
    kmax = int(np.argmax(np.abs(delta)))
    res = {"state": "changed" if ratio[k] > 1 else "unchanged",
           "max_abs": float(np.abs(delta[kmax])), "t_max": float(t[kmax]),
           "max_rel": float(np.abs(delta[kmax]) / scale) if scale else None,
           "delta": float(delta[k]), "t": float(t[k]), "bound": float(bound[k]),
           "ratio": float(ratio[k]),
           "error_bars": "own estimates" if (so.err is not None and sn.err is not None)
           else "round-off floor" + (" + one side's estimate" if (so.err is not None
                                                                 or sn.err is not None) else "")}
    if not same:
        res["note"] = f"grids differ: compared on t ∈ [{t[0]:.6g}, {t[-1]:.6g}] s"
    return res, (t, x_old, x_new, delta, bound)


def _values(name, old, new, rel):
    """A scalar (frequency, critical speed) against the relative floor `rel`."""
    d = new - old
    bound = rel * max(abs(old), abs(new), 1e-300)
    r = abs(d) / bound if np.isfinite(d) else np.inf
    return {"channel": name, "state": "changed" if r > 1 else "unchanged", "max_abs": abs(d),
            "max_rel": abs(d) / abs(old) if old else None, "delta": d, "bound": bound,
            "ratio": r, "error_bars": "round-off floor", "old": old, "new": new}


def compare_modes(ro, rn, critical_o, critical_n):
    rows = []
    fo, fn = ro.frequencies or [], rn.frequencies or []
    if len(fo) != len(fn):
        rows.append({"channel": "number of modes", "state": "changed", "old": len(fo),
                     "new": len(fn), "ratio": np.inf})
    for i, (a, b) in enumerate(zip(fo, fn)):
        lo = (ro.labels or [""] * len(fo))[i]
        ln = (rn.labels or [""] * len(fn))[i]
        row = _values(f"mode {i + 1}" + (f" ({ln})" if ln else ""), a, b, FREQ_REL)
        row["unit"] = "Hz"
        if lo != ln:
            row.update(state="changed", note=f"label {lo!r} → {ln!r}")
        rows.append(row)
    for name in sorted(set(critical_o) | set(critical_n)):
        if name in critical_o and name in critical_n:
            rows.append(_values(f"critical speed {name}", critical_o[name], critical_n[name],
                                FREQ_REL))
        else:
            rows.append({"channel": f"critical speed {name}", "state": "changed",
                         "old": critical_o.get(name), "new": critical_n.get(name),
                         "ratio": np.inf, "note": "appeared" if name in critical_n else "gone"})
    return rows


def compare_maps(mo, mn):
    out = []
    for key in sorted(set(mo) | set(mn)):
        if key not in mo or key not in mn:
            out.append({"map": key, "state": "new" if key in mn else "gone"})
            continue
        bo, bn = mo[key]["boundaries"], mn[key]["boundaries"]
        for solver in sorted(set(bo) | set(bn)):
            a, b = bo.get(solver), bn.get(solver)
            if a is None or b is None:
                out.append({"map": key, "solver": solver, "state": "new" if a is None
                            else "gone"})
                continue
            rows = []
            if len(a) != len(b):
                rows.append({"channel": "number of crossings", "state": "changed",
                             "old": len(a), "new": len(b), "ratio": np.inf})
            for i, (x, y) in enumerate(zip(a, b)):
                half = sum(abs(s["bracket"][1] - s["bracket"][0]) / 2
                           for s in (x, y) if s.get("bracket"))
                d = float(y["x"]) - float(x["x"])
                bound = max(half, FREQ_REL * abs(float(x["x"])), 1e-300)
                moved = abs(d) > bound or (x.get("from"), x.get("to")) != (y.get("from"),
                                                                             y.get("to"))
                rows.append({"channel": f"crossing {i + 1} {y.get('from')}→{y.get('to')}"
                             + (f" at y={y['y']:.6g}" if y.get("y") is not None else ""),
                             "state": "changed" if moved else "unchanged",
                             "old": x["x"], "new": y["x"], "delta": d, "bound": bound,
                             "ratio": abs(d) / bound, "error_bars": "brackets"})
            out.append({"map": key, "solver": solver,
                        "state": "changed" if any(r["state"] == "changed" for r in rows)
                        else "unchanged", "channels": rows})
    return out


# --- the diff ---------------------------------------------------------------------------------

def pair_cases(old: Side, new: Side):
    """Case names of `old` → those of `new`; BadInput when the same name holds different
    scenes or nothing is in common."""
    common = [n for n in old.cases if n in new.cases]
    if not old.cases and not new.cases:               # two map folders: their boundaries
        if not set(old.maps) & set(new.maps):
            raise BadInput(f"different scenes: {old.path} maps {', '.join(old.maps)}, "
                           f"{new.path} maps {', '.join(new.maps)}")
        return {}
    if not common and len(old.cases) == 1 and len(new.cases) == 1:
        (a, ca), (b, cb) = next(iter(old.cases.items())), next(iter(new.cases.items()))
        if ca.scene != cb.scene:
            raise BadInput(f"different scenes: {old.path} is {ca.scene}, {new.path} is "
                           f"{cb.scene}")
        return {a: b}
    for n in common:
        if old.cases[n].scene != new.cases[n].scene:
            raise BadInput(f"case {n}: scene {old.cases[n].scene} in {old.path}, "
                           f"{new.cases[n].scene} in {new.path}: different scenes")
    if not common:
        raise BadInput(f"nothing in common: {old.path} has {', '.join(list(old.cases)[:4])}, "
                       f"{new.path} has {', '.join(list(new.cases)[:4])}")
    return {n: n for n in common}


def _unit(scene, ch):
    try:
        from ..output.report import channel_unit
        from ..scenes import get_scene
        return channel_unit(get_scene(scene), ch)
    except BadInput:
        return ""


def diff(old: Side, new: Side, keep_plots=True):
    """The diff as a dict (the JSON document) and the plot data of changed channels."""
    pairs = pair_cases(old, new)
    cases, plots = [], {}
    for name in old.cases:
        if name not in pairs:
            c = old.cases[name]
            cases.append({"case": name, "scene": c.scene, "state": "gone", "runs": []})
    for name_o, name_n in pairs.items():
        co, cn = old.cases[name_o], new.cases[name_n]
        case = {"case": name_n, "scene": cn.scene, "inputs": dict_changes(co.params, cn.params),
                "runs": [], "verdicts_flipped": []}
        for solver in list(co.runs) + [s for s in cn.runs if s not in co.runs]:
            ro, rn = co.runs.get(solver), cn.runs.get(solver)
            if ro is None or rn is None:
                case["runs"].append({"solver": solver, "state": "new" if ro is None else "gone",
                                     "channels": []})
                continue
            run = {"solver": solver, "status": [ro.status, rn.status],
                   "inputs": run_inputs(ro, rn), "channels": []}
            if ro.digest and ro.digest == rn.digest:
                run["same_inputs_digest"] = ro.digest[:16]
            if ro.status != rn.status:
                run["channels"].append({"channel": "status", "state": "changed",
                                        "old": ro.status, "new": rn.status, "ratio": np.inf,
                                        "note": rn.reason or ro.reason})
            elif ro.frequencies is not None and ro.status == "ok":   # a frequency case
                run["channels"] = compare_modes(ro, rn, co.critical.get(solver, {}),
                                                cn.critical.get(solver, {}))
            elif ro.status == "ok":
                so, sn = ro.series(), rn.series()
                for ch in list(so) + [c for c in sn if c not in so]:
                    if ch not in so or ch not in sn:
                        run["channels"].append({"channel": ch, "state": "changed",
                                                "note": "new channel" if ch in sn
                                                else "channel gone", "ratio": np.inf})
                        continue
                    res, arrays = compare_series(so[ch], sn[ch])
                    res = {"channel": ch, "unit": _unit(cn.scene, ch), **res}
                    run["channels"].append(res)
                    if res["state"] == "changed" and arrays is not None and keep_plots:
                        plots[(name_n, solver, ch)] = arrays
            run["state"] = "changed" if any(r["state"] == "changed" for r in run["channels"]) \
                else "unchanged"
            case["runs"].append(run)
        for key in sorted(set(co.verdicts) & set(cn.verdicts)):
            if co.verdicts[key] != cn.verdicts[key]:
                a, b, ch = key.split("~")
                case["verdicts_flipped"].append({"a": a, "b": b, "channel": ch,
                                                 "old": co.verdicts[key],
                                                 "new": cn.verdicts[key]})
        changed = any(r["state"] != "unchanged" for r in case["runs"]) \
            or case["verdicts_flipped"] or (co.error or None) != (cn.error or None)
        case["state"] = "changed" if changed else "unchanged"
        cases.append(case)
    for name, c in new.cases.items():
        if name not in pairs.values():
            cases.append({"case": name, "scene": c.scene, "state": "new", "runs": []})
    maps = compare_maps(old.maps, new.maps)
    units = [r for c in cases for r in c["runs"]] + maps
    summary = {s: sum(u["state"] == s for u in units)
               for s in ("changed", "unchanged", "new", "gone")}
    summary["cases_new"] = sum(c["state"] == "new" for c in cases)
    summary["cases_gone"] = sum(c["state"] == "gone" for c in cases)
    summary["verdicts_flipped"] = sum(len(c.get("verdicts_flipped", [])) for c in cases)
    chans = [ch for u in units for ch in u.get("channels", [])]
    summary["channels_changed"] = sum(ch["state"] == "changed" for ch in chans)
    summary["channels_unchanged"] = sum(ch["state"] == "unchanged" for ch in chans)
    obj = {"old": str(old.path), "new": str(new.path), "old_kind": old.kind,
           "new_kind": new.kind, "summary": summary,
           "any_change": any(c["state"] != "unchanged" for c in cases)
           or any(m["state"] != "unchanged" for m in maps),
           "rule": RULE, "cases": cases, "maps": maps}
    obj["lines"] = change_lines(obj)
    obj["notes"] = [f"{', '.join(c['inputs'] + r['inputs'])}: {c['case']} {r['solver']} "
                    f"unchanged within its error bars" for c in obj["cases"]
                    for r in c["runs"] if r["state"] == "unchanged"
                    and (c["inputs"] or r["inputs"])]
    return obj, plots


RULE = (f"changed when |new − old| exceeds, at some instant, the sum of both runs' own error "
        f"estimates, a baseline's interpolation tolerance and a round-off floor of "
        f"{FLOOR_REL:g} × the channel's largest |value|; frequencies and critical speeds "
        f"against {FREQ_REL:g} relative; map crossings against their brackets")


def _g(x, spec=".2g"):
    return "—" if x is None else (format(x, spec) if isinstance(x, float) else str(x))


def change_lines(obj):
    """One line per changed run (its worst channel) and per new / gone / flipped item."""
    lines = []
    for c in obj["cases"]:
        if c["state"] in ("new", "gone"):
            lines.append(f"{c['case']} ({c['scene']}): case {c['state']}")
            continue
        for r in c["runs"]:
            if r["state"] in ("new", "gone"):
                lines.append(f"{c['case']} {r['solver']}: solver {r['state']}")
            if r["state"] != "changed":
                continue
            moved = [ch for ch in r["channels"] if ch["state"] == "changed"]
            w = max(moved, key=lambda ch: ch.get("ratio", 0))
            why = ", ".join(c["inputs"] + r["inputs"]) or (
                "same inputs digest" if r.get("same_inputs_digest") else "no input differs")
            unit = f" {w['unit']}" if w.get("unit") else ""
            if "delta" in w and "bound" in w:
                what = (f"{w['channel']} moved {_g(w['delta'])}{unit} against error bars "
                        f"{_g(w['bound'])}")
            else:
                what = f"{w['channel']} {_g(w.get('old'), '.8g')} → {_g(w.get('new'), '.8g')}" + (
                    f" ({w['note']})" if w.get("note") else "")
            more = f" (+{len(moved) - 1} more channels)" if len(moved) > 1 else ""
            lines.append(f"{why}: {c['case']} {r['solver']} {what}{more}")
        for f in c.get("verdicts_flipped", []):
            lines.append(f"{c['case']}: verdict {f['a']}–{f['b']} {f['channel']} "
                         f"{f['old']} → {f['new']}")
    for m in obj["maps"]:
        where = f"map {m['map']}" + (f" {m['solver']}" if m.get("solver") else "")
        if m["state"] in ("new", "gone"):
            lines.append(f"{where}: {m['state']}")
        for ch in m.get("channels", []):
            if ch["state"] == "changed":
                lines.append(f"{where} {ch['channel']}: {_g(ch.get('old'), '.8g')} → "
                             f"{_g(ch.get('new'), '.8g')}" + (f" (moved {_g(ch['delta'])} against "
                                                       f"brackets {_g(ch['bound'])})"
                                                       if "delta" in ch else ""))
    return lines


def run_diff(old, new) -> DiffResult:
    """Diff two results (each a `Result`, or a path `Result.load` reads: a campaign, run or map
    folder, or a baseline), in memory; `.save(folder)` writes report.md, diff.json and the
    plots of the channels that moved."""
    t0 = time.perf_counter()
    old, new = (x if isinstance(x, Result) else Result.load(x) for x in (old, new))
    obj, plots = diff(old.side(), new.side())
    obj["wall_s"] = round(time.perf_counter() - t0, 3)
    return DiffResult(obj, plots=plots)


def new_diff_dir(root):
    """The default diff folder (no --out): ROOT/diff/<time>-<pid>, not made here."""
    stamp = datetime.datetime.now().strftime("%Y%m%d-%H%M%S")
    return Path(root) / "diff" / f"{stamp}-{os.getpid()}"


def check_baseline(result, baseline):
    """For tests: None when `result` (a `Result`, or a run or campaign folder) matches
    `baseline` within the error bars; else the diff table (text). A missing baseline file is
    written from the result and reported as such (the caller fails once: review and commit
    it)."""
    from ..output.diff_report import diff_table
    from .sides import save_baseline
    if not Path(baseline).exists():
        save_baseline(result, baseline)
        return None, f"baseline written to {baseline}: review and commit it"
    d = run_diff(baseline, result)
    return (diff_table(d.data) if d["any_change"] else None), None
