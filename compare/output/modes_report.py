"""The Markdown of `xval modes`' report.md, composed from the data a modes result holds (the
workflows return data only): the head (title, header, each solver's frequencies, damped modes,
growing modes, the verdict table, modes left unpaired), the Campbell diagram, the threshold
speed and the identification. The scene's own hooks (explanations, identification) hand back
their lines, carried here as they are. Duck-typed: nothing here imports a Result."""
from __future__ import annotations

import math

import numpy as np

from ..analysis.verdict import Verdict, agree_text
from ..physics.whirl import shown_label
from .report import header_lines
from .tables import VERDICT_HEADER, markdown, verdict_rows

DAMPED_HEADER = ["solver", "mode", "whirl", "f_d [Hz]", "ω_d [rad/s]", "ω_d [rpm]", "ζ",
                 "log dec"]


def log_dec(zeta):
    """The logarithmic decrement δ = 2πζ/√(1 − ζ²) (inf for ζ ≥ 1: no oscillation)."""
    z = np.asarray(zeta, float)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(z < 1, 2 * np.pi * z / np.sqrt(np.maximum(1 - z * z, 0.0)), np.inf)


def damped_rows(results) -> list[list[str]]:
    """One row per mode of every solver that gives damping ratios (DAMPED_HEADER): Hz, rad/s
    and rpm side by side, ζ and log dec (ROSS's conventions)."""
    rows = []
    for m in results:
        if m.status != "ok" or m.damping is None:
            continue
        whirl = m.whirl or ["—"] * len(m.labels)
        for f, lb, wh, z, d in zip(m.frequencies_hz, m.labels, whirl, m.damping,
                                   log_dec(m.damping)):
            rows.append([m.solver, shown_label(lb, wh), wh, f"{f:.10g}", f"{2 * np.pi * f:.10g}",
                         f"{60 * f:.8g}", f"{z + 0.0:.8g}", f"{d + 0.0:.6g}"])   # no −0
    return rows


def head(scene, params, results, comparisons, growing, unpaired) -> list[str]:
    """Title, header, one row per solver (frequencies, labels, notes), the damped modes where
    a solver gives ζ, the growing modes (`growing`: solver, mode, growth_per_s, zeta), the
    verdict table of the mode-by-mode `comparisons`, the modes left unpaired."""
    md = [f"# {scene.name}: {scene.title}", "", *header_lines(scene, params),
          "| solver | status | frequencies [Hz] | labels | notes |", "|---|---|---|---|---|"]
    md += [f"| {r.solver} | {r.status} | {', '.join(f'{f:.8g}' for f in r.frequencies_hz)} | "
           f"{', '.join(map(shown_label, r.labels, r.whirl or [None] * len(r.labels)))} | "
           f"{'; '.join(r.notes) or r.reason or ''} |" for r in results]
    if any(r.damping is not None for r in results):
        md += ["", "Damped modes (ζ: damping ratio, log dec δ = 2πζ/√(1 − ζ²); whirl about the "
               "spin as ROSS names it):", "",
               *markdown(DAMPED_HEADER, damped_rows(results)).splitlines()]
    if growing:
        md += ["", "**unstable**: " + "; ".join(
            f"{g['solver']} {g['mode']} grows at {g['growth_per_s']:.6g} /s (ζ = {g['zeta']:.3g})"
            for g in growing)]
    md += ["", *markdown(VERDICT_HEADER, verdict_rows(comparisons)).splitlines()]
    if unpaired:
        md += ["", "Modes left unpaired (not compared):", "",
               "| a | b | solver | mode | frequency [Hz] | why |", "|---|---|---|---|---|---|"]
        md += [f"| {u['a']} | {u['b']} | {u['solver']} | {u['mode']} | "
               f"{u['frequency_hz']:.8g} | {u['reason']} |" for u in unpaired]
    return md


def campbell_section(cb, obj: dict, told: dict) -> list[str]:
    """"## Campbell diagram": the sampling, the events, the critical speeds, the growing
    roots, what stayed unconfirmed or missing, and the sweep's verdicts. `obj`: the diagram's
    JSON; `told`: what the JSON does not hold — `floor` (the scene's ζ allowance), `frame`
    (the figure's), `sweep` and `renamed` (the sweep's Comparisons, judged and not)."""
    from ..analysis.campbell import MAC_KEEP  # scipy and rerun: only where one is drawn
    from .campbell_plot import critical_table
    grid, frame, floor = obj["values"], told["frame"], told["floor"]
    sweep, renamed = told["sweep"], told["renamed"]
    onsets = obj["growing_from"]
    md = ["", "## Campbell diagram", "",
          f"{len(grid)} values of {cb.parameter} ({obj['grid_points']} on the scene's grid, "
          f"{len(grid) - obj['grid_points']} added where lines come close, swap or lose their "
          f"shape); the solvers report their lines in the {cb.frame} frame"
          + (f", the figure shows them in the {frame} frame" if frame != cb.frame else "")
          + ".", "Lines continue where consecutive mode shapes correlate (MAC ≥ "
          f"{MAC_KEEP}); least MAC on a line outside a marked veering: "
          + ", ".join(f"{s} {v:.3f}" for s, v in obj["min_mac_unmarked"].items()) + ".", ""]
    md += [f"- {s} {e['kind']}: {' / '.join(e['lines'])} at {cb.parameter} ≈ {e['at']:.4g} "
           f"({e['lo']:.4g}–{e['hi']:.4g}; least gap {e['gap_hz']:.3g} Hz)"
           for s, ev in obj["events"].items() for e in ev]
    md += [""] + critical_table(cb, obj["critical_speeds"])
    md += ["", f"Growing roots on the sweep (ζ below −({floor:.1e}, the scene's ζ allowance, + "
           "the solver's own ζ error); onset where ζ crosses zero):", ""] + [
        f"- {s}: {o['line']} grows from {cb.parameter} ≈ {o['from']:.6g} "
        f"({o['lo']:.6g}–{o['hi']:.6g}; least ζ {o['least_zeta']:.3g})"
        for s, os_ in onsets.items() for o in os_] if any(onsets.values()) else []
    md += [f"- {n}: {u['name']} unconfirmed (the lines cross near {u['lines_estimate']:.6g}): "
           f"{u['reason']}" for n, us in obj["unconfirmed_critical_speeds"].items() for u in us]
    md += [f"- {m['solver']}: no critical speeds — {m['reason']}" for m in obj["incomplete"]]
    md += ["", f"Every sampled {cb.parameter} and every critical speed judged pairwise: "
           + agree_text(c.verdict for c in sweep) + "."]
    md += [f"- {c.a} vs {c.b} {c.channel}: {c.verdict} (Δ/bound {c.ratio:.2g})"
           for c in sweep if c.verdict != Verdict.AGREE]
    if renamed:
        md += [f"- not judged, the two solvers give the name to different modes there (each "
               f"one's mode nearest the other's is another): {len(renamed)} comparisons, "
               + ", ".join(f"{c.a} vs {c.b} {c.channel}" for c in renamed[:4])
               + (" …" if len(renamed) > 4 else "")]
    return md + ["", "![campbell](campbell.png)"]


