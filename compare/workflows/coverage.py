"""Do the error bars bound the error? Each solver's own error estimate (`solvers.simulate(...,
estimate_error=True)`: the tighter rerun plus what it cannot see) against its true error — the
distance to a far tighter run of the same solver (1000× the tolerance, 1/16 of the step: an
order-p method's error there is 16^-p of the run's) — over parameter points sampled near the
scene's defaults, inside each parameter's admissible range.

Per solver: the fraction of (point, channel) pairs whose estimate contains the true error
(the claim: ≥ 95 %), and the median sharpness true/estimate (≥ 0.1: a bound 1000× too wide
says nothing). `xval`'s verdicts are only as good as these two numbers.
"""
from __future__ import annotations

import numpy as np

from .. import solvers
from ..leafinfo import LeafInfo
from ..scenes import Scene, get_scene

FAR = 4          # halvings of a fixed step for the reference (1/16 of it)
FAR_RTOL = 1e-3  # the reference's tolerance, relative to the run's (floored at 1e-14)


def sample(scene: Scene, n: int, seed: int = 0, spread: float = 0.05,
           fixed: dict | None = None) -> list[dict]:
    """`n` resolved parameter dicts: each float parameter with a non-zero default drawn
    uniformly within ±`spread` of it (relative), clipped into its admissible range; `fixed`
    (name -> value, e.g. a short t_end), the horizon and the output grid step are not drawn."""
    rng = np.random.default_rng(seed)
    fixed = dict(fixed or {})
    out = []
    for _ in range(n):
        over = dict(fixed)
        for p in scene.params:
            if p.name in fixed or p.name in ("t_end", "output_dt") or not p.is_float \
                    or not p.default:
                continue
            v = float(p.default) * (1 + spread * rng.uniform(-1, 1))
            lo = p.lo if not p.open_lo else np.nextafter(p.lo, np.inf)
            over[p.name] = float(np.clip(v, lo, p.hi))
        out.append(scene.resolve(over))
    return out


def far_tighter(info: LeafInfo, settings: dict) -> dict | None:
    """The reference settings: a tolerance 1000× tighter (not below 1e-14), else 1/16 of the
    step, and every other discretisation knob 1/16 of its value; None where the solver has
    neither a step nor a tolerance."""
    s = info.refined(dict(settings), FAR)
    if s.get("integrator") in info.adaptive and \
            isinstance(s.get("rtol"), (int, float)):
        s["rtol"] = max(s["rtol"] * FAR_RTOL, 1e-14)
        if isinstance(s.get("atol"), (int, float)):
            s["atol"] = s["atol"] * s["rtol"] / settings["rtol"]
        return s
    for _ in range(FAR):
        s, _, _ = solvers.tighter_settings(info, s)
        if s is None:
            return None
    return s


def reference_run(scene: Scene, solver: solvers.Solver, params: dict, warm_up: bool = False,
                  dt: float | None = None):
    """The solver's far tighter run (None where it has no accuracy knob); `dt`: the step its
    "auto" chose in the run (an explicit engine's stability-bound step)."""
    s = solvers.settings_for(solver, scene.name, t_out=scene.output_grid(params))
    if s.get("dt") == "auto" and dt:
        s["dt"] = dt
    s = far_tighter(solver.info(scene), s)
    return None if s is None else solvers.simulate(scene, solver, params, s, warm_up=warm_up)


def point(scene: Scene, solver: solvers.Solver, params: dict, warm_up: bool = False,
          ref=None) -> dict:
    """One solver at one point: per channel, the estimate (max over t, plus the reference's
    own round-off) and the true error (max over t of |run − reference|); the reference is
    `ref` (another solver's far tighter run of the same point) or the solver's own. Status
    other than "ok" where the run, its estimate or the reference did not complete."""
    settings = solvers.settings_for(solver, scene.name, t_out=scene.output_grid(params))
    tr = solvers.simulate(scene, solver, params, settings, estimate_error=True,
                          warm_up=warm_up)
    if tr.status != "ok" or not tr.errors:
        return {"status": tr.status if tr.status != "ok" else tr.stats.get("error_estimate_by")}
    ref = ref or reference_run(scene, solver, params, dt=tr.settings.get("dt"))
    return bars(scene, tr, ref)


