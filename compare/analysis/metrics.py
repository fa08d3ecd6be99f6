"""Comparisons as values: trajectory deviations, event measures, energy, frequency matching.

Each comparison is computed once, as a dataclass, and rendered by the JSON output, the report
and the recording alike.
"""
from dataclasses import asdict, dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment

from ..atomic import num
from .step_errors import pair_error, shares_scheme
from .trajectory import Modes, Trajectory
from .verdict import Verdict


@dataclass(frozen=True)
class Comparison:
    """One pair, one channel. The verdict weighs the deviation against what explains it: the
    two solvers' own error estimates (from tighter reruns) plus the scene's modelling allowance.
    `tolerance` is that bound relative to the scale."""
    a: str
    b: str
    channel: str
    max_abs: float
    rms: float
    max_rel: float          # max |Δ| / scale
    scale: float            # the channel's scale: max |value| over both runs
    tolerance: float        # (error_estimate + allowance) / scale: the bound that decided
    verdict: Verdict        # agree | inconclusive | disagree | incomplete | skipped (from str)
    decided_by: str         # the number that decided, in words
    deviation: float = np.nan        # max |Δ| (SI), = max_abs
    error_estimate: float | None = None   # max (err_a + err_b) over the run (SI), if estimated
    allowance: float = np.nan        # the scene's modelling allowance (SI)
    # b is a closed form (its label), not a solver: `a` judged against it (`against_formula`)
    formula: bool = False

    def __post_init__(self):            # read back from JSON: the string becomes the type
        object.__setattr__(self, "verdict", Verdict(self.verdict))

    @property
    def ratio(self) -> float:
        """Deviation over the bound that decided (≤ 1: agree)."""
        bound = self.tolerance * self.scale
        return self.deviation / bound if bound > 0 else np.inf

    @property
    def shown(self) -> str:
        """The verdict as tables print it: `agree (marginal)` above MARGINAL of the bound
        (`Verdict.shown`)."""
        return self.verdict.shown(self.ratio)

    def as_dict(self):
        return {**asdict(self), "ratio": float(self.ratio), "shown": self.shown}


# An agreement is only as sharp as the wider of the two solvers' own error bars: where that bar
# exceeds both the allowance and this fraction of the channel's scale (of the frequency, for a
# mode), the pair would agree with almost anything, so the verdict is `inconclusive`. Measured
# over the default campaign's cases (316 comparisons): max(err_a, err_b)/scale ≤ 8.2e-4
# (spinning-shaft whirl 5, MuJoCo's bar; median 3e-7), 12x below; the rotor at --dt 0.05
# (torque 3.2, 2 s) reaches 3.1 % on |ω| and 86 % on the tilt.
INCONCLUSIVE_FRACTION = 1e-2


def too_wide(errors: dict, allow: float, scale: float, unit: str = "") -> str | None:
    """Why an agreement is `inconclusive`, in words: the wider of the two solvers' own error
    bars ({solver: max error, SI}) exceeds `allow` and INCONCLUSIVE_FRACTION of `scale`; else
    None."""
    solver, e = max(errors.items(), key=lambda kv: kv[1])
    if not (e > allow and e > INCONCLUSIVE_FRACTION * scale):
        return None
    return (f"{solver}'s own error bar {e:.2g}{unit} ({100 * e / scale:.2g} % of scale) "
            f"> {100 * INCONCLUSIVE_FRACTION:g} % : inconclusive")


def judged(d: float, bound: float, errors: dict | None, allow: float, scale: float,
           unit: str = "") -> tuple[Verdict, str | None]:
    """(verdict, the inconclusive sentence or None): `disagree` beyond the bound, else
    `inconclusive` where one solver's error bar is too wide to tell (`too_wide`), else
    `agree`."""
    if not d <= bound:
        return Verdict.DISAGREE, None
    wide = too_wide(errors, allow, scale, unit) if errors else None
    return (Verdict.INCONCLUSIVE if wide else Verdict.AGREE), wide


