"""A leaf as the rest of xval sees it — read once per leaf module, the only place that reads a
leaf's attributes (`DEFAULT_SETTINGS`, `INTEGRATORS`, `ADAPTIVE`, `AUTO_DT`, `MODES_SETTINGS`,
`ORDERS`, `KNOBS`, `KNOB_LIMITS`, `KNOB_HOLDS`, `KNOB_INTEGRATORS`, `COARSER_DT`, `JITTER_PROBE`,
`check_settings`, `regimes`, `unbalance_response`) — and the accuracy knobs as types: `Fixed(dt)` or
`Adaptive(rtol, atol)`, each with its tighter setting, its step count and its ladder (the shape
of scipy's `OdeSolver`, which carries its own order, and diffrax's step-size controllers); a leaf's
other discretisation knobs (`KNOBS`: a finite-difference step) as `Knob`s, each varied by the
error estimate on its own.
"""
from __future__ import annotations

import importlib
from dataclasses import dataclass, field
from types import ModuleType

import numpy as np

from .contract import canonical_integrator, merge_settings
from .errors import BadInput

# the order a method should show (a leaf may declare its own `ORDERS`); the bench flags an
# observed convergence order below it
ORDERS = {"euler": 1, "explicit_euler": 1, "midpoint": 2, "linacc": 2, "rk4": 4, "rk44": 4,
          "rk67": 6, "generalized_alpha": 2, "trapezoidal": 2, "imr": 2, "implicitfast": 1,
          "implicit": 1}
RTOLS = tuple(10.0 ** -k for k in range(1, 14))     # the tolerance ladder, 1e-1 … 1e-13
START_RTOL = 1e-6
# a map point's first, cheap run: a tolerance 1e5× looser than the accurate default (DOP853 at
# 1e-6 takes ~1/4 the steps of 1e-11 on the rotor); a point next to a regime change is rerun at
# the accurate setting (compare/workflows/map_trace.py: adaptive_grid)
CHEAP_LOOSENING = 1e5
MAX_DOUBLINGS = 7          # a fixed step goes at most 2^7 coarser or finer than the default


def _number(x):
    return isinstance(x, (int, float)) and not isinstance(x, bool)


def snap(dt, dt_out):
    """Largest step ≤ dt that divides the output step into whole steps."""
    return dt_out / max(1, int(np.ceil(dt_out / dt - 1e-9)))


@dataclass(frozen=True)
class Fixed:
    """A fixed step: halving it is the tighter run; an order-p method's error is
    2^p/(2^p − 1) ≤ 2 times |y − y_half|."""
    dt: float
    error_factor = 2.0

    def tighter(self) -> Fixed:
        return Fixed(self.dt / 2)

    def steps(self, t_end: float) -> float:
        return t_end / self.dt

    def apply(self, settings: dict) -> dict:
        return {**settings, "dt": self.dt}

    def text(self) -> str:
        return f"dt {self.dt:g}"

    def ladder(self, dt_out: float, t_end: float) -> tuple[list[Fixed], int]:
        """Steps coarse → fine around this one (factors of ~2: up to the output step snapped
        to its divisors, above it multiples 2^m of it that divide the horizon) and this
        step's index."""
        dt0, coarse = self.dt, {dt_out}
        for j in range(1, MAX_DOUBLINGS + 1):
            c = dt0 * 2 ** j
            if c <= dt_out * (1 + 1e-9):
                coarse.add(snap(c, dt_out))
            else:
                c = dt_out * 2 ** round(np.log2(c / dt_out))
                if c <= t_end / 8 and abs(t_end / c - round(t_end / c)) < 1e-9:
                    coarse.add(c)
        coarse = sorted((c for c in coarse if c > dt0 * (1 + 1e-9)), reverse=True)
        fine = list(dict.fromkeys(snap(dt0 / 2 ** j, dt_out) if dt0 <= dt_out
                                  else dt0 / 2 ** j for j in range(MAX_DOUBLINGS + 1)))
        return [Fixed(d) for d in coarse + fine], len(coarse)