def bars(scene: Scene, tr, ref) -> dict:
    """A run's error bars against its reference `ref` (as `point`): per channel the estimate
    and the true error, or a status saying why there is no truth."""
    if ref is None:
        return {"status": "no accuracy knob for a reference"}
    if ref.status != "ok":
        return {"status": f"reference {ref.status}"}
    # the truth is known to the reference's own round-off (solvers.py's floor for one run):
    # where the run is itself at round-off (lagrange-exact's press at rk4 1e-5: 3e-14 of the
    # scale), 32000 reference steps carry as much
    scale = truth_scales(scene, ref)
    known = {c: np.sqrt(solvers._steps(ref)) * solvers.EPS * scale[c] for c in scene.channels}
    return {"status": "ok",
            "estimate": {c: float(np.nanmax(tr.errors[c]) + known[c]) for c in scene.channels},
            "true": {c: float(np.nanmax(np.abs(tr.channels[c] - ref.channels[c])))
                     for c in scene.channels},
            "scale": scale, "floor": truth_floor(scene, ref, scale)}


def truth_floor(scene: Scene, ref, scale: dict | None = None) -> dict:
    """What the truth is not known better than, per channel: its rounding added up step by
    step, linearly at worst (Exudyn's rotor-spinup energies at dt/16 and dt/32 differ by 7e-12 J
    of 7 J, 30× the √steps figure, within the linear 5e-11 J); `scale`: `truth_scales`'."""
    scale = scale or truth_scales(scene, ref)
    return {c: float(solvers._steps(ref) * solvers.EPS * scale[c]) for c in scene.channels}


def truth_scales(scene: Scene, ref) -> dict:
    """What each channel of the truth rounds with: its largest |value|, and for the energy
    balance, a residual near zero, the energies it balances (as the energy rule weighs it):
    andrews-squeezer's far runs (MuJoCo's, lagrange-partial's) disagree on it by 5–7e-13 of
    the spring energy, MuJoCo's moving by 2–5e-12 J when its step halves again."""
    scale = {c: float(np.nanmax(np.abs(ref.channels[c]))) for c in scene.channels}
    if scene.energy_channel in scale:
        scale[scene.energy_channel] = float(solvers.energy_scale(scene, scale))
    return scale


def study(scene_name: str, n: int, seed: int = 0, solver_names=None, fixed: dict | None = None,
          spread: float = 0.05, reference: str | dict | None = None, log=None) -> dict:
    """The coverage of every chosen solver's error estimate over `n` sampled points:
    {solver: {"points", "pairs", "contained", "sharpness", "misses", "not_run"}}, where
    `contained` is the fraction of (point, channel) pairs with true ≤ estimate, `sharpness` the
    median true/estimate, `misses` the worst pairs (channel, true, estimate, params drawn).
    `reference`: a solver whose far tighter runs are every other solver's truth (independent;
    one that models the same system exactly), or {solver: that solver's reference}; else (and
    for the solvers the dict leaves out) each solver's own far tighter run."""
    sc = get_scene(scene_name)
    chosen = solvers.pick(sc, solver_names)
    points = sample(sc, n, seed, spread, fixed)
    if isinstance(reference, str):
        reference = {s.name: reference for s in chosen if s.name != reference}
    reference = {k: v for k, v in (reference or {}).items() if k in {s.name for s in chosen}}
    refs = {}
    for name in set(reference.values()):
        rs = solvers.get_solver(name)
        refs[name] = [reference_run(sc, rs, p, warm_up=(k == 0)) for k, p in enumerate(points)]
    out = {}
    for s in chosen:
        rows, not_run = [], {}
        mine = refs.get(reference.get(s.name), [None] * n)
        for k, p in enumerate(points):
            r = point(sc, s, p, warm_up=(k == 0), ref=mine[k])
            if r["status"] != "ok":
                not_run[r["status"]] = not_run.get(r["status"], 0) + 1
                continue
            rows += [(c, r["true"][c], r["estimate"][c], k) for c in sc.channels]
        true = np.array([r[1] for r in rows])
        est = np.array([r[2] for r in rows])
        inside = true <= est
        ratio = true[est > 0] / est[est > 0]
        worst = sorted((r for r, ok in zip(rows, inside) if not ok),
                       key=lambda r: -r[1] / max(r[2], 1e-300))[:5]
        out[s.name] = {"points": len(points) - sum(not_run.values()), "pairs": len(rows),
                       "contained": float(np.mean(inside)) if len(rows) else float("nan"),
                       "sharpness": float(np.median(ratio)) if len(ratio) else float("nan"),
                       "misses": [{"channel": c, "true": t, "estimate": e, "point": k}
                                  for c, t, e, k in worst],
                       "not_run": not_run}
        if log:
            o = out[s.name]
            log(f"{sc.name} {s.name}: {o['points']} points, contained {o['contained']:.3f}, "
                f"median true/estimate {o['sharpness']:.2f}"
                + (f", not run {not_run}" if not_run else ""))
    return out