def ratio_text(r: float) -> str:
    """A deviation/bound ratio with two significant digits (3e-10 vs 2.6e-10 hid a 12 % miss)."""
    return f"{r:.2g}" if np.isfinite(r) else "—"


def deviation(a: Trajectory, b: Trajectory, channel: str,
              allowance: float | tuple, power_scale: float | None = None) -> Comparison:
    """Deviation of two trajectories on their common output grid, with the verdict.

    `allowance`: relative to the channel's scale, ("abs", bound) in SI units, or
    ("rel+abs", rel, floor): rel · scale + floor (a channel that stays near zero, like the
    tilt of an upright rotor, needs an absolute floor). The solvers' own errors come from
    `Trajectory.errors` where estimated, summed — or, for two runs of one scheme, the error of
    their difference (`step_errors.pair_error`). `power_scale`: what an error bar is too wide
    against (`too_wide`) where the channel's own values are not — a residual that stays at
    zero, as an energy balance, is judged against the energy it balances; default the
    channel's scale."""
    if a.status != "ok" or b.status != "ok":
        why = ", ".join(f"{t.solver} {t.status}" for t in (a, b) if t.status != "ok")
        tol = allowance if not isinstance(allowance, tuple) else allowance[1]
        return Comparison(a.solver, b.solver, channel, np.nan, np.nan, np.nan, np.nan,
                          tol, Verdict.SKIPPED, f"not compared: {why}")
    if len(a.t) != len(b.t) or np.max(np.abs(a.t - b.t)) > 1e-9 * max(a.t[-1], 1.0):
        raise ValueError("trajectories of one run must share the output grid")
    x, y = a.channels[channel], b.channels[channel]
    d = np.abs(x - y)
    scale = float(max(np.max(np.abs(x)), np.max(np.abs(y)), 1e-300))
    max_abs = float(np.max(d))
    rel = max_abs / scale
    allow = allowance_si(allowance, scale)
    ea, eb = a.errors.get(channel), b.errors.get(channel)
    both = ea is not None and eb is not None
    shared = both and shares_scheme(a, b, channel)
    err = float(np.nanmax(pair_error(a, b, channel))) if both else None
    bound = allow + (err or 0.0)
    unit = getattr(channel, "unit", "")
    verdict, wide = judged(max_abs, bound, {a.solver: float(np.nanmax(ea)),
                                            b.solver: float(np.nanmax(eb))} if both else None,
                           allow, max(scale, power_scale or 0.0), f" {unit}" if unit else "")
    why = (f"max|Δ| = {max_abs:.2e} (at t = {a.t[np.argmax(d)]:.4g} s) "
           f"{'>' if verdict == Verdict.DISAGREE else '≤'} "
           + (f"error estimates {err:.1e}{' (one scheme: of a − b)' if shared else ''} "
              f"+ allowance {allow:.1e}" if err is not None
              else f"allowance {allow:.1e} (no error estimate)")
           + f" (Δ/bound {ratio_text(max_abs / bound if bound > 0 else np.inf)})")
    why = f"{wide}; {why}" if wide else why
    failed = [t for t in (a, b) if t.stats.get("error_estimate_failed")]
    if verdict == Verdict.DISAGREE and failed:
        # beyond the allowance alone, with one error bar missing: nothing is known
        verdict = Verdict.INCOMPLETE
        why = "; ".join(f"{t.solver}'s error estimate failed ({t.stats['error_estimate_failed']})"
                        for t in failed) + f": not judged; {why}"
    return Comparison(a.solver, b.solver, channel, max_abs, float(np.sqrt(np.mean(d**2))), rel,
                      scale, bound / scale, verdict, why, max_abs, err, allow)