@dataclass(frozen=True)
class Adaptive:
    """An error-controlled method: a tolerance 100× tighter is the tighter run (exact by
    comparison: factor 1); its steps are not known in advance."""
    rtol: float
    atol: float | None = None
    # an error-controlled order-p method's error goes as tol^(p/(p+1)): the 100× tighter rerun
    # keeps up to 100^(-1/2) = 1/10 of the run's error, which |Δ| misses (factor 1 fell 0.4 %
    # short on the quaternion rotor's tilt against a 1000× tighter run)
    error_factor = 10 / 9

    def tighter(self) -> Adaptive:
        return Adaptive(self.rtol / 100, None if self.atol is None else self.atol / 100)

    def steps(self, t_end: float) -> None:
        return None

    def apply(self, settings: dict) -> dict:
        return {**settings, "rtol": self.rtol,
                **({} if self.atol is None else {"atol": self.atol})}

    def text(self) -> str:
        return f"rtol {self.rtol:g}"

    @staticmethod
    def ladder() -> tuple[list[Adaptive], int]:
        return [Adaptive(r) for r in RTOLS], RTOLS.index(START_RTOL)

    def cheap(self, rtol: float | None = None) -> Adaptive | None:
        """The map's cheap level (`rtol`: the one the leaf declares, else the generic
        loosening), None where this tolerance is loose already."""
        r = rtol or min(self.rtol * CHEAP_LOOSENING, START_RTOL)
        return None if r <= self.rtol else Adaptive(
            r, None if self.atol is None else self.atol * r / self.rtol)


@dataclass(frozen=True)
class Knob:
    """A discretisation knob besides the step or tolerance (a leaf's `KNOBS`: setting name ->
    the order p of its error, ∝ value^p: p > 0 a step that shrinks toward the limit, as a
    finite-difference step; p < 0 a ratio that grows toward it, as MuJoCo's constraint time
    constant over the step): tighter moves it by 2 toward the limit, cutting its error by
    2^|p|; coarser the other way (`solvers._knob_errors`). `most`: the most halvings a
    reference run takes (a leaf's `KNOB_LIMITS`; None: no limit) — a finite difference's error
    is h^p·f⁽ᵖ⁺¹⁾ plus its rounding δ/h^k, so past its round-off optimum a smaller h is worse.
    A name joining settings with "+" is one knob that moves them together: steps whose errors
    form one homogeneous term (lagrange-partial's two virtual steps of one loop, a·Δφ² + b·Δψ²
    with a and b of opposite sign: each alone moved the press's slider by 17 × what both
    together did, custom_models/press/partial.py). `holds`: a setting moved the other way so
    that its product with the knob stays (a leaf's `KNOB_HOLDS`): MuJoCo's press varies dt/tc
    at a fixed time constant tc = solref_factor·dt — at a fixed dt a larger factor softens the
    loop too, a change the dt halving already sees (17 × the sampling's at `xval calibrate
    press --seed 777`'s set 9). `integrators`: the integrators the knob acts with (a leaf's
    `KNOB_INTEGRATORS`; None: all): with any other it has no value and is not varied."""
    name: str
    order: float
    most: int | None = None
    holds: str | None = None
    integrators: tuple | None = None

    @property
    def names(self) -> tuple[str, ...]:
        """The settings the knob moves."""
        return tuple(self.name.split("+"))

    def value(self, settings: dict) -> float | None:
        if self.integrators is not None and settings.get("integrator") not in self.integrators:
            return None
        v, h = settings.get(self.names[0]), settings.get(self.holds, 1.0)
        return float(v) if _number(v) and v > 0 and _number(h) and h > 0 else None

    def tighter(self, settings: dict, halvings: int = 1) -> dict:
        f = 2.0 ** (-np.sign(self.order) * halvings)
        held = {self.holds: float(settings[self.holds]) / f} if self.holds else {}
        return {**settings, **{n: float(settings[n]) * f for n in self.names}, **held}


@dataclass(frozen=True)
class Integrator:
    name: str
    order: int | None
    adaptive: bool


# the settings that count a frequency leaf's mesh (elements, segments): integers, finer larger
MESH_SUFFIXES = ("elements", "segments")


