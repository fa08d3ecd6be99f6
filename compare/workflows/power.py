"""Detection power (`xval power SCENE`): what a run's `agree` is worth.

For each continuous physical parameter of the scene and each solver in turn, the smallest
relative change ε* of that parameter, reaching that ONE solver only (through the parameters it
is given, never by editing a leaf), that turns one of the run's agreeing verdicts into
`disagree`. Cheaply: one finite-difference run per (parameter, solver) gives each comparison's
output change per relative change D, the estimate is ε ≈ bound / D (the least over the
comparisons that involve the solver); one run at that ε confirms it; only where it does not
(a response that is not linear in ε) is ε bracketed by factors of 4 and bisected in log scale
to a factor 1.5. The perturbed runs carry the nominal run's own error estimates (an ε of a
parameter does not change what the solver's tighter rerun would say).
"""
from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass

import numpy as np

from .. import solvers
from ..analysis.verdict import Verdict
from ..errors import BadInput
from ..output import progress
from ..results import PowerResult
from .plan import plan

H = 1e-4            # the finite-difference step, relative
EPS_MAX = 1.0       # a change of 100 % that flips nothing: the parameter is not verified
REFINE = 1.5        # bisection stops when the bracket is this factor wide


@dataclass
class Power:
    parameter: str
    solver: str
    epsilon: float | None      # None: no ε up to 1 flips a verdict (or none to flip)
    pair: list | None          # the comparison that flips first: [a, b]
    channel: str | None
    how: str                   # linear | bisection | why there is no ε
    # an estimate's bracket [lo, hi] on ε* (`estimated`); `epsilon` is then hi
    bracket: list | None = None

    def as_dict(self):
        d = asdict(self)
        if self.bracket is None:
            del d["bracket"]
        return d


def _scaled(value, factor):
    return np.asarray(value) * factor if isinstance(value, np.ndarray) else value * factor


class _Study:
    """One plan: the nominal runs (with error estimates) and verdicts, and the runs of one
    solver with one parameter changed (the plan's settings and grid, other parameters)."""

    def __init__(self, pl):
        self.pl, self.sc, self.p, self.chosen = pl, pl.scene, pl.params, pl.solvers
        self.n_runs = 0
        self.nominal = {s.name: self._run(s, self.p, estimate=True) for s in self.chosen}
        self.base = self.compare(self.nominal)

    def _run(self, solver, params, estimate=False):
        self.n_runs += 1 + bool(estimate and self.sc.error_estimate)
        run = self.sc.either(time=self._simulate, modes=self._modes)
        return run(solver, params, estimate and self.sc.error_estimate)

    def _simulate(self, solver, params, estimate):
        return solvers.simulate(self.sc, solver, params, self.pl.settings[solver.name],
                                self.pl.timeout_s, estimate, warm_up=False,
                                t_out=self.pl.t_out)

    def _modes(self, solver, params, estimate):
        return solvers.modes(self.sc, solver, params)

    def compare(self, runs: dict) -> list:
        return self.sc.verdicts(self.p, [runs[s.name] for s in self.chosen])

    def perturbed(self, solver, name, eps):
        """The run of `solver` with parameter `name` × (1 + eps), its nominal error bars."""
        r = self._run(solver, {**self.p, name: _scaled(self.p[name], 1.0 + eps)})
        if self.sc.runs_carry_errors:
            r.errors = self.nominal[solver.name].errors
        return r

    def flipped(self, solver, run) -> list:
        """The comparisons that agreed nominally and disagree with `run` in place of `solver`'s
        (a run that failed flips everything it took part in: missing is never agree; the
        nominal error bars stay, so `inconclusive` would only be the scale moving, no flip)."""
        new = self.compare({**self.nominal, solver.name: run})
        return [(b, n) for b, n in zip(self.base, new)
                if b.verdict == Verdict.AGREE
                and n.verdict not in (Verdict.AGREE, Verdict.INCONCLUSIVE)
                and solver.name in (b.a, b.b)]


def _change(sc, a, b, channel) -> float:
    """max |a − b| of one channel (a time channel, a mode's frequency, or its ζ: "<mode> ζ")."""
    return sc.either(time=_channel_change, modes=_mode_change)(a, b, channel)


def _channel_change(a, b, channel) -> float:
    return float(np.max(np.abs(a.channels[channel] - b.channels[channel])))