def against_formula(tr: Trajectory, channel: str, label: str, values, allowance) -> Comparison:
    """A solver's channel against a closed form's `values` on its grid: |Δ| ≤ the formula's own
    error `allowance` (SI: what the formula neglects of that solver's model) + the solver's own
    error estimate. `allowance` a string: why the formula states no error there (outside its
    domain) — `inconclusive`, never agree."""
    if tr.status != "ok":
        return Comparison(tr.solver, label, channel, np.nan, np.nan, np.nan, np.nan, np.nan,
                          Verdict.SKIPPED, f"not compared: {tr.solver} {tr.status}",
                          formula=True)
    x, y = tr.channels[channel], np.asarray(values, float)
    d = np.abs(x - y)
    scale = float(max(np.max(np.abs(x)), np.max(np.abs(y)), 1e-300))
    max_abs = float(np.max(d))
    at = f"(at t = {tr.t[np.argmax(d)]:.4g} s)"
    e = tr.errors.get(channel)
    err = float(np.nanmax(e)) if e is not None else None
    unit = getattr(channel, "unit", "")
    if isinstance(allowance, str):
        return Comparison(tr.solver, label, channel, max_abs, float(np.sqrt(np.mean(d**2))),
                          max_abs / scale, scale, np.nan, Verdict.INCONCLUSIVE,
                          f"max|Δ| = {max_abs:.2e} {at}; {label} states no error here: "
                          f"{allowance}", max_abs, err, np.nan, True)
    bound = allowance + (err or 0.0)
    verdict, wide = judged(max_abs, bound, {tr.solver: err} if err is not None else None,
                           allowance, scale, f" {unit}" if unit else "")
    why = (f"max|Δ| = {max_abs:.2e} {at} {'>' if verdict == Verdict.DISAGREE else '≤'} "
           + (f"error estimate {err:.1e} + " if err is not None else "")
           + f"{label}'s own error {allowance:.1e}"
           + ("" if err is not None else " (no error estimate)")
           + f" (Δ/bound {ratio_text(max_abs / bound if bound > 0 else np.inf)})")
    return Comparison(tr.solver, label, channel, max_abs, float(np.sqrt(np.mean(d**2))),
                      max_abs / scale, scale, bound / scale, verdict,
                      f"{wide}; {why}" if wide else why, max_abs, err, allowance, True)


def allowance_si(allowance: float | tuple, scale: float) -> float:
    if not isinstance(allowance, tuple):
        return allowance * scale
    if allowance[0] == "abs":
        return allowance[1]
    return allowance[1] * scale + allowance[2]


def allowance(tolerances: dict, a: str, b: str, channel: str):
    """The modelling allowance of the pair (a, b) on `channel`: the pair's own ("by_pair",
    keyed "a|b" in either order), else that of the first of its solvers with one ("by_solver":
    e.g. the paper's own, non-conservative model), else the channel's."""
    pairs, solvers = tolerances.get("by_pair", {}), tolerances.get("by_solver", {})
    found = [pairs.get(k, {}).get(channel) for k in (f"{a}|{b}", f"{b}|{a}")]
    found += [solvers.get(s, {}).get(channel) for s in (a, b)]
    return next((x for x in found if x is not None), tolerances[channel])


def allowance_channels(tolerances: dict) -> list[str]:
    """The channels `tolerances` gives allowances for (not its "by_pair", "by_solver",
    "frequency_by_…" tables, "frequency_one_model" pairs, nor "wider": pair -> the scene's
    reason for a wider one)."""
    return [c for c in tolerances
            if not c.startswith(("by_", "frequency_by_", "damping_by_", "frequency_one_model",
                                 "wider"))]


def pairwise(trajectories: list[Trajectory], tolerances: dict,
             power_scales: dict | None = None) -> list[Comparison]:
    """Every pair on every channel of `tolerances` (channel -> allowance; `allowance` reads
    the pair's own from "by_pair" / "by_solver"); `power_scales`: channel -> `deviation`'s
    power_scale."""
    return [deviation(a, b, ch, allowance(tolerances, a.solver, b.solver, ch),
                      (power_scales or {}).get(ch))
            for i, a in enumerate(trajectories) for b in trajectories[i + 1:]
            for ch in allowance_channels(tolerances)]


def energy_residual(traj: Trajectory, channel: str = "energy_balance") -> float | None:
    """Largest |E(t) − E(0)| in joules over the finite part of the run."""
    e = traj.channels.get(channel)
    if e is None:
        return None
    e = e[np.isfinite(e)]
    return float(np.max(np.abs(e - e[0]))) if len(e) else None