@dataclass(frozen=True)
class LeafInfo:
    """What xval knows of one leaf module (`leaf_info(module_name)`, built once)."""
    module: ModuleType
    defaults: dict | None          # DEFAULT_SETTINGS (time leaves; None: a frequency leaf)
    modes_defaults: dict           # MODES_SETTINGS (frequency leaves)
    integrators: tuple             # Integrator records, in the leaf's order
    auto_dt: dict                  # integrator -> the number behind dt="auto"
    # integrator -> a map point's cheap first step (CHEAP_DT: a step the leaf shows stable
    # and whose regime a point's neighbours confirm, as for a loose tolerance)
    cheap_dt: dict
    # integrator -> a map point's cheap first tolerance (CHEAP_RTOL: one whose error the leaf
    # has measured far below the regime margins; else CHEAP_LOOSENING applies)
    cheap_rtol: dict
    own_check: bool                # the leaf checks settings against the grid itself
    batch_regimes: bool            # the leaf classifies many runs in one batch call
    knobs: tuple = ()              # Knob records: discretisation knobs besides dt / rtol
    # integrator -> step factors > 1 of the error estimate's coarser members (COARSER_DT: an
    # explicit step at its stability bound's safety margin, where halving costs 2× the run and
    # its changes do not converge; `coarser_members`, solvers._coarser_error)
    coarser_dt: dict = field(default_factory=dict)
    # setting -> factors, tried in order: a rerun that differs from the tight run only in where
    # its Newton iteration stops (JITTER_PROBE: a fixed step's Newton jitter,
    # solvers._unseen_error)
    jitter_probe: dict = field(default_factory=dict)

    @property
    def unbalance_response(self):
        """unbalance_response(params, spins) -> (complex amplitudes, their errors): a frequency
        leaf's steady response to a rotating unbalance (`xval response`); None where it has
        none. Looked up on use: a leaf package imports that capability's module only then."""
        return getattr(self.module, "unbalance_response", None)

    @property
    def name(self) -> str:
        return self.module.__name__

    @property
    def adaptive(self) -> tuple[str, ...]:
        return tuple(i.name for i in self.integrators if i.adaptive)

    @property
    def fixed(self) -> tuple[str, ...]:
        return tuple(i.name for i in self.integrators if not i.adaptive)

    @property
    def integrator_names(self) -> tuple[str, ...]:
        return tuple(i.name for i in self.integrators)

    def order(self, integrator: str) -> int | None:
        return next((i.order for i in self.integrators if i.name == integrator), None)

    def resolve(self, dt=None, rtol=None, integrator=None, extra=None) -> dict:
        """The leaf's accurate defaults with the user's knobs applied.

        `dt` moves an adaptive default to the leaf's fixed-step method, `rtol` moves a
        fixed-step default to its adaptive one; a leaf without the requested kind keeps its
        own (and the settings actually used say so)."""
        s = dict(self.defaults or {})
        adaptive, fixed, names = self.adaptive, self.fixed, self.integrator_names
        if integrator is not None:
            offered = [canonical_integrator(i) for i in names]
            if canonical_integrator(integrator) not in offered:
                raise BadInput(f"integrator: {integrator!r} is not offered by this solver "
                               f"(choose: {', '.join(offered)})")
            s["integrator"] = names[offered.index(canonical_integrator(integrator))]
        if dt is not None:
            s["dt"] = dt
            if s.get("integrator") in adaptive and integrator is None and fixed:
                s["integrator"] = "rk4" if "rk4" in fixed else fixed[0]
        if rtol is not None:
            if adaptive:
                s["rtol"] = rtol
                if s.get("integrator") not in adaptive and integrator is None:
                    s["integrator"] = adaptive[0]
            # else: no error-controlled integrator; its fixed step stays (the CLI says so)
        s.update(extra or {})
        return s

    def check(self, settings: dict, t_out: np.ndarray | None = None) -> dict:
        """The leaf's own check where it has one, else the shared merge (unknown keys,
        integrator); ValueError with one line."""
        if self.own_check:
            return self.module.check_settings(settings, t_out)
        if self.defaults is not None:
            return merge_settings(settings, self.defaults, self.integrator_names)
        return merge_settings(settings, self.modes_defaults, ())

    def knob(self, settings: dict) -> Fixed | Adaptive | None:
        """The accuracy knob `settings` turn: a tolerance for an error-controlled method, else
        a step ("auto" read as the leaf's `AUTO_DT`); None where neither is a number (a
        stability-bound explicit step)."""
        if settings.get("integrator") in self.adaptive and _number(settings.get("rtol")):
            atol = settings.get("atol")
            return Adaptive(settings["rtol"], atol if _number(atol) else None)
        dt = settings.get("dt")
        if dt == "auto":
            dt = self.auto_dt.get(settings.get("integrator"))
        return Fixed(dt) if _number(dt) and dt > 0 else None

    def cheaper(self, settings: dict) -> dict | None:
        """A map point's cheap first run: an error-controlled method at a looser tolerance
        (`Adaptive.cheap`, at the leaf's `CHEAP_RTOL` where it declares one); a fixed step at
        the larger one its leaf declares (`CHEAP_DT`, stable by the leaf's own measurement);
        else None: a larger step can cross a stability limit, so such a solver maps at its
        accurate step."""
        k = self.knob(settings)
        if isinstance(k, Fixed):
            dt = self.cheap_dt.get(settings.get("integrator"))
            return {**settings, "dt": dt} if _number(dt) and dt > k.dt else None
        c = k.cheap(self.cheap_rtol.get(settings.get("integrator"))) \
            if isinstance(k, Adaptive) else None
        return None if c is None else c.apply(settings)

    def steps(self, settings: dict, t_end: float) -> tuple[float, float] | None:
        """(steps, dt) of one run with a fixed step; None for an error-controlled method (its
        steps are not known in advance; the output grid bounds its memory)."""
        if settings.get("integrator") in self.adaptive:
            return None
        k = self.knob(settings)
        return None if k is None else (k.steps(t_end), k.dt)

    def tighter(self, settings: dict) -> tuple[dict | None, float, str]:
        """Settings for the run's own error estimate, the factor that turns |y − y_tight| into
        the error of the run, and how (see `Fixed`, `Adaptive`)."""
        k = self.knob(settings)
        if k is None:
            return None, 0.0, "no accuracy knob"
        tight = k.tighter()
        return tight.apply(settings), k.error_factor, tight.text()

    def coarser_members(self, settings: dict) -> list[dict]:
        """Settings of the error estimate's coarser members (the run is the finest): its fixed
        step × each factor the leaf declares for the integrator (`COARSER_DT`); [] where it
        declares none (the estimate halves the step)."""
        k = self.knob(settings)
        q = self.coarser_dt.get(settings.get("integrator"), ())
        return [{**settings, "dt": k.dt * f} for f in q] if isinstance(k, Fixed) else []

    def knob_reruns(self, settings: dict) -> list[tuple[Knob, dict]]:
        """Each discretisation knob `settings` set, with the settings that halve it alone (the
        error estimate varies every knob on its own: errors of opposite sign cannot cancel)."""
        return [(k, k.tighter(settings)) for k in self.knobs if k.value(settings)]

    def refined(self, settings: dict, halvings: int = 1) -> dict:
        """`settings` with every discretisation knob halved `halvings` times, no more than its
        `most` (a reference run, a map's confirmation: the step or tolerance is tightened
        apart)."""
        for k, _ in self.knob_reruns(settings):
            settings = k.tighter(settings, halvings if k.most is None else min(halvings, k.most))
        return settings