def _mode_change(a, b, channel) -> float:
    zeta = channel.endswith(" ζ")
    if zeta and (a.damping is None or b.damping is None):
        return math.inf
    fa, fb = (dict(zip(m.labels, m.damping if zeta else m.frequencies_hz)) for m in (a, b))
    key = channel[:-2] if zeta else channel
    return abs(fa[key] - fb[key]) if key in fa and key in fb else math.inf


def _estimate(study, solver, name):
    """(ε estimate, deciding comparison) from one finite-difference run, or (None, why)."""
    sc = study.sc
    agreeing = [c for c in study.base
                if c.verdict == Verdict.AGREE and solver.name in (c.a, c.b)]
    if not agreeing:
        return None, "no agreeing comparison to flip"
    fd = study.perturbed(solver, name, H)
    if fd.status != "ok":
        return None, f"the {H:g} step itself fails ({fd.status})"
    best = (math.inf, None)
    for c in agreeing:
        d = _change(sc, fd, study.nominal[solver.name], c.channel) / H
        bound = c.tolerance * c.scale
        if d > 0 and bound / d < best[0]:
            best = (bound / d, c)
    return best


def _verdict_at(study, solver, name, eps):
    run = study.perturbed(solver, name, eps)
    return study.flipped(solver, run)


def _bisect(study, solver, name, eps):
    """ε* bracketed from `eps` by factors of 4, then halved in log scale to REFINE."""
    lo, hi = None, None
    e = max(eps, 1e-16)                  # an estimate of 0 would never grow
    while e <= EPS_MAX:
        flips = _verdict_at(study, solver, name, e)
        if flips:
            hi = (e, flips[0][1])
            break
        lo, e = e, e * 4.0
    if hi is None:
        return None, None
    if lo is None:
        e = eps / 4.0
        while e > 1e-16:
            flips = _verdict_at(study, solver, name, e)
            if not flips:
                lo = e
                break
            hi, e = (e, flips[0][1]), e / 4.0
        if lo is None:
            return hi
    while hi[0] / lo > REFINE:
        mid = math.sqrt(lo * hi[0])
        flips = _verdict_at(study, solver, name, mid)
        if flips:
            hi = (mid, flips[0][1])
        else:
            lo = mid
    return hi


def _one(study, solver, name) -> Power:
    if not np.any(np.asarray(study.p[name], float)):
        return Power(name, solver.name, None, None, None,
                     "its value is 0: a relative change leaves it unchanged")
    eps, c = _estimate(study, solver, name)
    if eps is None:
        return Power(name, solver.name, None, None, None, c)
    if not math.isfinite(eps) or c is None:
        return Power(name, solver.name, None, None, None, "no channel responds to it")
    # linear response: the deviation at ε is |dev₀ ± ε·D|, so where the deciding comparison's
    # nominal deviation is at most half its bound and ε flips it, ε* lies in [ε/2, ε]
    if eps <= EPS_MAX and c.max_abs <= 0.5 * c.tolerance * c.scale:
        flips = _verdict_at(study, solver, name, eps)
        if flips:
            n = flips[0][1]
            return Power(name, solver.name, eps, [n.a, n.b], n.channel, "linear")
    found = _bisect(study, solver, name, min(eps, EPS_MAX))
    if found is None or found[0] is None:
        return Power(name, solver.name, None, None, None, f"no ε up to {EPS_MAX:g} flips a "
                     "verdict")
    e, n = found
    return Power(name, solver.name, e, [n.a, n.b], n.channel, "bisection")


def sensitivities(sc, solver, params: dict, settings: dict, t_out, timeout_s=None) -> dict:
    """{parameter: {channel: max|Δy| / H}} from one solver: the physics' response to a relative
    change of each continuous physical parameter, which every solver that agrees with this one
    shares to within that agreement. `H` as `xval power`'s finite difference; a parameter whose
    step fails maps to None."""
    run = lambda p: solvers.simulate(sc, solver, p, settings, timeout_s, False,  # noqa: E731
                                     warm_up=False, t_out=t_out)
    nominal = run(params)
    if nominal.status != "ok":
        return {}
    out = {}
    for q in sc.params:
        if not q.continuous_physical or not np.any(np.asarray(params[q.name], float)):
            continue
        fd = run({**params, q.name: _scaled(params[q.name], 1.0 + H)})
        out[q.name] = (None if fd.status != "ok" else
                       {c: float(np.max(np.abs(fd.channels[c] - nominal.channels[c]))) / H
                        for c in sc.channels})
    return out


