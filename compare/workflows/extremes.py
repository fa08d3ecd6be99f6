"""`xval extremes SCENE`: every extreme case of the scene's spec, with every solver.

Each case × solver ends in exactly one outcome:
- `within tolerance` — status ok and the independent check passes (the energy balance closes,
  a second solver at accurate settings agrees, or a closed form holds) to within the case's
  bound — the bound alone: an error estimate proportional to the drift would pass any drift
  (MuJoCo's 9.2e-4 against a 1e-6 bound) — with the number, its ratio to the bound (two
  significant digits, `(marginal)` above half of it), and whether the drift is the run's own
  numerical error (it shrinks at the tighter setting: the estimate says by how much);
- an honest status — `diverged` / `unstable` / `singular` / `timeout` with the time and reason
  (the solver's own detection or the adapter's one energy rule);
- `FAILED` — status ok but the independent check fails (silent garbage: the one forbidden
  outcome), or an honest status where the case expects a passing run;
- `FAILED (known)` — a FAILED the case declares (`Extreme.known_failures`: the solver cannot
  meet the bound at any practical setting, with the reason), counted apart, never a pass;
  `stale: …` — a declared solver that no longer fails (the declaration must go);
- `error` — the leaf crashed.

`--strict` exits 1 on FAILED, error or a stale declaration — not on a FAILED (known), which the
scene file explains; the long runs (`Extreme.slow`, a whole case or some solvers' runs) only
run with `--all`.
"""
from __future__ import annotations

import datetime
from pathlib import Path

import numpy as np

from .. import solvers
from ..analysis import metrics
from ..analysis.trajectory import Trajectory
from ..analysis.verdict import MARGINAL
from ..errors import BadInput
from ..results import ExtremesResult
from ..results.studies import KNOWN
from ..results.studies import extremes_problems as problems  # noqa: F401  (the refused rows)
from ..scenes import Extreme, Scene, get_scene
from .plan import Knobs, plan

HONEST = ("diverged", "unstable", "singular", "timeout")


def _own_error(tr: Trajectory, channel: str) -> float:
    e = tr.errors.get(channel)
    return float(np.nanmax(e)) if e is not None and len(e) else 0.0


def _judged(value: float, bound: float, what: str, own: float) -> tuple[bool, float, str]:
    """value ≤ bound, said with the ratio; `own`: the run's own error estimate on the same
    scale, reported (a drift mostly numerical shrinks at the tighter setting), never added."""
    ok = value <= bound
    ratio = value / bound if bound > 0 else np.inf
    why = (f"{what} {value:.2e} {'≤' if ok else '>'} bound {bound:.0e} "
           f"(ratio {metrics.ratio_text(ratio)}{', marginal' if ok and ratio > MARGINAL else ''})")
    if own > 0 and np.isfinite(value):
        why += (f"; the run's own error estimate {own:.1e}: "
                + ("the drift shrinks at the tighter setting" if own >= 0.5 * value
                   else "the drift stays at the tighter setting"))
    return ok, value, why


def energy_check(sc: Scene, tr: Trajectory, bound: float) -> tuple[bool, float, str]:
    e = tr.channels[sc.energy_channel]
    scale = max(max(float(np.max(np.abs(tr.channels[c])))
                    for c in (sc.energy_channel, *sc.energy_scale_channels)), 1e-300)
    drift = float(np.max(np.abs(e - e[0]))) / scale
    return _judged(drift, bound, "energy balance drift of the energy scale",
                   _own_error(tr, sc.energy_channel) / scale)


def reference_check(sc: Scene, tr: Trajectory, ref: Trajectory, bound: float):
    if ref.status != "ok":
        return False, float("nan"), f"reference {ref.solver} {ref.status}: {ref.reason}"
    k = sc.key_channel
    d = np.abs(tr.channels[k] - ref.channels[k])
    scale = max(float(np.max(np.abs(ref.channels[k]))), 1e-300)
    return _judged(float(np.max(d)) / scale, bound,
                   f"{k} relative to {ref.solver} (accurate settings)",
                   (_own_error(tr, k) + _own_error(ref, k)) / scale)


def _plan(solver, sc, case, params, timeout_s):
    """One solver's plan of the case: its accurate settings with the case's overrides where the
    solver has the key (an integrator it does not offer is left out; a dict value is per
    solver: {name: value}, the solvers it does not name keep their own), checked against the
    output grid and the budgets."""
    info = solver.info(sc)
    over = {k: v.get(solver.name) if isinstance(v, dict) else v
            for k, v in case.settings.items() if k in info.defaults}
    over = {k: v for k, v in over.items() if v is not None}
    integrator = over.pop("integrator", None)
    if integrator is not None and integrator not in info.integrator_names:
        integrator = None
    dt = over.get("dt", {**info.defaults, **solver.preset}.get("dt"))
    if isinstance(dt, float) and dt > params["output_dt"] and "dt" not in over:
        over["dt"] = params["output_dt"]      # a fine output grid: its default step must fit
    return plan(sc, case.set, [solver.name], over, Knobs(integrator=integrator),
                timeout_s=timeout_s)