_INFO: dict = {}


def leaf_info(module_name: str) -> LeafInfo:
    """The leaf module's view, built once (again only where the module object changed: a
    test that puts a stand-in under the same name)."""
    leaf = importlib.import_module(module_name)       # a dict look-up once imported
    info = _INFO.get(module_name)
    if info is None or info.module is not leaf:
        info = _INFO[module_name] = _build(leaf)
    return info


def _has(leaf: ModuleType, name: str) -> bool:
    return name in getattr(leaf, "LAZY", {}) or hasattr(leaf, name)


def _build(leaf: ModuleType) -> LeafInfo:
    adaptive = tuple(getattr(leaf, "ADAPTIVE", ()))
    orders = {**ORDERS, **getattr(leaf, "ORDERS", {})}
    integrators = tuple(Integrator(n, orders.get(n), n in adaptive)
                        for n in getattr(leaf, "INTEGRATORS", ()))
    defaults = getattr(leaf, "DEFAULT_SETTINGS", None)
    return LeafInfo(module=leaf, defaults=None if defaults is None else dict(defaults),
                    modes_defaults=dict(getattr(leaf, "MODES_SETTINGS", {})),
                    integrators=integrators, auto_dt=dict(getattr(leaf, "AUTO_DT", {})),
                    cheap_dt=dict(getattr(leaf, "CHEAP_DT", {})),
                    cheap_rtol=dict(getattr(leaf, "CHEAP_RTOL", {})),
                    own_check=_has(leaf, "check_settings"),
                    batch_regimes=_has(leaf, "regimes"),
                    knobs=tuple(Knob(n, p, getattr(leaf, "KNOB_LIMITS", {}).get(n),
                                     getattr(leaf, "KNOB_HOLDS", {}).get(n),
                                     getattr(leaf, "KNOB_INTEGRATORS", {}).get(n))
                                for n, p in getattr(leaf, "KNOBS", {}).items()),
                    coarser_dt=dict(getattr(leaf, "COARSER_DT", {})),
                    jitter_probe=dict(getattr(leaf, "JITTER_PROBE", {})))
