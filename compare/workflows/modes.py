"""`xval modes`: natural frequencies from every solver that can linearise, matched mode by mode;
for a scene that declares a Campbell sweep, each solver's mode lines over the sweep (tracked by
mode-shape correlation where the leaves return shapes, else by label) with the critical speeds
where a line crosses an excitation line, the mode shapes in 3D where the scene has a
`mode_shape_3d` hook (compare/mode_shapes.py), and the scene's own identification hook
(frequencies identified from free responses of its time-domain solvers). Nothing here names a
scene.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy.optimize import brentq, linear_sum_assignment

from .. import solvers
from ..analysis import band_edge, campbell, metrics
from ..analysis.campbell import mac
from ..analysis.trajectory import Modes
from ..analysis.verdict import Verdict, agree_text
from ..errors import BadInput
from ..results import ModesResult
from ..results.modes import damped_json, growing_modes
from ..scenes import Scene, get_scene
from .plan import plan
from .threshold import run_threshold

SAME_MODE = 0.5     # a mode followed by label must share this much shape with its line (MAC)


def sweep(scene: Scene, solver: solvers.Solver, params: dict, values: np.ndarray) -> list[Modes]:
    """The solver's modes at each value of the scene's sweep parameter."""
    name = scene.campbell.parameter
    return [solvers.modes(scene, solver, {**params, name: float(v)}) for v in values]


def _unique(labels) -> bool:
    return all(labels) and len(set(labels)) == len(labels)


def track(results: list[Modes]) -> dict[str, np.ndarray]:
    """The lines on which critical speeds are found, on the scene's grid (the diagram draws
    compare/analysis/campbell.py's lines). Never by sorting: from one point to the next a
    mode keeps its label where both points label their modes uniquely and alike (the leaves
    classify modes from their shapes: flap / lag / torsion, forward / backward whirl);
    elsewhere — repeated roots at rest ("whirl 1" twice), a leaf without
    physical labels — by mode-shape correlation (MAC, optimal assignment), else by nearest
    frequency. Each line is keyed by its label at the end of the sweep, made unique."""
    ok = [r for r in results if r.status == "ok" and len(r.frequencies_hz)]
    if len(ok) != len(results) or not ok:
        return {}
    n = min(len(r.frequencies_hz) for r in ok)
    lines = np.full((n, len(ok)), np.nan)
    order = np.arange(n)
    lines[:, 0] = ok[0].frequencies_hz[:n]
    for k in range(1, len(ok)):
        prev, cur = ok[k - 1], ok[k]
        before = [prev.labels[j] for j in order]
        if _unique(prev.labels) and _unique(cur.labels) and set(before) <= set(cur.labels):
            order = np.array([cur.labels.index(lb) for lb in before])
        elif prev.shapes is not None and cur.shapes is not None:
            rows, cols = linear_sum_assignment(-mac(prev.shapes[order], cur.shapes))
            order = cols[np.argsort(rows)]
        else:
            cost = np.abs(prev.frequencies_hz[order][:, None] - cur.frequencies_hz[None, :])
            rows, cols = linear_sum_assignment(cost)
            order = cols[np.argsort(rows)]
        lines[:, k] = cur.frequencies_hz[order]
    keys = []
    for i, j in enumerate(order):
        key = ok[-1].labels[j] or f"mode {i + 1}"
        keys.append(key if key not in keys else f"{key} #{keys.count(key) + 1}")
    return dict(zip(keys, lines))


def _refine(gap, lo, hi, v0, d):
    """The root of `gap` in [lo, hi] to 1e-9 relative (the frequencies it compares are located
    to 1e-10: a tighter bracket meets their noise). Every evaluation is a whole modes run
    (~0.5 s on the helicopter), so the step is first cut at v0 ± d around an estimate, and
    brentq runs on the piece holding the sign change; values are remembered
    (brentq evaluates its bracket's ends again). The step's ends are evaluated anew: the swept
    lines follow a mode by shape, `gap` by label, and near-degenerate pairs (the hovering
    fuselage's) swap labels between sweep points."""
    memo: dict = {}

    def f(v):
        if v not in memo:
            memo[v] = gap(v)
        return memo[v]
    a, b = max(lo, v0 - d), min(hi, v0 + d)
    for x0, x1 in ((a, b), (lo, a), (b, hi)):           # the estimate's piece first
        if x1 <= x0:
            continue
        if f(x0) == 0.0:
            return x0
        if f(x0) * f(x1) < 0:
            return brentq(f, x0, x1, xtol=1e-9 * abs(x1), rtol=1e-14)
    raise ValueError("no sign change of the gap in the step")


def critical_speeds(scene: Scene, solver: solvers.Solver, params: dict, values: np.ndarray,
                    results: list[Modes], hint: dict | None = None,
                    unconfirmed: list | None = None) -> list[dict]:
    """For each excitation of the scene's Campbell (compare/scenes/base.py `Excitation`): the
    sweep values where a mode line, seen in the excitation's frame, crosses order × the
    rotation frequency (the solver's `results` on the grid `values`, re-expressed in that frame
    where the modes whirl: compare.physics.whirl), refined by root finding on the solver
    itself (the mode followed by label, else by nearest frequency). The first estimate is the
    lines' linear interpolation (±2 % of the step), or another solver's critical speed of the
    same name in `hint` (±1e-4 relative: solvers that agree save half the modes runs; one that
    does not falls back to the whole step). One entry per crossing (`entry`); a crossing of
    the lines the solver does not confirm is appended to `unconfirmed` with the reason."""
    cb = scene.campbell
    if cb.excitation_hz is None:
        return []
    out = []
    for exc in cb.active(params):                  # a 2× line only where a 2× load exists
        def seen(m, v, exc=exc):
            return campbell.in_frame(m, cb.excitation_hz(params, v), cb.frame, exc.frame)
        lines = track([seen(m, v) for m, v in zip(results, values)])
        on_line = np.array([exc.order * cb.excitation_hz(params, v) for v in values])
        for key, f in lines.items():
            g = f - on_line
            idx = np.nonzero(np.sign(g[:-1]) * np.sign(g[1:]) < 0)[0]
            for i in idx[:1]:                      # the first crossing of each line
                name = key if exc is cb.excitations[0] else f"{key} ({exc.order}×)"
                shapes = [r.shapes[r.labels.index(key)] for r in results[i:i + 2]
                          if r.shapes is not None and key in r.labels]
                found = _crossing(scene, solver, params, values, i, g, key, f[i], shapes, exc,
                                  seen, (hint or {}).get(name))
                if isinstance(found, str):
                    if unconfirmed is not None:
                        unconfirmed.append({"name": name, "order": exc.order,
                                            "excitation": exc.name, "frame": exc.frame,
                                            "lines_estimate": float(_linear(values, g, i)),
                                            "step": [float(values[i]), float(values[i + 1])],
                                            "reason": found})
                    continue
                out.append(entry(cb, params, name, exc, *found))
    return out


def entry(cb, params, name, exc, value, whirl, error=None, slope=None,
          linearisation=None) -> dict:
    """One critical speed as a ROSS user reads it: the sweep value, the speed in rad/s and
    rpm, the crossing's frequency in Hz and rad/s (in `frame`, where the lines crossed the
    excitation), the excitation, the mode's whirl ("forward"/"backward"; None: no whirl); its
    error estimate in the sweep's unit and the slope of frequency minus excitation there
    (Hz per unit: what turns a frequency allowance into one on the speed)."""
    speed_hz = cb.excitation_hz(params, value)
    return {"name": name, "value": float(value), "unit": cb.unit, "error": error,
            "slope_hz": slope, "linearisation_error": linearisation,
            "speed_rad_s": 2 * np.pi * speed_hz, "speed_rpm": 60 * speed_hz,
            "frequency_hz": exc.order * speed_hz,
            "frequency_rad_s": 2 * np.pi * exc.order * speed_hz,
            "order": exc.order, "excitation": exc.name, "frame": exc.frame, "whirl": whirl,
            "solver_frame": cb.frame}


def _linear(values, g, i):
    lo, hi = values[i], values[i + 1]
    return lo - g[i] * (hi - lo) / (g[i + 1] - g[i])


def _crossing(scene, solver, params, values, i, g, key, f0, shapes, exc, seen, near):
    """The crossing of line `key` in step i, on the solver: (value, whirl), or why not (str).
    The mode is followed by its label, else by the frequency nearest `f0`; where the line's
    `shapes` at the step's ends are known, the mode must share half its shape with one of them
    (MAC ≥ SAME_MODE): a leaf that misses a mode renumbers the others (mstmm misses the shaft's
    forward whirl within |ω*| < 1e-7 of its rotating-frame zero and called the second bending
    mode 'forward whirl 1' there, MAC 0.023 with the line: brentq then stopped at that band's
    edge, 3.6e-8 off); half, not MAC_KEEP, so that a mode halfway through a veering holds."""
    cb = scene.campbell
    whirl = {}

    def gap(v):
        m = seen(solvers.modes(scene, solver, {**params, cb.parameter: float(v)}), v)
        if key in m.labels:
            j = m.labels.index(key)
        elif _unique(m.labels):          # the solver names its modes, none of them so
            raise ValueError(f"no mode {key!r} at {v}")
        else:
            j = int(np.argmin(np.abs(m.frequencies_hz - f0)))
        if shapes and m.shapes is not None and np.max(mac(m.shapes[j], shapes)) < SAME_MODE:
            raise ValueError(f"the mode called {key!r} at {v} is another (MAC "
                             f"{np.max(mac(m.shapes[j], shapes)):.2f} with the line's)")
        whirl["last"] = campbell.whirl(m, exc.frame, cb.excitation_hz(params, v))[j]
        errors = metrics.frequency_errors(m)
        whirl["error_hz"] = None if errors is None else float(errors[j])
        lin = metrics.frequency_errors(m, linearisation=True)
        whirl["linearisation_hz"] = None if lin is None else float(lin[j])
        return m.frequencies_hz[j] - exc.order * cb.excitation_hz(params, v)
    lo, hi = values[i], values[i + 1]
    v0 = _linear(values, g, i)                                 # linear, from the lines
    try:
        v = (_refine(gap, lo, hi, near, 1e-4 * abs(near)) if near is not None and lo < near < hi
             else _refine(gap, lo, hi, v0, 0.02 * (hi - lo)))
    except (ValueError, IndexError) as e:
        first = f"root finding on the solver: {e}"
        # a body-frame linearisation can lose the mode exactly at the crossing (its body-frame
        # frequency is 0 there): parabola through points beside it, its root taken only among
        # them. Else the solver does not confirm the crossing and none is reported: the lines
        # can pass between different modes over a step (the hovering helicopter's whole-
        # aircraft modes have no 'fuselage' label below ~10 rad/s), and a root extrapolated
        # from points near the lines' estimate (4.54 rad/s) to 4.98 was no critical speed.
        x = v0 + 1e-3 * (hi - lo) * np.array([-3, -2, 2, 3.0])
        try:
            y = np.array([gap(v) for v in x])
            roots = np.roots(np.polyfit(x - v0, y, 2)).real + v0
            v = float(roots[np.argmin(np.abs(roots - v0))])
        except (ValueError, IndexError) as e:
            return f"{first}; parabola beside the estimate: {e}"
        if not x[0] <= v <= x[-1]:
            return (f"{first}; the parabola's root {v:.6g} lies outside the points beside the "
                    f"estimate [{x[0]:.6g}, {x[-1]:.6g}]")
    at_root = dict(whirl)
    edge = band_edge.locate(lambda x: (gap(x), whirl.get("error_hz"),
                                       whirl.get("linearisation_hz")), v, lo, hi, (g[i], g[i + 1]))
    if edge is None:                            # a crossing: the mode as found at its root
        whirl.update(at_root)
    elif isinstance(edge, str):
        return edge
    else:
        v, error, lin = edge                    # the whirl: the last point fitted, beside it
        # an edge moves with the frequencies as the line does: the allowance over its slope
        slope = exc.order * abs(cb.excitation_hz(params, hi) - cb.excitation_hz(params, lo)) / (
            hi - lo)
        return (v, whirl.get("last"), None if error is None else error + 1e-9 * abs(v), slope,
                None if lin is None else lin + 1e-9 * abs(v))
    # the crossing's error: the mode's frequency error over the gap's slope across the step,
    # plus the root's own tolerance (1e-9 relative)
    slope = abs((g[i + 1] - g[i]) / (hi - lo))
    error, lin = ((None if whirl.get(k) is None or slope == 0 else
                   whirl[k] / slope + 1e-9 * abs(v)) for k in ("error_hz", "linearisation_hz"))
    return v, whirl.get("last"), error, slope, lin


def _same_mode(runs: list, c) -> bool:
    """Whether the two modes a sweep comparison pairs by name are one mode: each is the other
    solver's nearest in frequency. Where a solver misses a mode (MSTMM's root scan starts at
    0.1 Hz; the hovering aircraft has two flap modes below it at 1.25 rad/s) the names shift,
    and a comparison of two different modes says nothing about either solver."""
    label = c.channel.split(" @ ")[0].removesuffix(" ζ")
    a, b = (next(m for m in runs if m.solver == s) for s in (c.a, c.b))
    if label not in a.labels:
        return True
    fa, fb = (np.asarray(m.frequencies_hz, float) for m in (a, b))
    i = a.labels.index(label)
    # its partner: the mode of that name, else (paired by frequency) the one c measured against
    # (a ζ comparison's deviation is no frequency: its pair's nearest stands for it)
    j = (b.labels.index(label) if label in b.labels else
         int(np.argmin(np.abs(fb - fa[i]))) if c.channel.split(" @ ")[0].endswith(" ζ") else
         int(np.argmin(np.abs(np.abs(fb - fa[i]) - c.deviation))))
    return int(np.argmin(np.abs(fb - fa[i]))) == j and int(np.argmin(np.abs(fa - fb[j]))) == i


def critical_speed_comparisons(sc: Scene, params: dict, entries: dict) -> list:
    """Every pair of solvers' critical speeds of one name, as Comparisons ("critical speed
    <name>"): |Δ| against both crossings' error estimates plus the pair's frequency allowance
    for that mode at the crossing's speed, carried onto the speed (δf over the slope of
    frequency minus excitation, the flatter of the two) — a crossing computed is a crossing
    judged. The allowance is the larger of the two crossings' (a model difference that grows
    with speed: rotating-beam's torsion shift ∝ Ω², 3× the scene's speed-0 allowance at a
    38 rad/s crossing, `xval calibrate rotating-beam --seed 7373` set 0's Campbell)."""
    cb = sc.campbell
    tol = sc.tolerances_for(params)
    one_model = set(tol.get("frequency_one_model", ()))
    at = {}

    def allowance(a, b, e):
        """The pair's relative allowance on e's mode at e's crossing speed."""
        v = e["value"]
        if v not in at:
            at[v] = sc.tolerances_for({**params, cb.parameter: float(v)})
        return metrics.frequency_allowance(at[v], a, b, _mode_of(e))
    names = list(entries)
    out = []
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            mine = {e["name"]: e for e in entries[b]}
            for ea in entries[a]:
                eb = mine.get(ea["name"])
                if eb is None:
                    continue
                d = abs(ea["value"] - eb["value"])
                scale = max(abs(ea["value"]), abs(eb["value"]), 1e-300)
                slopes = [e["slope_hz"] for e in (ea, eb) if e.get("slope_hz")]
                allow = (max(allowance(a, b, ea), allowance(a, b, eb)) * ea["frequency_hz"]
                         / min(slopes) if slopes else 0.0)
                shared = bool({f"{a}|{b}", f"{b}|{a}"} & one_model)
                # one discrete model: only what each one's linearisation adds (as frequencies)
                key = "linearisation_error" if shared else "error"
                own = (None if ea.get(key) is None or eb.get(key) is None
                       else {a: ea[key], b: eb[key]})
                err = sum(own.values()) if own else None
                bound = allow + (err or 0.0)
                v, wide = metrics.judged(d, bound, own, allow, scale, f" {ea['unit']}"
                                         if ea["unit"] else "")
                why = (f"{ea['value']:.8g} vs {eb['value']:.8g}: |Δ| {d:.2e} "
                       f"{'>' if v == Verdict.DISAGREE else '≤'} "
                       + (f"error estimates {err:.1e} + " if err is not None else "")
                       + f"allowance {allow:.1e} (the frequency allowance over the slope)")
                out.append(metrics.Comparison(
                    a, b, f"critical speed {ea['name']}", d, d, d / scale, scale,
                    bound / scale, v, f"{wide}; {why}" if wide else why, d, err, allow))
    return out


def _mode_of(e: dict) -> str:
    """The mode a critical speed entry crosses with: its name without the excitation's order."""
    return e["name"].removesuffix(f" ({e['order']}×)")


def by_name(entries: list[dict]) -> dict[str, float]:
    """{name: value} of a solver's critical speeds (the JSON's `critical_speeds`)."""
    return {e["name"]: e["value"] for e in entries}


def campbell_diagram(sc: Scene, chosen, params, log=print, frame=None):
    """Critical speeds on the scene's grid (lines by label, refined on each solver's own mode:
    unchanged by the diagram), then the diagram: the grid refined where any solver's lines are
    uncertain, every solver on the same points, lines tracked by MAC with veerings and
    crossings told apart (compare/analysis/campbell.py) in the frame the solvers report, and
    read in the other frame too where the modes whirl. The figure is drawn in `frame` (default:
    the solvers'). Returns the JSON part, the critical speeds, what the report says beyond the
    JSON (`told`: the ζ allowance, the figure's frame, the sweep's comparisons judged and not)
    and what the figure draws (values, the lines in `frame`, critical speeds, events, `frame`,
    the lines in the solvers' frame)."""
    cb = sc.campbell
    frame = frame or cb.frame
    chosen = [s for s in chosen if not cb.solvers or s.name in cb.solvers]
    values = cb.values(params)
    memo = {s.name: {} for s in chosen}

    def at(s, v):
        if v not in memo[s.name]:
            memo[s.name][v] = solvers.modes(sc, s, {**params, cb.parameter: float(v)})
        return memo[s.name][v]
    entries, usable, unconfirmed, missing = {}, [], {}, []
    for s in chosen:
        results = [at(s, float(v)) for v in values]
        if not track(results):
            bad = next((m for m in memo[s.name].values() if m.status != "ok"), None)
            missing.append({"solver": s.name, "reason": "a sweep point failed: no lines"
                            + (f" ({bad.status}: {bad.reason})" if bad else "")})
            log(f"campbell {s.name}: {missing[-1]['reason']}")
            continue
        usable.append(s)
        entries[s.name] = critical_speeds(sc, s, params, values, results,
                                          hint=by_name(next(iter(entries.values()), [])),
                                          unconfirmed=unconfirmed.setdefault(s.name, []))
    crit = {s: by_name(es) for s, es in entries.items()}
    step = (values[-1] - values[0]) / max(len(values) - 1, 1)
    grid, per_point = campbell.sample(lambda v: [at(s, v) for s in usable], values,
                                      cb.refine if usable else 0, step / 2 ** cb.depth)
    diagrams = {s.name: campbell.track_lines(grid, [p[k] for p in per_point])
                for k, s in enumerate(usable)}
    # every sampled value judged as the scene's own point is: pair by pair, mode by mode, with
    # each solver's error bars and the allowances at that value (a line drawn is a line judged).
    # Whirling modes are judged as seen from the ground: in the rotating frame a forward whirl's
    # frequency passes through 0 at its critical speed, where a relative comparison says nothing
    judged = "fixed" if "fixed" in cb.frames else cb.frame
    sweep, renamed = [], []
    for v, runs in zip(grid, per_point):
        seen = [campbell.in_frame(m, cb.excitation_hz(params, v), cb.frame, judged)
                for m in runs]
        for c in sc.verdicts({**params, cb.parameter: float(v)}, seen):
            c = replace(c, channel=f"{c.channel} @ {cb.parameter} {v:.6g}")
            (sweep if _same_mode(seen, c) else renamed).append(c)
    sweep += critical_speed_comparisons(sc, params, entries)
    by_frame = {f: {s.name: diagrams[s.name].lines_of(
        [campbell.in_frame(p[k], cb.excitation_hz(params, v), cb.frame, f)
         for p, v in zip(per_point, grid)]) for k, s in enumerate(usable)} for f in cb.frames}
    lines = by_frame[cb.frame]
    events = {s: d.events for s, d in diagrams.items()}
    # ζ along each line (tracked as the frequencies are), where a solver gives damping
    zeta = {s.name: diagrams[s.name].lines_of([replace(p[k], frequencies_hz=p[k].damping)
                                               for p in per_point])
            for k, s in enumerate(usable)
            if all(p[k].damping is not None for p in per_point)}
    # and ζ's error estimate along the same lines, where the solver gives one
    zeta_error = {s.name: diagrams[s.name].lines_of(
        [replace(p[k], frequencies_hz=p[k].extra["damping_error"]) for p in per_point])
        for k, s in enumerate(usable) if s.name in zeta
        and all(p[k].extra.get("damping_error") is not None for p in per_point)}
    floor = sc.tolerances_for(params).get("damping", 0.0)
    onsets = {s: campbell.growing_onsets(grid, z, floor, zeta_error.get(s))
              for s, z in zeta.items()}
    none = lambda f: [None if not np.isfinite(x) else float(x) for x in f]   # noqa: E731
    obj = {"parameter": cb.parameter, "values": list(grid), "grid_points": len(values),
           "frame": cb.frame, "lines_hz": {s: {k: none(v) for k, v in ln.items()}
                                           for s, ln in lines.items()},
           "lines_hz_by_frame": {f: {s: {k: none(v) for k, v in ln.items()}
                                     for s, ln in by.items()} for f, by in by_frame.items()},
           "line_mac": {s: {k: none(v) for k, v in d.mac.items()} for s, d in diagrams.items()},
           "events": {s: [e.as_dict() for e in ev] for s, ev in events.items()},
           "min_mac_unmarked": {s: d.min_mac_unmarked() for s, d in diagrams.items()},
           "excitations": [{"order": e.order, "frame": e.frame, "name": e.name}
                           for e in cb.active(params)],
           "critical_speeds": entries,
           "zeta_lines": {s: {k: none(v) for k, v in z.items()} for s, z in zeta.items()},
           "growing_from": {s: o for s, o in onsets.items() if o},
           "unconfirmed_critical_speeds": {s: u for s, u in unconfirmed.items() if u},
           "incomplete": missing,
           "sweep_verdicts": {"comparisons": len(sweep), "renamed": [
                                  f"{c.a} vs {c.b} {c.channel}" for c in renamed],
                              "counts": dict(Verdict.tally(c.verdict for c in sweep)),
                              "not_agree": [c.as_dict() for c in sweep
                                            if c.verdict != Verdict.AGREE]}}
    if lines:
        obj["figure_frame"] = frame
    # what the report says beyond the JSON (compare/output/modes_report.py composes it)
    told = {"floor": floor, "frame": frame, "sweep": sweep, "renamed": renamed}
    growing = {s: {k: np.asarray(z, float) < -(floor + np.nan_to_num(np.asarray(
        zeta_error.get(s, {}).get(k, 0.0), float))) for k, z in zeta[s].items()}
        for s, o in onsets.items() if o}
    return obj, crit, told, (grid, by_frame[frame], entries, events, frame, lines, growing), \
        [c for c in sweep if c.verdict != Verdict.AGREE]


def _run_time(scene: Scene, solver_name: str, params: dict, max_dt: float,
              tighter: bool = False):
    """A time-domain run for an identification hook: the solver's accurate defaults, its fixed
    step capped so that it fits the record's grid; `tighter`: at the settings of its own error
    estimate instead (`LeafInfo.tighter`), the factor on |y − y_tight| in
    stats["error_factor"]."""
    s = solvers.get_solver(solver_name)
    settings = solvers.settings_for(s, scene.name)
    if isinstance(settings.get("dt"), float) and settings["dt"] > max_dt:
        settings["dt"] = max_dt
    factor = None
    if tighter:
        tight, factor, _ = s.info(scene).tighter(settings)
        settings = tight if tight is not None else settings
    tr = solvers.simulate(scene, s, params, settings)
    if factor is not None:
        tr.stats["error_factor"] = factor
    return tr


def _at_rest(sc, params, m):
    """At rest (the Campbell's rotation frequency 0) a forward and a backward whirl are one
    degenerate pair with no sense of whirl: their whirl is "—" (the labels stay the keys
    the solvers are paired by; `shown_label` drops the sense where the whirl is "—")."""
    cb = sc.campbell
    if m.whirl is None or cb is None or cb.excitation_hz is None \
            or cb.parameter not in params or cb.excitation_hz(params, params[cb.parameter]) != 0:
        return m
    return replace(m, whirl=["—"] * len(m.whirl))


def run_modes(scene_name, solver_names, overrides, log=print, campbell_sweep=True,
              identify=True, campbell_frame=None, threshold=True) -> ModesResult:
    """Every chosen solver's modes, compared; the Campbell diagram (its figure in
    `campbell_frame`, default the solvers' frame), the explanations, the threshold speed
    (workflows/threshold.py) and the identification where the scene has them. Held in memory:
    `.save(folder)` writes it."""
    sc = get_scene(scene_name).modal()       # a time scene answers by its linearisation
    if campbell_frame is not None and campbell_frame not in (
            sc.campbell.frames if sc.campbell else ()):
        raise BadInput(f"--campbell-frame {campbell_frame}: {sc.name} draws its Campbell "
                       + (f"diagram in the {' or '.join(sc.campbell.frames)} frame"
                          if sc.campbell else "diagram nowhere: it sweeps nothing"))
    pl = plan(sc, overrides, solver_names)
    params, chosen = pl.params, list(pl.solvers)
    results = []
    for s in chosen:
        log(f"{sc.name}: {s.name} …")
        results.append(_at_rest(sc, params, solvers.modes(sc, s, params)))
    comparisons = sc.verdicts(params, results)
    unpaired = metrics.unpaired_modes(results, sc.tolerances_for(params))
    incomplete = [{"solver": r.solver, "status": r.status, "reason": r.reason}
                  for r in results if r.status != "ok"]
    # what the report needs beyond the JSON (compare/output/modes_report.py composes it): the
    # scene's own comparisons (the head's table), the lines of its hooks, the sweep's `told`
    extra, parts = {}, {"comparisons": comparisons}
    growing = growing_modes(results, sc.tolerances_for(params).get("damping", 0.0))
    if growing:                                  # only then: undamped answers stay as they were
        extra["unstable"] = growing
    if sc.explain_frequencies and any(c.verdict == Verdict.DISAGREE for c in comparisons):
        ran = {r.solver: r for r in results}        # the runs above, not run again
        rows, lines_md = sc.explain_frequencies(
            params, comparisons, lambda n, p: ran[n] if p == params and n in ran
            else solvers.modes(sc, solvers.get_solver(n), p), sc.tolerances_for(params))
        extra["explanations"] = rows
        parts["explain"] = lines_md
    crit, obj_cb, drawing = {}, None, None
    if sc.campbell and campbell_sweep and any(
            not sc.campbell.solvers or s.name in sc.campbell.solvers for s in chosen):
        obj_cb, crit, parts["campbell"], drawing, off_sweep = campbell_diagram(
            sc, chosen, params, log, campbell_frame)
        comparisons = comparisons + off_sweep        # the sweep's refusals are the run's
    if threshold and sc.threshold is not None and sc.threshold.active(params):
        extra["threshold"] = run_threshold(sc, params, chosen, solver_names, log)
    if sc.identify and identify:
        rows, lines_md = sc.identify(params, _run_time, solver_names or None)
        if rows:
            extra["identified_from_free_response"] = rows
            more = []
            for row in rows:             # a ring-down fit against the solver's eigenvalues
                eig, fit = identified_against_eigenvalues(sc, row, results)
                if fit is not None:
                    row.update(damped_json(fit))
                    more += sc.verdicts(params, [eig, fit])
            comparisons = comparisons + more
            parts["identify"] = (lines_md, more)
    failed = {m["solver"] for m in incomplete}
    incomplete += [m for m in (obj_cb or {}).get("incomplete", []) if m["solver"] not in failed]
    status, summary = modes_status(comparisons, {"incomplete": incomplete,
                                                 "unpaired_modes": unpaired,
                                                 "campbell": obj_cb,
                                                 "unstable": growing,
                                                 "threshold": extra.get("threshold")})
    return ModesResult(sc, params, results, comparisons, status=status, summary=summary,
                       critical_speeds=crit, campbell=obj_cb, unpaired_modes=unpaired,
                       incomplete=incomplete, extra=extra, parts=parts, drawing=drawing)


def identified_against_eigenvalues(sc: Scene, row: dict, results: list[Modes]):
    """(the solver's eigenvalue run, the fit as `Modes` of "<solver> ring-down") for a row of
    an identification hook that fitted modes to the solver's free response (labels,
    frequencies_hz, damping, whirl; errors in frequency_error_hz / damping_error), the
    verdicts to set them against each other; (None, None) where the row has no such fit or
    the solver's eigenvalues did not run here."""
    eig = next((r for r in results if r.solver == row["solver"] and r.status == "ok"), None)
    if eig is None or row.get("status") != "ok" or "damping" not in row:
        return None, None
    return eig, Modes(scene=sc.name, solver=f"{row['solver']} ring-down",
                      frequencies_hz=np.asarray(row["frequencies_hz"], float),
                      labels=row["labels"], damping=np.asarray(row["damping"], float),
                      whirl=row.get("whirl"),
                      extra={k: np.asarray(row[k], float) for k in ("frequency_error_hz",
                                                                     "damping_error")
                             if k in row})


def modes_status(comparisons, obj) -> tuple[str, str]:
    """The run's status and its one line: `incomplete` where a solver (or its Campbell sweep)
    failed or nothing was compared, else `disagree` on any disagreement, else `inconclusive` on
    any agreement one solver's error bar is too wide to make, else `agree`; the
    unpaired modes and unconfirmed critical speeds counted alongside."""
    line = agree_text(c.verdict for c in comparisons)
    missing = [f"{m['solver']} " + (f"{m['status']} ({m['reason']})" if "status" in m
                                    else m["reason"]) for m in obj["incomplete"]]
    if missing:
        line += "; incomplete: " + ", ".join(missing)
    elif not comparisons:
        line += "; incomplete: nothing compared"
    unpaired = len(obj["unpaired_modes"])
    unconf = sum(len(u) for u in ((obj.get("campbell") or {})
                                  .get("unconfirmed_critical_speeds") or {}).values())
    line += (f"; {unpaired} modes unpaired" if unpaired else "") + (
        f"; {unconf} critical speeds unconfirmed" if unconf else "")
    unstable = sorted({g["solver"] for g in obj.get("unstable", [])})
    if unstable:                       # a finding about the system, not a verdict on solvers
        line += "; unstable (a mode grows) in " + ", ".join(unstable)
    th = obj.get("threshold") or {}
    off = [f"{r['solver']} {kind.replace('_', ' ')} {r['status'] if r['status'] != 'ok' else ''}"
           .strip() for kind in ("eigenvalues", "time_domain") for r in th.get(kind, [])
           if r["status"] != "ok" or not r["agrees"]]
    if off:                            # a threshold not found, or off the closed form
        line += "; threshold off the closed form: " + ", ".join(off)
    # a failed solver outranks every verdict; any verdict worse than inconclusive is disagree
    worst = Verdict.worst(c.verdict for c in comparisons)
    status = (Verdict.INCOMPLETE if missing or not comparisons else
              Verdict.DISAGREE if off or worst.rank > Verdict.INCONCLUSIVE.rank else worst)
    return status, line
