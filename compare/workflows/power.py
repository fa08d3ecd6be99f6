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
from ..errors import BadInput
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
    pair: str | None           # the comparison that flips first: "a vs b"
    channel: str | None
    how: str                   # linear | bisection | why there is no ε

    def as_dict(self):
        return asdict(self)


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
        if self.sc.is_modes:
            return solvers.modes(self.sc, solver, params)
        return solvers.simulate(self.sc, solver, params, self.pl.settings[solver.name],
                                self.pl.timeout_s, estimate and self.sc.error_estimate,
                                warm_up=False, t_out=self.pl.t_out)

    def compare(self, runs: dict) -> list:
        return self.sc.verdicts(self.p, [runs[s.name] for s in self.chosen])

    def perturbed(self, solver, name, eps):
        """The run of `solver` with parameter `name` × (1 + eps), its nominal error bars."""
        r = self._run(solver, {**self.p, name: _scaled(self.p[name], 1.0 + eps)})
        if not self.sc.is_modes:
            r.errors = self.nominal[solver.name].errors
        return r

    def flipped(self, solver, run) -> list:
        """The comparisons that agreed nominally and disagree with `run` in place of `solver`'s
        (a run that failed flips everything it took part in: missing is never agree)."""
        new = self.compare({**self.nominal, solver.name: run})
        return [(b, n) for b, n in zip(self.base, new)
                if b.verdict == "agree" and n.verdict != "agree"
                and solver.name in (b.a, b.b)]


def _change(sc, a, b, channel) -> float:
    """max |a − b| of one channel (a time channel or a mode's frequency)."""
    if sc.is_modes:
        fa = dict(zip(a.labels, a.frequencies_hz))
        fb = dict(zip(b.labels, b.frequencies_hz))
        return abs(fa[channel] - fb[channel]) if channel in fa and channel in fb else math.inf
    return float(np.max(np.abs(a.channels[channel] - b.channels[channel])))


def _estimate(study, solver, name):
    """(ε estimate, deciding comparison) from one finite-difference run, or (None, why)."""
    sc = study.sc
    agreeing = [c for c in study.base if c.verdict == "agree" and solver.name in (c.a, c.b)]
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
    e = eps
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
            return Power(name, solver.name, eps, f"{n.a} vs {n.b}", n.channel, "linear")
    found = _bisect(study, solver, name, min(eps, EPS_MAX))
    if found is None or found[0] is None:
        return Power(name, solver.name, None, None, None, f"no ε up to {EPS_MAX:g} flips a "
                     "verdict")
    e, n = found
    return Power(name, solver.name, e, f"{n.a} vs {n.b}", n.channel, "bisection")


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
    for name in parameters or physical:
        for s in chosen:
            rows.append(_one(study, s, name))
            r = rows[-1]
            log(f"{sc.name}: {name} in {s.name}: "
                + (f"ε* = {r.epsilon:.2g} ({r.pair}, {r.channel}; {r.how})"
                   if r.epsilon is not None else f"none ({r.how})"))
    return PowerResult({"scene": sc.name, "params": {k: overrides[k] for k in overrides},
                        "solvers": [s.name for s in chosen],
                        "nominal": {"agree": sum(c.verdict == "agree" for c in study.base),
                                    "comparisons": len(study.base)},
                        "power": [r.as_dict() for r in rows], "summary": summary(rows),
                        "runs": study.n_runs, "wall_s": round(time.perf_counter() - t0, 3)})
