"""The leaf contract as code: what a leaf model receives and returns, one settings merge, one
spelling per integrator.

Leaves (`custom_models/`, `reference_models/`) may import this module and `compare.physics`
(both numpy only) — nothing else from `compare` (tests/front/test_layers.py enforces it). The
adapter in `compare/solvers.py` validates every result a leaf returns.
"""
from __future__ import annotations

import functools
import importlib
import pkgutil
import sys
from dataclasses import dataclass, field

import numpy as np

# One spelling per integrator; the old spellings of earlier leaves are still accepted.
ALIASES = {"rk44": "rk4", "generalized-alpha": "generalized_alpha",
           "trapezoidal-index2": "trapezoidal", "ode23": "rk23",
           "velocityverlet": "velocity_verlet", "semi-implicit-euler": "euler"}
# One spelling per setting key (old spellings of earlier leaves still accepted).
KEY_ALIASES = {"rho_inf": "spectral_radius", "newton_tolerance": "newton_tol",
               "newton_rtol": "newton_tol", "newton_rel_tol": "newton_tol",
               "newton_atol": "newton_abs_tol", "fine_newton_rel_tol": "fine_newton_tol"}


def canonical_integrator(name: str) -> str:
    name = str(name).lower()
    return ALIASES.get(name, name).replace("-", "_")


def merge_settings(settings: dict | None, defaults: dict, integrators: tuple,
                   extra_keys: tuple = ()) -> dict:
    """The caller's settings over a leaf's defaults, checked the same way for every leaf:
    unknown keys and integrators raise ValueError with one line; integrator names and key
    spellings are normalised. `extra_keys` are accepted without a default (e.g. presets).
    Settings this merge returned for the same `defaults` come back as they are."""
    if isinstance(settings, Checked) and settings.by is defaults:
        return settings
    s = dict(defaults)
    for k, v in (settings or {}).items():
        k = KEY_ALIASES.get(k, k)
        if v is None and k in s:
            continue                         # "not given": keep the default
        s[k] = v
    unknown = sorted(set(s) - set(defaults) - set(extra_keys))
    if unknown:
        raise ValueError(f"unknown settings {unknown} (known: {sorted(defaults)})")
    if "integrator" in s:
        name = canonical_integrator(s["integrator"])
        allowed = tuple(canonical_integrator(i) for i in integrators)
        if name not in allowed:
            raise ValueError(f"integrator {s['integrator']!r} is not offered "
                             f"(choose: {', '.join(allowed)})")
        s["integrator"] = name
    return Checked(s, by=defaults)


class Checked(dict):
    """Settings a check has passed, marked with the check (`by`) and the output span it
    checked them for: handed to the same check again they are not checked again, so a run's
    settings are checked once (`compare.solvers.settings_for`), not again in every `simulate`.
    Any change in place drops the mark; a copy (`dict(s)`, `{**s}`) is a plain dict."""

    def __init__(self, *args, by=None, span=None, **kw):
        super().__init__(*args, **kw)
        self.by, self.span = by, span

    def _changed(self, name, *args):
        self.by = None
        return getattr(super(), name)(*args)

    def __setitem__(self, k, v):
        self._changed("__setitem__", k, v)

    def __delitem__(self, k):
        self._changed("__delitem__", k)

    def update(self, *args, **kw):
        self.by = None
        super().update(*args, **kw)

    def pop(self, *args):
        return self._changed("pop", *args)

    def setdefault(self, *args):
        return self._changed("setdefault", *args)

    def clear(self):
        self._changed("clear")


def _span(t_out):
    t = None if t_out is None else np.asarray(t_out, float)
    return None if t is None or t.size < 2 else (float(t[0]), float(t[-1]))


def check_once(check):
    """A leaf's `check_settings(settings, t_out=None)` that returns settings it already passed
    (for the same output span, or any span when none is given now) as they are."""
    @functools.wraps(check)
    def once(settings=None, *args, **kw):
        t_out = args[0] if args else kw.get("t_out")
        span = _span(t_out)
        if isinstance(settings, Checked) and settings.by is once \
                and (span is None or span == settings.span):
            return settings
        return Checked(check(settings, *args, **kw), by=once, span=span)
    return once


def require_positive(settings: dict, keys: tuple, auto_ok: bool = False) -> None:
    """ValueError with one line unless every setting in `keys` is a number > 0 (with `auto_ok`,
    None and "auto" pass too: the leaf picks the value)."""
    for k in keys:
        v = settings[k]
        if auto_ok and v in (None, "auto"):
            continue
        try:
            ok = float(v) > 0.0
        except (TypeError, ValueError):
            ok = False
        if not ok:
            raise ValueError(f"{k} must be > 0{' or ' + repr('auto') if auto_ok else ''}, "
                             f"got {v!r}")


class Channel(str):
    """A scene's output channel: it is its name (dict keys, JSON, `==` and the leaves see a plain
    string) and carries its SI unit — the unit's one home, read by every plot and table. A
    plug-in may name its channels with plain strings; they are drawn unitless ([–]).
    `rounding`: the parameter whose size the channel's rounding scales with where that is not
    its own value (a constraint residual, zero in exact arithmetic, computed from lengths), or
    a function (channels, params) -> the channel's rounding at each output time (SI), where the
    configuration amplifies it (a loop's closure near its singular position)."""

    def __new__(cls, name: str, unit: str = "", rounding: str | None = None):
        self = super().__new__(cls, name)
        self.unit, self.rounding = unit, rounding
        return self

    def __getnewargs__(self):          # pickled with its unit (pool workers, Dask)
        return (str(self), self.unit, self.rounding)