# --- event measures: meaningful when phases drift ------------------------------------------

def first_crossing(t: np.ndarray, x: np.ndarray, level: float) -> float | None:
    """Time x first reaches `level` from below (linear interpolation), or None."""
    above = np.nonzero(x >= level)[0]
    if len(above) == 0 or above[0] == 0:
        return None
    i = above[0]
    return float(t[i - 1] + (level - x[i - 1]) * (t[i] - t[i - 1]) / (x[i] - x[i - 1]))


def peak(t: np.ndarray, x: np.ndarray) -> tuple[float, float]:
    """(value, time) of the maximum, refined by a parabola through the three samples."""
    i = int(np.nanargmax(x))
    if 0 < i < len(x) - 1:
        y0, y1, y2 = x[i - 1], x[i], x[i + 1]
        den = y0 - 2 * y1 + y2
        if den < 0:
            off = 0.5 * (y0 - y2) / den
            return float(y1 - 0.25 * (y0 - y2) * off), float(t[i] + off * (t[1] - t[0]))
    return float(x[i]), float(t[i])


def window_mean(t: np.ndarray, x: np.ndarray, t0: float, t1: float) -> float | None:
    w = (t >= t0) & (t <= t1)
    return float(np.mean(x[w])) if w.any() else None


# --- convergence order ---------------------------------------------------------------------

def observed_order(steps, errors) -> float:
    """Least-squares slope of log(error) against log(step)."""
    steps, errors = np.asarray(steps, float), np.asarray(errors, float)
    ok = errors > 0
    return float(np.polyfit(np.log(steps[ok]), np.log(errors[ok]), 1)[0])


# --- frequencies ---------------------------------------------------------------------------

def family(label: str) -> str:
    """A mode's family and kind, its label without the number: "flap cyclic 2" → "flap
    cyclic"; a label without one is its own family."""
    head, _, tail = label.rpartition(" ")
    return head if head and tail.isdigit() else label


