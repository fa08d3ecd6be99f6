"""`xval bench SCENE --identify`'s summary lines, report.md and bench.json (the numbers from
compare/workflows/bench_identify.py)."""
from __future__ import annotations

from pathlib import Path

from .study import write_study


def _vals(names, values) -> str:
    return "—" if values is None else ", ".join(f"{n}={v:.6g}" for n, v in zip(names, values))


def _yes(x) -> str:
    return "—" if x is None else ("yes" if x else "no")


def summary_lines(obj: dict) -> list[str]:
    rec, rows = obj["record"], obj["rows"]
    ident = [r for r in rows if r["kind"] == "identify"]
    plain = next(r for r in rows if r["kind"] == "least_squares")
    lines = [f"record: {rec['solver']}, {rec['samples']} samples to {rec['t_end']:g} s "
             f"({len(rec['channels'])} channels, seed {rec['seed']}); truth "
             + _vals(obj["unknowns"], obj["truth"])]
    for r in ident:
        lines.append(
            f"identify {r['solver']}: {r['wall_s']:.3g} s (median of {len(r['walls_s'])}), "
            f"{r['runs']} runs, " + (f"χ²/dof {r['chi2_dof']:.3g}, truth inside the 95 % "
                                     f"intervals: {_yes(r['all_inside'])} ("
                                     + _vals(r["unknowns"], r["values"]) + ")"
                                     if r["converged"] else f"did not converge: {r['why']}"))
    lines.append(
        f"least_squares {plain['solver']} from the defaults: {plain['wall_s']:.3g} s, "
        f"{plain['runs']} runs, {'converged' if plain['converged'] else 'not converged'} "
        f"(cost {plain['cost']:.4g}, χ²/dof {plain['chi2_dof']:.3g}), reached the truth: "
        f"{_yes(plain['reached_truth'])} (" + _vals(plain["unknowns"], plain["values"]) + ")")
    q = obj["ratio"]
    lines.append(f"ratio identify/least_squares on {plain['solver']}: wall {q['wall']:.3g}, "
                 f"runs {q['runs']:.3g}; identify with all {len(ident)} solvers "
                 f"{obj['identify_wall_s']:.3g} s")
    if obj["start_is_truth"]:
        lines.append("note: the truth is the start (--set an unknown off its default to make "
                     "least_squares search)")
    return lines


def markdown(obj: dict) -> list[str]:
    rec, u = obj["record"], obj["unknowns"]
    md = [f"# Identification speed: {obj['scene']}", "",
          f"A record from {rec['solver']} ({rec['samples']} samples to {rec['t_end']:g} s, "
          f"channels {', '.join(rec['channels'])}, the scene's noise σ, seed {rec['seed']}) at "
          f"the truth {_vals(u, obj['truth'])}; fitted from {_vals(u, obj['start'])}. Median "
          f"wall of {obj['repeats']} repeats. *identify*: xval's fit (multi-start on the "
          "first solver, the others from its optimum; no profile check); *least_squares*: "
          "scipy's least_squares with its defaults over the same residuals, scaling and "
          "bounds. Reached the truth: every estimate within the 95 % half width of xval's "
          "fit on that solver.", "",
          *[f"- {x}" for x in summary_lines(obj)], "",
          "| fit | solver | median wall [s] | runs | converged | χ²/dof | estimates | "
          "truth inside |", "|---|---|---|---|---|---|---|---|"]
    for r in obj["rows"]:
        chi = "—" if r["chi2_dof"] is None else f"{r['chi2_dof']:.3g}"
        est = _vals(u, r["values"])
        if r["kind"] == "identify" and r["values"] is not None:
            est = ", ".join(f"{n}={v:.6g} ± {h:.2g}" for n, v, h in
                            zip(u, r["values"], r["half_width"]))
        inside = r["all_inside"] if r["kind"] == "identify" else r["reached_truth"]
        md.append(f"| {r['kind']} | {r['solver']} | {r['wall_s']:.4g} | {r['runs']} | "
                  f"{_yes(r['converged'])} | {chi} | {est} | {_yes(inside)} |")
    return md


def write_identify_bench(out_dir: Path, obj: dict) -> dict:
    """report.md and bench.json in `out_dir`; `obj` (its `result` type set by the caller) with
    its summary lines and report path."""
    obj["summary_lines"] = summary_lines(obj)
    return write_study(out_dir, markdown(obj), obj, "bench.json", report_in_json=False)