def rounds_with(channel, own: float, params: dict) -> float:
    """The size a channel's rounding scales with: `own` (its values' size), or the parameter
    the channel names (`Channel.rounding`, a plain channel names none) where that is larger."""
    name = getattr(channel, "rounding", None)
    return max(own, abs(float(params[name]))) if isinstance(name, str) else own


@dataclass
class LeafResult:
    """What `simulate(params, t_out, settings)` returns.

    channels: exactly the scene's channels, float arrays on t_out, SI, NaN after a failure.
    status: "ok" or "diverged" (with t_fail and reason: NaN, energy jump, bound, singularity).
    stats: "steps", "rhs_evals" (-1 where an engine does not tell), optional "rejected",
    "newton_iters", "retries", "integrate_s" — one meaning per key.
    settings: the settings actually used. extra: auxiliary arrays (e.g. "orientation" (n, 4)
    w, x, y, z). invariants: conserved quantity -> largest relative drift the leaf measured.
    """
    channels: dict
    status: str = "ok"
    t_fail: float | None = None
    reason: str | None = None
    stats: dict = field(default_factory=dict)
    settings: dict = field(default_factory=dict)
    extra: dict = field(default_factory=dict)
    invariants: dict = field(default_factory=dict)

    STATUSES = ("ok", "diverged", "unstable", "singular")

    @classmethod
    def coerce(cls, res) -> LeafResult:
        """A leaf's return value as a LeafResult (earlier leaves return a plain dict)."""
        if isinstance(res, cls):
            return res
        if not isinstance(res, dict) or "channels" not in res:
            raise TypeError(f"leaf returned {type(res).__name__}, not a LeafResult")
        known = {k: res[k] for k in ("channels", "status", "t_fail", "reason", "stats",
                                     "settings", "extra", "invariants") if k in res}
        return cls(**known)

    def validate(self, channels: tuple, n: int) -> str | None:
        """Why this result breaks the contract, or None."""
        missing = [c for c in channels if c not in self.channels]
        if missing:
            return f"leaf did not return channels {missing}"
        for c in channels:
            a = np.asarray(self.channels[c])
            if a.shape != (n,):
                return f"channel {c!r} has shape {a.shape}, expected ({n},)"
        if self.status not in self.STATUSES:
            return f"unknown status {self.status!r}"
        if self.status != "ok" and self.t_fail is None:
            return f"status {self.status!r} without t_fail"
        for k, v in self.stats.items():
            if not isinstance(v, (int, float, np.integer, np.floating)):
                return f"stats[{k!r}] is not a number"
        return None


@dataclass
class LeafModes:
    """What `modes(params, settings)` returns: frequencies in Hz (ascending; damped where the
    leaf linearises with damping), one label each ("flap 1", "forward whirl", …), optional
    damping ratios ζ, optional whirl directions ("forward", "backward", "mixed": ROSS's words
    in the contract's lower case; "—" for a mode without whirl), optional mode shapes (any
    array with one row per mode, used for tracking modes across a sweep by MAC), and notes
    (e.g. "approximate: eccentric rotor at spin ≠ 0")."""
    frequencies_hz: np.ndarray
    labels: list
    damping: np.ndarray | None = None
    shapes: np.ndarray | None = None
    whirl: list | None = None
    settings: dict = field(default_factory=dict)
    notes: list = field(default_factory=list)
    extra: dict = field(default_factory=dict)

    @classmethod
    def coerce(cls, res) -> LeafModes:
        if isinstance(res, cls):
            return res
        if not isinstance(res, dict) or "frequencies_hz" not in res:
            raise TypeError(f"leaf returned {type(res).__name__}, not a LeafModes")
        known = {k: res[k] for k in ("frequencies_hz", "labels", "damping", "shapes", "whirl",
                                     "settings", "notes", "extra") if k in res}
        return cls(**known)

    def validate(self) -> str | None:
        f = np.asarray(self.frequencies_hz, float)
        if f.ndim != 1 or len(self.labels) != len(f):
            return f"{len(f)} frequencies but {len(self.labels)} labels"
        if not np.all(np.isfinite(f)):
            return "non-finite frequency"
        for name in ("damping", "whirl"):
            given = getattr(self, name)
            if given is not None and len(given) != len(f):
                return f"{len(f)} frequencies but {len(given)} {name} values"
        return None


# Deprecated: the name earlier leaves and plug-ins import. It is the same class; the name
# `ModesResult` now belongs to what `xval.modes` returns (compare/results/modes.py).
ModesResult = LeafModes


def lazy_exports(package: str, where: dict[str, str]):
    """A package's module `__getattr__` (PEP 562): each name imported from its own submodule on
    first use — a leaf package's capabilities (`regimes`, `modes`, …: a time run imports none
    of them), the Result types. `where`: name -> submodule (the package's `LAZY`). A name may
    not be a submodule's: importing that submodule (from a sibling, a test) would bind the
    module over the name, and `__getattr__` would never be asked again."""
    subs = {m.name for m in pkgutil.iter_modules(sys.modules[package].__path__)}
    clash = sorted(set(where) & subs)
    if clash:
        raise ImportError(f"{package}: LAZY names {clash} are also its submodules' names")

    def __getattr__(name):
        if name not in where:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        return getattr(importlib.import_module(f"{package}.{where[name]}"), name)
    return __getattr__