def threshold_section(obj: dict) -> list[str]:
    """"## Threshold speed": the closed form, every solver's eigenvalue threshold and the time
    solvers' (their table), the time-domain growth rates against the closed form. `obj`: the
    threshold block of the JSON (compare/workflows/threshold.py)."""
    w_cf = obj["closed_form_rad_s"]
    md = ["", "## Threshold speed (a root starts to grow)", ""]
    if w_cf is None or not math.isfinite(w_cf):
        return md + ["Closed form: none — every speed is stable."]

    def row(source, r):
        if r["status"] != "ok":
            return f"| {source} | {r['status']}: {r['reason']} | | | | | |"
        w = r["threshold_rad_s"]
        return (f"| {source} | {w:.10g} | {w * 30 / math.pi:.8g} | {r['error_rad_s']:.2g} | "
                f"{w - w_cf:+.2g} | {'yes' if r['agrees'] else 'NO'} | "
                f"{r['evaluations']} in {r['wall_s']:.2f} s |")
    md += [f"Closed form Ω_th = {w_cf:.10g} rad/s ({w_cf * 30 / math.pi:.8g} rpm). "
           "Eigenvalues: the largest Re λ crossing zero (brentq). Time domain: the rotor "
           f"released from rest at a deflection of {obj['release']:g} at constant speed, "
           f"{obj['record_s']:g} s records, the growing root fitted by matrix pencil (error: the "
           "fit's change from half the record to all of it plus the solver's own, from its "
           "tighter rerun), the zero of σ located by brentq.", "",
           "| source | Ω_th [rad/s] | rpm | ± [rad/s] | − closed form | within ± | evaluations |",
           "|---|---|---|---|---|---|---|"]
    md += [row(r["solver"], r) for r in obj["eigenvalues"]]
    md += [row(f"{r['solver']} (time domain)", r) for r in obj["time_domain"]]
    md += ["", "Time-domain growth rates against the closed form at the measured speed:", "",
           "| solver | speed [rad/s] | σ [1/s] | ± | closed form σ | whirl [rad/s] | agrees |",
           "|---|---|---|---|---|---|---|"]
    md += [f"| {r['solver']} | {p['spin_rad_s']:.10g} | {p['growth_per_s']:.8g} | "
           f"{p['error']:.2g} | {p['closed_form_growth_per_s']:.8g} | {p['whirl_rad_s']:.8g} | "
           f"{'yes' if p['agrees'] else 'NO'} |"
           for r in obj["time_domain"] for p in r["points"] if p["status"] == "ok"]
    return md


def identify_section(lines: list[str], verdicts: list) -> list[str]:
    """The scene's identification lines (its hook's words) and, where ring-down fits were set
    against the solvers' eigenvalues, their verdict table."""
    md = [""] + list(lines)
    if verdicts:
        md += ["", *markdown(VERDICT_HEADER, verdict_rows(verdicts)).splitlines()]
    return md


def sections(result) -> dict[str, list[str]]:
    """Every Markdown section of a modes result made in memory, by name ("head", "explain",
    "campbell", "threshold", "identify"), from `result.parts` (what the workflow found beyond
    the JSON: the scene's mode-by-mode comparisons, the explanation and identification lines
    of the scene's hooks and the ring-down verdicts, the Campbell diagram's `told`) and the
    result's own fields (runs, unpaired modes, campbell, extra's unstable and threshold)."""
    sc, parts = result.scene, result.parts
    runs = list(result.runs.values())
    out = {"head": head(sc, result.params, runs, parts.get("comparisons", result.comparisons),
                        result.extra.get("unstable", []), result.unpaired_modes),
           "explain": [""] + parts["explain"] if parts.get("explain") is not None else [],
           "campbell": [], "threshold": [], "identify": []}
    if result.campbell is not None and parts.get("campbell") is not None:
        out["campbell"] = campbell_section(sc.campbell, result.campbell, parts["campbell"])
    if result.extra.get("threshold") is not None:
        out["threshold"] = threshold_section(result.extra["threshold"])
    if parts.get("identify") is not None:
        out["identify"] = identify_section(*parts["identify"])
    return out