def estimated(comparisons: list, sens: dict, by: str) -> list[Power]:
    """ε* per (parameter, solver) from one solver's sensitivities `sens`, without a confirming
    run (the campaign: one run per parameter of its cheapest solver is what a case can pay).
    With a response linear in ε, a comparison with bound B, nominal deviation Δ₀ and output
    change D per relative change cannot flip below (B − Δ₀)/D and must flip at (B + Δ₀)/D:
    `epsilon` is the latter (what the verdicts are sure to detect) over the solver's agreeing
    comparisons, `bracket` both ends; `xval power` confirms with runs."""
    names = list(dict.fromkeys(x for c in comparisons for x in (c.a, c.b)
                               if not (c.formula and x == c.b)))   # a closed form: no solver
    rows = []
    for name, d in sens.items():
        for s in names:
            if d is None:
                rows.append(Power(name, s, None, None, None, f"the {H:g} step fails in {by}"))
                continue
            ends = [((c.tolerance * c.scale - c.max_abs) / d[c.channel],
                     (c.tolerance * c.scale + c.max_abs) / d[c.channel], c)
                    for c in comparisons
                    if c.verdict == Verdict.AGREE and s in (c.a, c.b) and d.get(c.channel)]
            if not ends or min(e[1] for e in ends) > EPS_MAX:
                rows.append(Power(name, s, None, None, None,
                                  f"no agreeing comparison responds to it up to {EPS_MAX:g}"))
                continue
            lo = min(e[0] for e in ends)
            hi, _, c = min((e[1], i, e[2]) for i, e in enumerate(ends))
            rows.append(Power(name, s, hi, [c.a, c.b], c.channel,
                              f"estimated from {by}'s sensitivity, unconfirmed",
                              [max(lo, 0.0), hi]))
    return rows


def summary(rows: list[Power]) -> str:
    """One line: the ε a run detects in any parameter of one solver, the least visible one,
    and what it does not verify."""
    found = [r for r in rows if r.epsilon is not None]
    blind = sorted({r.parameter for r in rows if r.epsilon is None})
    if not found:
        return ("this run detects no change of any physical parameter up to 100 %"
                + (f"; not verified: {', '.join(blind)}" if blind else ""))
    worst = max(found, key=lambda r: r.epsilon)
    best = min(found, key=lambda r: r.epsilon)
    seen = sorted({r.parameter for r in found} - set(blind))
    text = (f"this run detects a {worst.epsilon:.1g} error in any of {', '.join(seen)} of one "
            f"solver (least visible: `{worst.parameter}` in {worst.solver}, "
            f"{worst.epsilon:.1g}; most: `{best.parameter}` in {best.solver}, "
            f"{best.epsilon:.1g})")
    if blind:
        text += f"; not verified for some solver: {', '.join(blind)}"
    return text


def run_power(scene_name: str, overrides: dict, names: list[str],
              parameters: list[str] | None = None, timeout_s: float | None = None,
              log: Callable = print) -> PowerResult:
    """`xval power`: the table parameter × solver → ε*, with the summary line and the cost."""
    t0 = time.perf_counter()
    pl = plan(scene_name, overrides, names, timeout_s=timeout_s)
    sc, chosen = pl.scene, pl.solvers
    physical = [q.name for q in sc.params if q.continuous_physical]
    for name in parameters or []:
        if name not in physical:
            sc.param(name)                    # unknown: BadInput with the list
            raise BadInput(f"{name}: not a continuous physical parameter of {sc.name} "
                           f"(those are: {', '.join(physical)})")
    study = _Study(pl)
    rows = []
    names_ = parameters or physical
    bar = progress.task(f"power {sc.name}", len(names_) * len(chosen),
                        "perturbed parameter × solver")
    for name in names_:
        for s in chosen:
            rows.append(_one(study, s, name))
            bar.advance()
            r = rows[-1]
            log(f"{sc.name}: {name} in {s.name}: "
                + (f"ε* = {r.epsilon:.2g} ({' vs '.join(r.pair)}, {r.channel}; {r.how})"
                   if r.epsilon is not None else f"none ({r.how})"))
    bar.close()
    return PowerResult({"scene": sc.name, "params": {k: overrides[k] for k in overrides},
                        "solvers": [s.name for s in chosen],
                        "nominal": {Verdict.AGREE: Verdict.tally(
                                        c.verdict for c in study.base)[Verdict.AGREE],
                                    "comparisons": len(study.base)},
                        "power": [r.as_dict() for r in rows], "summary": summary(rows),
                        "runs": study.n_runs, "wall_s": round(time.perf_counter() - t0, 3)})
