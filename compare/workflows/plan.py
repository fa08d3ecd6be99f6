"""One planner under every study: `plan(scene, overrides, solvers, settings, knobs, limits)`
picks the solvers, resolves the parameters, checks the budgets, merges and checks every
solver's settings and builds the output grid — once, before anything runs or is written. A
`Plan` is what a run needs; `Plan.tighter()` is the same run at the settings of each solver's
own error estimate, `Plan.digest()` the key a campaign stores its result under.

Bad input raises `BadInput` with one line; a caller that plans many (a campaign's cases, an
extreme case per solver) prefixes where.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from .. import solvers as registry
from ..errors import BadInput
from ..leafinfo import LeafInfo
from ..scenes import Scene, get_scene
from . import budget
from .digest import job_digest


@dataclass(frozen=True)
class Knobs:
    """The accuracy knobs of `xval run` (`--dt`, `--rtol`, `--integrator`), for every solver:
    `dt` moves an adaptive default to a fixed step, `rtol` a fixed step to an adaptive method
    (`LeafInfo.resolve`)."""
    dt: float | None = None
    rtol: float | None = None
    integrator: str | None = None

    def __post_init__(self):
        if self.dt is not None and self.rtol is not None:
            raise BadInput("--dt and --rtol: give one, not both")


@dataclass(frozen=True)
class Limits:
    """The size of the work allowed (None: the defaults of `budget`). `together`: one run holds
    every solver's output at once (a run compares them); a map's points hold one at a time."""
    max_output_gib: float | None = None
    max_steps: float | None = None
    together: bool = True


@dataclass(frozen=True)
class Plan:
    scene: Scene
    overrides: dict
    params: dict                       # every parameter, resolved and validated
    solvers: tuple                     # Solver objects
    settings: dict                     # solver name -> its settings, checked
    t_out: np.ndarray | None = field(default=None, compare=False)   # time scenes
    timeout_s: float | None = None
    estimate_errors: bool = True

    @property
    def names(self) -> list[str]:
        return [s.name for s in self.solvers]

    def info(self, solver) -> LeafInfo:
        return solver.info(self.scene)

    def only(self, solver) -> Plan:
        """This plan for one of its solvers (a campaign job, a map's runs)."""
        return replace(self, solvers=(solver,), settings={solver.name: self.settings[solver.name]})

    def tighter(self) -> tuple[Plan, dict]:
        """The plan at each solver's tighter settings (those of its own error estimate:
        `Fixed.tighter`, `Adaptive.tighter`) without a further estimate, and per solver
        (factor, how); a solver with no accuracy knob is left out of the plan."""
        tight, how = {}, {}
        for s in self.solvers:
            st, factor, text = self.info(s).tighter(self.settings[s.name])
            how[s.name] = (factor, text)
            if st is not None:
                tight[s.name] = st
        return replace(self, solvers=tuple(s for s in self.solvers if s.name in tight),
                       settings=tight, estimate_errors=False), how

    def digest(self) -> str:
        """The campaign store's key: scene, resolved parameters, solver names, settings (a time
        job's own; none for a frequency case), package versions and the code behind them."""
        if self.t_out is None:
            return job_digest(self.scene, self.params, list(self.solvers), {})
        if len(self.solvers) != 1:
            raise ValueError("a stored time job is one solver's: digest Plan.only(solver)")
        (s,) = self.solvers
        return job_digest(self.scene, self.params, [s], self.settings[s.name])


def names(solvers) -> list[str]:
    """None, one name or a list of names."""
    if solvers is None:
        return []
    if isinstance(solvers, str):
        return [solvers]
    if not all(isinstance(s, str) for s in solvers):
        raise BadInput(f"solvers: expected solver names, got {solvers!r}")
    return list(solvers)


def per_solver_settings(settings: dict | None, chosen) -> dict:
    """`settings` for every solver alike ({"dt": 1e-3}), or per solver keyed by solver name
    ({"exudyn": {...}, "mujoco": {...}}, as campaign cases write them); a dict whose keys are
    all solver names is read per solver."""
    names_ = [s.name for s in chosen]
    if not settings:
        return {n: {} for n in names_}
    if not isinstance(settings, dict):
        raise BadInput(f"settings: expected a dict, got {settings!r}")
    keyed = [k for k in settings if k in registry.REGISTRY]
    if keyed and len(keyed) < len(settings):
        raise BadInput(f"settings: mixes solver names ({', '.join(keyed)}) with setting names "
                       f"({', '.join(k for k in settings if k not in registry.REGISTRY)}); give "
                       "one dict for all solvers or one per solver")
    if not keyed:
        return {n: dict(settings) for n in names_}
    for k, v in settings.items():
        if k not in names_:
            raise BadInput(f"settings: {k!r} is not among the solvers run "
                           f"({', '.join(names_)})")
        if not isinstance(v, dict):
            raise BadInput(f"settings: {k}: expected a dict of settings, got {v!r}")
    return {n: dict(settings.get(n, {})) for n in names_}


def plan(scene: Scene | str, overrides: dict | None = None, solvers=None,
         settings: dict | None = None, knobs: Knobs = Knobs(), limits: Limits = Limits(), *,
         timeout_s: float | None = None, estimate_errors: bool = True) -> Plan:
    """Everything a run needs, checked in this order: scene, solvers (default: all of the
    scene's), the output's size (before the grid is allocated), parameters, the requested step
    against the step budget, each solver's settings against the grid, each solver's steps."""
    sc = scene if isinstance(scene, Scene) else get_scene(scene)
    overrides = dict(overrides or {})
    chosen = registry.pick(sc, names(solvers))
    extra = per_solver_settings(settings, chosen)
    if not sc.has_output_grid:                   # nothing to budget or set on a grid
        return Plan(sc, overrides, sc.resolve(overrides), tuple(chosen),
                    {s.name: {} for s in chosen}, None, timeout_s, estimate_errors)
    budget.check_output(sc, overrides, len(chosen) if limits.together else 1,
                        limits.max_output_gib)
    params = sc.resolve(overrides)
    budget.check_dt(params, knobs.dt, limits.max_steps)
    t_out = sc.output_grid(params)
    checked = {}
    for s in chosen:
        checked[s.name] = registry.settings_for(s, sc, knobs.dt, knobs.rtol, knobs.integrator,
                                                extra=extra[s.name], t_out=t_out)
        budget.check_steps(s.name, s.info(sc), params, checked[s.name], limits.max_steps)
    return Plan(sc, overrides, params, tuple(chosen), checked, t_out, timeout_s,
                estimate_errors)