def _run(pl):
    (s,) = pl.solvers
    return solvers.simulate(pl.scene, s, pl.params, pl.settings[s.name], pl.timeout_s,
                            estimate_error=True, t_out=pl.t_out)


def run_case(sc: Scene, case: Extreme, chosen, timeout_s=None, log=print) -> list[dict]:
    params = sc.resolve(case.set)
    names = [s for s in chosen if not case.solvers or s.name in case.solvers]
    ref = None
    if case.check == "reference":
        ref = _run(plan(sc, case.set, [sc.reference_solvers[0]], timeout_s=timeout_s))
    rows = []
    for s in names:
        try:
            pl = _plan(s, sc, case, params, timeout_s)
        except BadInput as e:
            rows.append({"case": case.name, "solver": s.name, "outcome": "not applicable",
                         "value": None, "detail": str(e)})
            log(f"{sc.name} {case.name} {s.name}: not applicable — {e}")
            continue
        st = pl.settings[s.name]
        tr = _run(pl)
        row = {"case": case.name, "solver": s.name, "status": tr.status, "t_fail": tr.t_fail,
               "wall_s": tr.wall_s, "settings": {k: st.get(k) for k in case.settings}}
        if tr.status == "ok":
            if case.check == "energy":
                passed, value, what = energy_check(sc, tr, case.bound)
            elif case.check == "reference":
                passed, value, what = reference_check(sc, tr, ref, case.bound)
            else:
                passed, value, what = case.check(params, tr)
            if case.expect == "status":
                passed, what = False, f"returned ok where the case must end with a status; {what}"
            row.update(outcome="within tolerance" if passed else "FAILED", value=value,
                       detail=what, marginal=bool(passed and case.bound
                                                  and value > MARGINAL * case.bound))
        elif tr.status in HONEST:
            bad = case.expect == "ok"
            row.update(outcome=("FAILED: " if bad else "") + tr.status, value=tr.t_fail,
                       detail=f"at t = {tr.t_fail:.6g} s: {tr.reason}")
        else:
            row.update(outcome="error", value=None, detail=tr.reason)
        _declared(row, case.known_failures.get(s.name))
        log(f"{sc.name} {case.name} {s.name}: {row['outcome']} — {row['detail']}")
        rows.append(row)
    return rows


def _declared(row: dict, known: str | None):
    """A declared known failure: FAILED as declared, or a stale declaration (a crash stays an
    error)."""
    if not known or row["outcome"] == "error":
        return
    if row["outcome"].startswith("FAILED"):
        row.update(outcome=KNOWN, detail=f"known: {known}; {row['detail']}")
    else:
        row.update(outcome=f"stale: {row['outcome']}",
                   detail=f"declared a known failure ({known}), yet {row['detail']}")


def extremes_dir(root, scene_name) -> Path:
    """The default extremes folder (no --out): ROOT/extremes/SCENE-YYYYmmdd-HHMMSS."""
    stamp = datetime.datetime.now().strftime("%Y%m%d-%H%M%S")
    return Path(root) / "extremes" / f"{scene_name}-{stamp}"


def run_extremes(scene_name: str, solver_names, include_slow=False, timeout_s=None,
                 log=print) -> ExtremesResult:
    sc = get_scene(scene_name)
    if not sc.extremes:
        raise BadInput(f"scene {sc.name!r} lists no extreme cases")
    if sc.command != "run":
        raise BadInput(f"scene {sc.name!r}: its extremes run through `xval {sc.command}`")
    chosen = solvers.pick(sc, solver_names)
    cases = [c for c in sc.extremes if include_slow or c.slow is not True]
    rows = [r for c in cases for r in run_case(
        sc, c, [s for s in chosen if include_slow or not c.slow_for(s.name)], timeout_s, log)]
    skipped = [] if include_slow else (
        [c.name for c in sc.extremes if c.slow is True]
        + [f"{c.name}: {s.name}" for c in cases for s in chosen
           if c.slow_for(s.name) and (not c.solvers or s.name in c.solvers)])
    obj = {"scene": sc.name, "cases": [{"name": c.name, "set": c.set, "settings": c.settings,
                                        "check": c.check if isinstance(c.check, str)
                                        else "closed form", "bound": c.bound,
                                        "expect": c.expect, "known_failures":
                                        c.known_failures, "why": c.why} for c in cases],
           "results": rows,
           "skipped_slow": skipped,
           "n_failed": sum(r["outcome"].startswith("FAILED") and r["outcome"] != KNOWN
                           for r in rows),
           "n_known": sum(r["outcome"] == KNOWN for r in rows),
           "n_stale": sum(r["outcome"].startswith("stale") for r in rows)}
    return ExtremesResult(obj)