def match_modes(fa: list, la: list, fb: list, lb: list, why: dict | None = None
                ) -> list[tuple[int, int]]:
    """Pair the modes of two solvers: within each family both name (`family`), by the least
    total |Δf| — a label's number counts the family's modes that made the solver's list, so
    two lists that hold different ones number them differently (helicopter-hover, `xval
    calibrate --seed 2026` set 6: a coupled fuselage–rotor root named "flap cyclic 2" by MuJoCo
    and "fuselage 2" by Exudyn made Exudyn's 15.66 Hz mode its flap cyclic 2, against mstmm's
    4.45 Hz) —, the rest by nearest value, accepted only when it is nearer than half the gap to
    any other candidate, so two close modes are never both paired with one, and within a
    factor 2 of each other (the last two left over are no pair for being alone: mstmm's 15.68
    Hz flap differential 2 met MuJoCo's 0.36 Hz fuselage mode so), and never a mode whose twin
    is past the other's list (`_past_list`). Returns [(i, j)]
    index pairs. `why`, if given, receives for each mode left unpaired ("a", i) / ("b", j) the
    reason, in words."""
    pairs, used_a, used_b = [], set(), set()
    for fam in {family(n) for n in la if n} & {family(n) for n in lb if n}:
        ia = [i for i, n in enumerate(la) if n and family(n) == fam]
        ib = [j for j, n in enumerate(lb) if n and family(n) == fam]
        cost = np.abs(np.subtract.outer([fa[i] for i in ia], [fb[j] for j in ib]))
        for r, c in zip(*linear_sum_assignment(cost)):
            pairs.append((ia[r], ib[c]))
            used_a.add(ia[r])
            used_b.add(ib[c])
    cand = sorted((abs(fa[i] - fb[j]), i, j) for i in range(len(fa)) for j in range(len(fb))
                  if i not in used_a and j not in used_b)
    refused = {}                      # the first (nearest) candidate refused, per mode
    past = {("a", i): _past_list(fa[i], _label(la, i), la, fb, lb) for i in range(len(fa))
            if i not in used_a}
    past.update({("b", j): _past_list(fb[j], _label(lb, j), lb, fa, la) for j in range(len(fb))
                 if j not in used_b})
    for d, i, j in cand:
        if i in used_a or j in used_b:
            continue
        others = [(abs(fa[i] - fb[k]), "b", k) for k in range(len(fb))
                  if k != j and k not in used_b]
        others += [(abs(fa[k] - fb[j]), "a", k) for k in range(len(fa))
                   if k != i and k not in used_a]
        if d > 0.5 * max(abs(fa[i]), abs(fb[j])):    # not within a factor 2: no twin
            refused.setdefault(("a", i), f"nearest by frequency: {_mode(lb, j)} of b at "
                               f"{fb[j]:.10g} Hz, not within a factor 2 of it")
            refused.setdefault(("b", j), f"nearest by frequency: {_mode(la, i)} of a at "
                               f"{fa[i]:.10g} Hz, not within a factor 2 of it")
        elif all(d < 0.5 * o for o, _, _ in others):
            if past[("a", i)] or past[("b", j)]:
                for key in (("a", i), ("b", j)):
                    if past[key]:
                        refused.setdefault(key, past[key])
                continue
            pairs.append((i, j))
            used_a.add(i)
            used_b.add(j)
        else:
            o, side, k = min(others)
            rival = f"{_mode(lb if side == 'b' else la, k)} of {side} at " \
                    f"{fb[k] if side == 'b' else fa[k]:.10g} Hz"
            text = (f"nearest by frequency: {{}} ({d:.2g} Hz away), but {rival} is "
                    f"{o:.2g} Hz from the pair (pairing needs under half of it)")
            refused.setdefault(("a", i), text.format(f"{_mode(lb, j)} of b at {fb[j]:.10g} Hz"))
            refused.setdefault(("b", j), text.format(f"{_mode(la, i)} of a at {fa[i]:.10g} Hz"))
    if why is not None:
        for side, mine, theirs, f in (("a", la, lb, fb), ("b", lb, la, fa)):
            used = used_a if side == "a" else used_b
            for i in sorted(set(range(len(mine))) - used):
                name = _label(mine, i)
                label = ("" if not name else f"label {name!r} not among the other's; "
                         if family(name) not in {family(n) for n in theirs if n} else
                         f"the other lists fewer {family(name)!r} modes, each nearer its own; ")
                why[(side, i)] = label + (refused.get((side, i)) or (
                    "no counterpart: every mode of the other solver is paired closer"
                    if len(f) else "the other solver returned no modes"))
    return sorted(pairs)


def _past_list(f: float, label: str, labels: list, other: list, other_labels: list
               ) -> str | None:
    """Why a left-over mode pairs with none of the other solver's, or None: it lies above the
    other's highest mode, in a family the other lists fewer of — its twin is past the other's
    list (rotating-beam, `xval calibrate --seed 5150` set 8: the engines' fifth mode is lag 1
    at 46.57 Hz, mstmm's flap 4 at 46.91 Hz, each one's other mode sixth, and the two met as a
    leftover pair 0.7 % apart)."""
    if not label or not len(other) or f <= max(other):
        return None
    fam = family(label)
    if sum(family(n) == fam for n in other_labels if n) >= sum(
            family(n) == fam for n in labels if n):
        return None
    return (f"above the other's highest mode ({max(other):.10g} Hz), in a family it lists "
            f"fewer of: its twin is past the other's list")


def _label(labels, i) -> str:
    """Mode i's label, "" where the solver gives none."""
    return labels[i] if i < len(labels) else ""


def _mode(labels, i):
    return repr(labels[i]) if i < len(labels) and labels[i] else f"mode {i + 1}"


def unpaired_modes(results: list[Modes], tolerances: dict | None = None) -> list[dict]:
    """Per pair of solvers that ran, each mode `match_modes` leaves unpaired, with why: listed,
    never silently dropped from the comparison (a pair compared root by root, `by_root`, has
    none)."""
    out = []
    ok = [r for r in results if r.status == "ok"]
    for n, a in enumerate(ok):
        for b in ok[n + 1:]:
            if by_root(a, b, tolerances):
                continue
            why: dict = {}
            match_modes(list(a.frequencies_hz), a.labels, list(b.frequencies_hz), b.labels,
                        why)
            for (side, i), reason in sorted(why.items()):
                m = a if side == "a" else b
                lab = _label(m.labels, i)
                out.append({"a": a.solver, "b": b.solver, "solver": m.solver,
                            "mode": lab or f"mode {i + 1}",
                            "frequency_hz": float(m.frequencies_hz[i]), "reason": reason})
    return out


def frequency_errors(m: Modes, linearisation: bool = False) -> np.ndarray | None:
    """A solver's own error estimate per mode (Hz), where its leaf gives one in
    extra["frequency_error_hz"] (a Richardson change N → 2N, a mesh change, a root tolerance,
    round-off), else None; with `linearisation`, only the part a second solver of the same
    discrete model does not share (extra["linearisation_error_hz"]: its finite-difference
    step), else None."""
    e = m.extra.get("linearisation_error_hz" if linearisation else "frequency_error_hz")
    if e is None:
        return None
    e = np.abs(np.asarray(e, float))
    return e if e.shape == np.shape(m.frequencies_hz) else None


def damping_allowance(tolerances: dict, a: str, b: str) -> float:
    """The pair's allowance on ζ (absolute): "damping", raised by a "damping_by_solver" entry
    of either solver."""
    by = tolerances.get("damping_by_solver", {})
    return max([tolerances["damping"]] + [by.get(s, 0.0) for s in (a, b)])


def frequency_allowance(tolerances: dict, a: str, b: str, mode: str | None = None) -> float:
    """The relative allowance of the pair (a, b) on frequencies: the pair's own
    ("frequency_by_pair", "a|b" in either order), else the larger of "frequency" and a
    "frequency_by_solver" entry of its solvers (e.g. a rigid-segment chain whose sections
    carry rotary inertia the Euler–Bernoulli model has not) — for a `mode` (label) that the
    solver's "frequency_by_mode" entry ({label: allowance}) names, that mode's own instead."""
    pairs = tolerances.get("frequency_by_pair", {})
    for k in (f"{a}|{b}", f"{b}|{a}"):
        if k in pairs:
            return pairs[k]
    by_solver = tolerances.get("frequency_by_solver", {})
    by_mode = tolerances.get("frequency_by_mode", {})

    def of(s):
        own = by_mode.get(s) or {}
        return own[mode] if mode in own else by_solver.get(s, 0.0)
    return max([tolerances["frequency"]] + [of(s) for s in (a, b)])


# A leaf's oscillating roots (Hz, ascending) before it shifts them into the frame it reports
# in and names them (the helicopter engines: fixed-frame roots, each shown on the blades by ±Ω
# as its name says), with "roots_error_hz" and "roots_linearisation_error_hz" beside them
ROOTS = "roots_hz"


def by_root(a: Modes, b: Modes, tolerances: dict | None) -> bool:
    """Are two solvers compared root by root (`ROOTS`, in order), not mode by mode? Where both
    give their roots and the scene lists the pair as one discrete model ("frequency_one_model"):
    one model has one set of roots, while a root whose shape mixes two families is named — and
    so shifted into the rotor frame, or left out of the first n — either way by two
    linearisations of it (helicopter-hover, calibration set 5: the 2.70504 Hz root, 'fuselage
    2' for Exudyn and a flap cyclic at 6.26579 Hz for MuJoCo; at set 4 one engine names two
    roots differently from one process to the next)."""
    one_model = set((tolerances or {}).get("frequency_one_model", ()))
    return (bool({f"{a.solver}|{b.solver}", f"{b.solver}|{a.solver}"} & one_model)
            and all(ROOTS in m.extra for m in (a, b)))


def root_comparisons(a: Modes, b: Modes, tolerances: dict) -> list[Comparison]:
    """Two solvers of one discrete model root by root in ascending order (channel "root k"):
    |Δ| ≤ the pair's allowance + what each one's linearisation adds to that root, as for its
    modes (`frequency_comparisons`). A pair of roots closer than their difference may swap
    places: then each is compared with its twin, no further off."""
    ra, rb = (np.asarray(m.extra[ROOTS], float) for m in (a, b))
    ea, eb = (m.extra.get("roots_linearisation_error_hz") for m in (a, b))
    tol = frequency_allowance(tolerances, a.solver, b.solver)
    out = []
    for k in range(min(len(ra), len(rb))):
        fa, fb = ra[k], rb[k]
        d, scale = abs(fa - fb), max(abs(fa), abs(fb), 1e-300)
        own = None if ea is None or eb is None else {a.solver: float(ea[k]),
                                                     b.solver: float(eb[k])}
        err = sum(own.values()) if own else 0.0
        bound = tol * scale + err
        v, wide = judged(d, bound, own, tol * scale, scale, " Hz")
        why = (f"roots {fa:.8g} vs {fb:.8g} Hz: |Δ| {d:.2e} "
               f"{'>' if v == Verdict.DISAGREE else '≤'} linearisation error estimates "
               f"{err:.1e} + allowance {tol * scale:.1e} Hz (one discrete model: its "
               "discretisation error cancels)")
        out.append(Comparison(a.solver, b.solver, f"root {k + 1}", d, d, d / scale, scale,
                              bound / scale, v, f"{wide}; {why}" if wide else why, d,
                              err if own else None, tol * scale))
    return out


# A first-order estimate s of a model difference (relative) as an allowance: what it neglects
# grows as s² (the blade's rotary inertia: 1.32–1.35 s² left on lag 1 after the predicted
# shift, compare/scenes/mstmm.py), and ×2 for the mode shape's own change with it
FIRST_ORDER_SAFETY, SECOND_ORDER = 2.0, 2.0


def first_order_allowance(s):
    """The allowance of a model difference whose first-order estimate is `s` (relative)."""
    return FIRST_ORDER_SAFETY * (s + SECOND_ORDER * s**2)


def model_allowance(m: Modes, other: Modes, i: int) -> float:
    """The relative allowance of run `m`'s mode i against a solver whose model lacks a
    feature of m's: per feature m names in extra["model_differences"] ({feature: per-mode
    shift in Hz that it makes, estimated by m itself — the sections' rotary inertia of a
    rigid-segment chain, the axial flexibility of the paper's beams}) that `other` does not
    name too, `first_order_allowance` of that mode's shift, summed; 0 where there is none."""
    theirs = other.extra.get("model_differences") or {}
    f = abs(m.frequencies_hz[i])
    return sum(first_order_allowance(abs(float(v[i])) / f)
               for name, v in (m.extra.get("model_differences") or {}).items()
               if name not in theirs and i < len(v) and np.isfinite(v[i]))


def models_allowance(a: Modes, b: Modes, ia: int, ib: int) -> float:
    """What the two models' own named differences allow for the pair's modes ia and ib
    (`model_allowance` of each against the other, added: independent features)."""
    return model_allowance(a, b, ia) + model_allowance(b, a, ib)


def frequency_comparisons(results: list[Modes], tolerances: dict) -> list[Comparison]:
    """Every pair of solvers, mode by mode, as Comparisons (channel = the mode's label), each
    pair against its `frequency_allowance` (of the mode) from the scene's `tolerances`. As for time
    channels, the verdict is |Δ| ≤ allowance + both solvers' error estimates
    (`frequency_errors`), where both give one — except for a pair listed in
    "frequency_one_model" ("a|b"): two solvers of one discrete model (the same segments,
    springs and extrapolation) share its discretisation error, which cancels in their
    difference; their estimates would only hide a difference between them, so such a pair is
    judged against its own allowance plus only what each one's linearisation adds, where both
    give it — root by root where both give their roots (`by_root`)."""
    out = []
    ok = [r for r in results if r.status == "ok"]
    one_model = set(tolerances.get("frequency_one_model", ()))
    for i, a in enumerate(ok):
        for b in ok[i + 1:]:
            if by_root(a, b, tolerances):
                out += root_comparisons(a, b, tolerances)
                continue
            shared = bool({f"{a.solver}|{b.solver}", f"{b.solver}|{a.solver}"} & one_model)
            for ia, ib in match_modes(list(a.frequencies_hz), a.labels,
                                      list(b.frequencies_hz), b.labels):
                # a mode's own allowance where both name it alike, else the solvers' largest;
                # a model difference one of them estimates for this mode itself, if larger
                same = a.labels[ia] if a.labels[ia] and a.labels[ia] == b.labels[ib] else None
                tol = max(frequency_allowance(tolerances, a.solver, b.solver, same),
                          models_allowance(a, b, ia, ib))
                fa, fb = a.frequencies_hz[ia], b.frequencies_hz[ib]
                d = abs(fa - fb)
                scale = max(abs(fa), abs(fb), 1e-300)
                ea, eb = frequency_errors(a, shared), frequency_errors(b, shared)
                own = (None if ea is None or eb is None
                       else {a.solver: float(ea[ia]), b.solver: float(eb[ib])})
                err = sum(own.values()) if own else None
                bound = tol * scale + (err or 0.0)
                v, wide = judged(d, bound, own, tol * scale, scale, " Hz")
                cancels = "one discrete model: its discretisation error cancels"
                why = (f"{fa:.8g} vs {fb:.8g} Hz: |Δ| {d:.2e} "
                       f"{'>' if v == Verdict.DISAGREE else '≤'} "
                       + (f"{'linearisation ' if shared else ''}error estimates {err:.1e} + "
                          f"allowance {tol * scale:.1e} Hz" + (f" ({cancels})" if shared else "")
                          if err is not None else f"allowance {tol * scale:.1e} Hz ("
                          + (cancels if shared else "no error estimate") + ")"))
                out.append(Comparison(
                    a.solver, b.solver, a.labels[ia] or f"mode {ia + 1}", d, d, d / scale,
                    scale, bound / scale, v, f"{wide}; {why}" if wide else why, d, err,
                    tol * scale))
    return out


def damping_comparisons(results: list[Modes], tolerances: dict) -> list[Comparison]:
    """Every pair of solvers that give damping ratios, mode by mode (paired as the
    frequencies), as Comparisons on ζ (channel "<label> ζ"). ζ is already a fraction of
    critical damping, so its difference is compared as it is (scale 1): |Δζ| ≤ the allowance
    ("damping", raised by a "damping_by_solver" entry of either solver) + both solvers' error
    estimates (extra["damping_error"]) where both give one."""
    out = []
    ok = [r for r in results if r.status == "ok" and r.damping is not None]
    for i, a in enumerate(ok):
        for b in ok[i + 1:]:
            tol = damping_allowance(tolerances, a.solver, b.solver)
            ea, eb = (m.extra.get("damping_error") for m in (a, b))
            for ia, ib in match_modes(list(a.frequencies_hz), a.labels,
                                      list(b.frequencies_hz), b.labels):
                za, zb = float(a.damping[ia]), float(b.damping[ib])
                d = abs(za - zb)
                own = (None if ea is None or eb is None
                       else {a.solver: float(abs(ea[ia])), b.solver: float(abs(eb[ib]))})
                err = sum(own.values()) if own else None
                bound = tol + (err or 0.0)
                v, wide = judged(d, bound, own, tol, 1.0)
                why = (f"ζ {num(za, '.8g')} vs {num(zb, '.8g')}: |Δ| {d:.2e} "
                       f"{'>' if v == Verdict.DISAGREE else '≤'} "
                       + (f"error estimates {err:.1e} + allowance {tol:.1e}" if err is not None
                          else f"allowance {tol:.1e} (no error estimate)"))
                out.append(Comparison(
                    a.solver, b.solver, f"{a.labels[ia] or f'mode {ia + 1}'} ζ", d, d, d, 1.0,
                    bound, v, f"{wide}; {why}" if wide else why, d, err, tol))
    return out
