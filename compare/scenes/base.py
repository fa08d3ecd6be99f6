"""The Scene type: the single source of a scene's parameters, defaults, channels, closed forms,
which leaf serves it for each solver, and its hooks (Campbell sweep, 3D drawing, default
campaign cases, findings). Nothing in `compare/` outside `compare/scenes/` names a scene."""
from collections.abc import Callable
from dataclasses import dataclass, field, fields
from typing import ClassVar

import numpy as np

from ..analysis.metrics import (
    against_formula,
    damping_comparisons,
    first_crossing,
    frequency_comparisons,
    pairwise,
)
from ..contract import Channel
from ..errors import BadInput
from ..physics.whirl import FRAMES
from .params import Param


@dataclass(frozen=True)
class Excitation:
    """An excitation line of a Campbell diagram: `order` × the rotation frequency as seen in
    `frame` ("fixed": from the ground, "rotating": from the rotor), `name` what excites it;
    `present(params) -> bool`: whether the system has it at these parameters (None: always) —
    a line it lacks is neither drawn nor crossed."""
    order: int
    frame: str
    name: str
    present: Callable | None = None

    def __post_init__(self):
        if self.frame not in FRAMES or self.order < 1:
            raise ValueError(f"excitation {self.name!r}: order ≥ 1 in a frame of {FRAMES}")


# a mass off the axis: a force turning with the rotor, fixed in it — 1× in the fixed frame
UNBALANCE = Excitation(1, "fixed", "unbalance")


def per_rev(n: int) -> Excitation:
    """The n-th harmonic of the loads a blade meets once per revolution (the fan plot's n/rev
    line, in the rotor's frame)."""
    return Excitation(n, "rotating", "per-rev blade loads")


@dataclass(frozen=True)
class Campbell:
    """A frequency scene's sweep: `parameter` from `lo` to `hi` in `n` points (each a number or
    the name of a scene parameter that holds it). `excitation_hz(params, value)` gives the
    rotation frequency [Hz] at a sweep value (a rotor speed in rad/s gives value/2π): the 1×
    line. The solvers report their lines in `frame`; `whirls`: their modes whirl about the
    spin axis (a direction per mode: the whirl sense a rotating-frame leaf reports in
    extra["whirl_sense"], the forward/backward label of a fixed-frame one), so that the lines
    map to the other frame (compare.physics.whirl) and the diagram can be drawn in either.
    Critical speeds are where a mode line crosses an `excitations` line in that excitation's
    frame, found on these `n` points; the first excitation's crossings are named by the mode,
    the others "<mode> (<order>×)" (orders are unique). The diagram adds at most `refine`
    points per solver, each halving a step where lines come close, swap order or lose their
    shape, down to the step / 2**`depth` (compare/analysis/campbell.py)."""
    parameter: str
    lo: float | str
    hi: float | str
    n: int | str
    excitation_hz: Callable | None = None
    frame: str = "fixed"
    excitations: tuple = (UNBALANCE,)
    whirls: bool = False
    unit: str = "rad/s"
    refine: int = 12
    depth: int = 3
    solvers: tuple = ()     # the solvers that draw it (default: every solver of the run)

    def __post_init__(self):
        orders = [e.order for e in self.excitations]
        if self.frame not in FRAMES or len(set(orders)) != len(orders):
            raise ValueError(f"Campbell: frame in {FRAMES}, unique excitation orders {orders}")
        if not self.whirls and any(e.frame != self.frame for e in self.excitations):
            raise ValueError("Campbell: an excitation in another frame than the lines' needs "
                             "whirling modes (whirls=True) to map them")

    def active(self, params) -> tuple:
        """The excitations the system has at `params` (`Excitation.present`)."""
        return tuple(e for e in self.excitations if e.present is None or e.present(params))

    @property
    def frames(self) -> tuple:
        """The frames the diagram can be drawn in: its own, and the other where modes whirl."""
        return FRAMES if self.whirls else (self.frame,)

    def values(self, params):
        get = lambda v: params[v] if isinstance(v, str) else v     # noqa: E731
        return np.linspace(float(get(self.lo)), float(get(self.hi)), int(get(self.n)))


@dataclass(frozen=True)
class Extreme:
    """One extreme case of a scene's spec: parameter overrides (`set`), settings overrides for
    the solvers that have those keys (e.g. a step above a stability limit), and the
    independent check that an `ok` run must pass.

    check: "energy" — the energy balance closes to `bound` of the energy scale (conservation
    law); "reference" — the key channel agrees with the scene's first reference solver at its
    accurate settings to `bound` of the channel's scale (a second solver); a callable
    (params, trajectory) -> (passed, value, what) for a closed form. `expect` says what an
    honest outcome is: "ok" (must pass the check), "status" (must end diverged / unstable /
    singular — e.g. past a singularity), or "either" (ok and passing, or an honest status)."""
    name: str
    set: dict = field(default_factory=dict)
    settings: dict = field(default_factory=dict)
    check: str | Callable = "energy"
    bound: float = 1e-6
    expect: str = "either"
    solvers: tuple = ()          # restrict to these (default: every solver of the scene)
    # long: run by `xval extremes --all` and the slow tests — True: the whole case; a tuple of
    # solver names: only their runs (an engine at the step that resolves the case)
    slow: bool | tuple = False
    # solver -> why it cannot meet the bound at any practical setting (the drift stops
    # shrinking, or the resolving run takes minutes): reported `FAILED (known)`, counted apart
    # from FAILED and never as a pass; one that passes after all is a stale declaration
    known_failures: dict = field(default_factory=dict)
    why: str = ""

    def slow_for(self, solver: str) -> bool:
        return self.slow is True or (isinstance(self.slow, tuple) and solver in self.slow)


@dataclass(frozen=True)
class MapSpec:
    """One map of a scene (`xval map`, the default campaign's `[[maps]]`): axes as
    "NAME=LO:HI", parameter overrides, solvers (default: the scene's), the bracket asked
    (fraction of each axis' range: `resolution` along x, `y_resolution` the rows the boundary's
    tracing may add, default `resolution`) and the coarse grid (points along x, rows along y)."""
    name: str
    x: str
    y: str | None = None
    set: dict = field(default_factory=dict)
    solvers: tuple = ()
    resolution: float = 1e-3
    y_resolution: float | None = None
    coarse: tuple = (17, 9)
    observable: str | None = None    # a map observable's name; None: the scene's regime
    level: float | None = None
    engines: str = "boundary"        # or "everywhere"


@dataclass(frozen=True)
class SpeedRegime:
    """A regime read off one channel against two levels of the parameters, `levels(params)`
    -> (reach, stay): `labels[0]` unless the channel reaches `reach` after t = 0, `labels[2]`
    where it stays above `stay` from `window` × t_end on, else `labels[1]`. Called on a run it
    decides that run (`Scene.regime`); a leaf's compiled batch (`regimes`, `solvers.regimes`)
    decides the same from the same numbers."""
    channel: str
    levels: Callable
    window: float
    labels: tuple

    def __call__(self, p, tr):
        reach, stay = self.levels(p)
        w = tr.channels[self.channel]
        if first_crossing(tr.t, w, reach) is None:
            return self.labels[0]
        return self.labels[2 if np.min(w[tr.t >= self.window * tr.t[-1]]) > stay else 1]


@dataclass(frozen=True)
class PublishedTiming:
    """A computing time the source reports for one of its tables: `seconds` (tool -> s) for
    the runs at `cases` (overrides of the scene's defaults, one run each; `xval bench` sums
    them)."""
    what: str
    seconds: dict
    cases: tuple = ({},)


def evaluate_allowances(tolerances, params):
    """`tolerances` with every callable entry f(params) (an allowance derived from the
    modelling difference it names) replaced by its value at `params`."""
    if callable(tolerances):
        return tolerances(params)
    if isinstance(tolerances, dict):
        return {k: evaluate_allowances(v, params) for k, v in tolerances.items()}
    return tolerances


@dataclass(frozen=True)
class AllowanceCase:
    """The allowances of a regime of the scene's parameters that its default allowances were
    not measured in (a 2-s sail run is not a full deployment): where `when(params)` holds, the
    run's verdicts use `tolerances` (a whole `Scene.tolerances` dict) instead. `name` says
    which regime; the measurement behind it sits next to it in the scene file."""
    name: str
    when: Callable
    tolerances: dict


@dataclass(frozen=True)
class FormulaCheck:
    """A closed form judged against each solver's `channel` (a `TimeScene`'s
    `formula_checks`): |channel − formula(params, t)| ≤ the formula's own error + the solver's
    error estimate (`compare.analysis.metrics.against_formula`), a comparison of its own in the
    run's verdicts (`b` = `label`, `formula` true). `error(params, t, solver)`: the formula's
    error against that solver's model, max |Δ| over `t` in SI, derived from what the formula
    neglects (its derivation next to it in the scene file and on the scene's page); a string
    where the formula states no error (outside its domain: `inconclusive`). `solvers`: those
    judged (empty: all)."""
    channel: str
    label: str
    formula: Callable
    error: Callable
    solvers: tuple = ()


@dataclass(frozen=True)
class Response:
    """An unbalance response (`xval response`): steady amplitude and phase of a complex
    observable a (its motion a·e^{iφ(t)}, φ the rotor's angle) vs constant spin, from the
    leaves' `unbalance_response(params, spins) -> (a, error)` (frequency domain) and from the
    `time_solvers` of `time_scene` run to steady state (time domain).
    `set`: the parameters the response runs at unless told (an unbalance small enough to stay
    linear, damping that makes a steady state); `critical(params) -> (Ω_c, ζ)`: the first
    critical speed and its damping ratio, which place the speeds (denser within ±3ζ of Ω_c);
    `decay(params, spin)`: the slowest free decay rate [1/s] (the settling time);
    `time_params(params, spin, t_end, output_dt, release=0.0)`: the time scene's parameters
    holding that spin (and the extra parameters only its solvers take), the rotor released
    from rest at a small deflection `release` (0: undeflected);
    `observe(params, trajectory) -> (z(t), e^{iφ(t)})`: the observable's samples and the
    rotor's angle from a run; `high_spot`: the factor turning a into the high spot's phasor relative
    to the heavy spot (the phase lag is −arg(high_spot·a))."""
    time_scene: str
    time_solvers: tuple
    critical: Callable
    decay: Callable
    time_params: Callable
    observe: Callable
    set: dict = field(default_factory=dict)
    high_spot: complex = 1.0
    amplitude: str = ""            # what |a| is, with its unit
    drive: str = ""                # how the time solvers hold the spin, in words


@dataclass(frozen=True)
class Threshold:
    """A speed above which a root grows (`xval modes` reports it where `active(params)`): from
    the closed form `speed(params)` (inf: stable at every speed), from each solver's
    eigenvalues (the largest growth rate, `Modes.extra["max_re_per_s"]`, crossing zero in
    `parameter`) and from the growth of free responses of the scene's `Response` time solvers,
    released by `release` with no forcing (`free`: the parameters that remove it) and fitted
    with `roots` damped exponentials. `growth(params, speed) -> (σ, ω)`: the closed form's
    growing root at a speed, which the time-domain fits are checked against."""
    parameter: str
    active: Callable
    speed: Callable
    growth: Callable
    release: float
    free: dict = field(default_factory=dict)
    roots: int = 2


@dataclass(frozen=True)
class Linearisation:
    """A time scene's modal answer (`xval modes` on it, `Scene.modal()`): its leaves'
    `modes(params, settings)` linearise the system about `operating_point` (a steady state of
    the scene's own parameters, in words) and return damped frequencies and damping ratios.
    `held`: the parameters the linear system does not take (how a run is made, initial
    conditions, a forcing it leaves out), name -> the value held (None: the default);
    `tolerances`: the frequency and damping allowances (as a frequency scene's); `identify`:
    the identification hook of frequency scenes, e.g. ring-downs of the time solvers."""
    operating_point: str
    tolerances: dict
    held: dict = field(default_factory=dict)
    identify: Callable | None = None


@dataclass(frozen=True)
class Calibration:
    """Where `xval calibrate` draws parameter sets (compare/workflows/calibrate.py). By default
    each float physical parameter with a non-zero default, log-uniformly in [default/2,
    2·default] within its admissible range, a time scene's horizon a tenth of its default;
    `region` (name -> (lo, hi)) adds or replaces axes, drawn log-uniformly where named in `log`
    (else uniformly); `fixed` (name -> value) holds names out of the region (a short horizon);
    `outside` (solver, "*" any -> (why, how its stop's reason starts)): where in the region
    that solver leaves its domain and stops — a set where it stops so is outside the region,
    skipped with this reason and never counted as agreement; a stop with another reason is
    not declared;
    `truth` (solver -> another): whose run is that solver's true answer in place of its own
    far tighter run — where it has none (a closed form of the same model) or where its own
    refinement grows noisier than the run (a stiff FE mesh, index-3 accelerations);
    `campaign`: the sets the default campaign draws (0: none — the scene's runs are too long
    for its budget)."""
    region: dict = field(default_factory=dict)
    fixed: dict = field(default_factory=dict)
    log: tuple = ()
    outside: dict = field(default_factory=dict)
    truth: dict = field(default_factory=dict)
    campaign: int = 0


@dataclass(frozen=True)
class Fit:
    """What `xval identify` fits (compare/workflows/identify.py): the default `unknowns`;
    `scale` (name -> typical size: the fit's unit, and a CI half-width above it — or above a
    quarter `period` — marks the unknown unidentified); `periodic` (name -> period: started
    from `starts` points across it, the estimate wrapped into [−period/2, period/2));
    `revolution` the channel of an angle the record must turn through by one period at least
    (2π); `noise` (channel -> σ) the default synthesis noise; `through` (name -> another): an
    unknown the data see only through the other's size (a defect's shape through its height),
    undetermined wherever the other's interval holds zero; `section` (angle, x, y channels):
    `--poincare PHASE` fits x, y once per revolution, where the angle passes PHASE + 2πk;
    `--detection` (the smallest `size` told from none): over `speeds` of the parameter `speed`,
    for each of the `channel_sets` (label -> channels)."""
    unknowns: tuple
    scale: dict = field(default_factory=dict)
    periodic: dict = field(default_factory=dict)
    starts: int = 32
    revolution: str | None = None
    noise: dict = field(default_factory=dict)
    through: dict = field(default_factory=dict)
    section: tuple = ()
    size: str | None = None
    speed: str | None = None
    speeds: tuple = ()
    channel_sets: dict = field(default_factory=dict)


ERRORS = ("max_abs",)      # the benchmark errors `Benchmark.deviation` computes


@dataclass(frozen=True)
class Benchmark:
    """The scene is a problem of the IFToMM Library of Computational Benchmark Problems:
    `problem` its id ("A04"); `columns` the monitored channels its results file lists after t,
    every `output_dt` seconds (the problem's output step; None: the run's grid);
    `reference(params, t) -> {channel: array on t}` the reference solution (NaN at times where
    it holds no value; None where it is not known at these parameters), `reference_name` what
    it is, `uncertainty` its own error (the channels' unit); `error` the problem's error:
    "max_abs" — the largest |run − reference| over the monitored channels and the times where
    the reference holds a value (`deviation`)."""
    problem: str
    columns: tuple
    reference: Callable
    reference_name: str
    output_dt: float | None = None
    uncertainty: float = 0.0
    error: str = "max_abs"

    def __post_init__(self):
        if self.error not in ERRORS or not self.columns:
            raise ValueError(f"benchmark {self.problem}: error in {ERRORS}, columns named")

    def deviation(self, params, t, channels):
        """The problem's error of a run (`t`, `channels` on it): {"error", "channel", "t",
        "scale" (the reference's largest |value|), "points" (reference values compared)}, or
        None where the reference is not known at `params`, holds no value on `t`, or the run
        has no finite value where it does."""
        t = np.asarray(t, float)
        ref = self.reference(params, t)
        if ref is None:
            return None
        best, scale, points = None, 0.0, 0
        for c in self.columns:
            r = np.asarray(ref[c], float)
            held = np.isfinite(r)
            if not held.any():
                continue
            d = np.abs(np.asarray(channels[c], float)[held] - r[held])
            if not np.all(np.isfinite(d)):
                return None
            points += int(held.sum())
            scale = max(scale, float(np.max(np.abs(r[held]))))
            i = int(np.argmax(d))
            if best is None or d[i] > best["error"]:
                best = {"error": float(d[i]), "channel": c, "t": float(t[held][i])}
        return best and {**best, "scale": scale, "points": points}


def tabulated(times, values: dict, holds: Callable, atol: float = 1e-9) -> Callable:
    """A reference given as a table: `values` (channel -> values at `times`), valid where
    `holds(params)`; as `Benchmark.reference`: on a grid t, each tabulated time found on it
    (within `atol` s) carries its value, every other time NaN."""
    times = np.asarray(times, float)
    values = {c: np.asarray(v, float) for c, v in values.items()}

    def reference(params, t):
        if not holds(params):
            return None
        t = np.asarray(t, float)
        out = {c: np.full(len(t), np.nan) for c in values}
        if not len(t):
            return out
        idx = np.clip(np.searchsorted(t, times), 0, len(t) - 1)
        for k, tk in enumerate(times):
            i = min((j for j in (idx[k] - 1, idx[k]) if 0 <= j < len(t)),
                    key=lambda j: abs(t[j] - tk))
            if abs(t[i] - tk) <= atol:
                for c, v in values.items():
                    out[c][i] = v[k]
        return out
    return reference


@dataclass(frozen=True)
class Scene:
    name: str
    title: str
    source: str                     # the paper / spec it comes from
    kind: str                       # "time" (xval run) or "modes" (xval modes)
    params: tuple[Param, ...]
    # solver name -> leaf module serving this scene (the registry line of each solver)
    leaves: dict = field(default_factory=dict)
    # the output channels, each a `Channel` carrying its unit (plain names: unitless)
    channels: tuple[Channel, ...] = ()
    # per-channel modelling allowance, relative to the channel's scale (max |value| of the
    # pair) or ("abs", SI): what the models may differ by beyond the solvers' own errors —
    # each set from a measured deviation, with the reason, in the scene file, ≤ 10 × it
    # (tests/verdicts/test_allowances.py). "by_pair" {"a|b": {channel: allowance}} gives a pair its
    # own (engine–engine: both engines share one model), "by_solver" {solver: {…}} every pair
    # with that solver; modes scenes: "frequency", "frequency_by_pair", "frequency_by_solver"
    # and per mode "frequency_by_mode" {solver: {label: allowance}}
    # (compare.analysis.metrics.allowance / frequency_allowance). Any entry may be a function
    # of the resolved parameters, f(params) -> allowance, derived from the modelling difference
    # it names; `tolerances_for(params)` evaluates them (read allowances only through it)
    tolerances: dict = field(default_factory=dict)
    # regimes with allowances of their own (AllowanceCase, first match wins; `tolerances_for`)
    allowance_cases: tuple = ()
    key_channel: str = ""           # the channel whose final value the benchmark measures
    energy_channel: str | None = "energy_balance"
    # a run whose energy balance drifts by more than this fraction of the energy scale is
    # reported `diverged` (stable-but-wrong integration must not pass as "ok"); the scale is the
    # largest |value| of the energy channel and of `energy_scale_channels`
    energy_bound: float = 0.05
    energy_scale_channels: tuple[str, ...] = ()
    # conserved quantities (channel -> reported as relative drift in `invariants`)
    invariant_channels: tuple[str, ...] = ()
    # closed forms drawn with a channel: channel -> (trajectory extra key, label); plotted in
    # the report and recorded as `<channel>/<label>` next to the solvers
    analytic: dict = field(default_factory=dict)
    # verdicts weigh each solver's own error from a tighter rerun (off where a rerun costs
    # more than the scene can pay; the allowances then carry the verdict alone)
    error_estimate: bool = True
    # why the scene's forces have a derivative that jumps in time (a bump's edges), if they
    # do: a fixed step straddles the jump at a fraction of itself that changes with the step,
    # so its error's size and sign jump between halvings and one halving's change can fall
    # short of it; a fixed step's estimate then takes a run at dt/4 and the band of the run and
    # its two refinements (`solvers._halving_error`)
    kinks: str = ""
    # the bench's reference: the first runs tightest, the second confirms it (names only)
    reference_solvers: tuple[str, ...] = ()
    # the solvers `xval bench` walks unless told (default: all): a solver of another model has
    # no accuracy to measure against the reference, only the model difference
    bench_solvers: tuple[str, ...] = ()
    check: Callable | None = None   # cross-parameter physical checks, raises BadInput
    findings: Callable | None = None  # (params, trajectories) -> list[Finding]
    # frequency scenes: the Campbell sweep; `identify(params, simulate, solver_names)` returns
    # (json rows, markdown lines) of frequencies identified from time-domain free responses
    campbell: Campbell | None = None
    identify: Callable | None = None
    response: Response | None = None        # the unbalance response (`xval response`)
    threshold: Threshold | None = None      # the speed where a root starts to grow
    # explain_frequencies(params, comparisons, modes_at(solver, params), tolerances) -> (json
    # rows, markdown lines): why the pairs that disagree do (measured), for the report
    explain_frequencies: Callable | None = None
    # mode_shape_3d(params, solver, shape row) -> [(points (n, 3) m, displacement (n, 3))]:
    # the structure's line strips and one mode's motion Re(displacement·e^{iωt}) on them
    mode_shape_3d: Callable | None = None
    # time scenes: draw_3d(rec, params, trajectory, colour, offset) logs the bodies to rerun;
    # plots(params, trajectories, figure) fills a matplotlib figure of scene-specific plots
    draw_3d: Callable | None = None
    plots: Callable | None = None
    # the default campaign's cases of this scene: [{"name", "set", "solvers", "timeout_s"}]
    campaign_cases: tuple = ()
    # the spec's extreme cases (`xval extremes`)
    extremes: tuple = ()
    # frequency scenes: the source's computing times (PublishedTiming), which `xval bench`
    # sets each solver's default-settings time against
    published_timings: tuple = ()
    # the channels the recording's first screen shows (default: key channel and energy)
    view_channels: tuple[str, ...] = ()
    # maps (`xval map`): regime(params, trajectory) -> the label of one ok run, decided by the
    # same function the findings use (a SpeedRegime: a compiled leaf may batch it);
    # map_observables: name -> (fn(params, trajectory) -> float or None, unit, doc), a scalar
    # per run (None: the event did not happen); maps: the scene's default maps (MapSpec), run
    # by the default campaign
    regime: Callable | None = None
    map_observables: dict = field(default_factory=dict)
    maps: tuple = ()
    notes: str = ""
    group: str = ""    # `xval list`'s group ("benchmarks": the field's refereed problems)
    # a time scene's answer to `xval modes` (Linearisation; `modal()`), and a frequency scene's
    # parameters held at fixed values (name -> value: its leaves get them, `--set` refuses them)
    linearisation: "Linearisation | None" = None
    held: dict = field(default_factory=dict)
    # `xval calibrate`'s sampling region (None: the default region, `Calibration`)
    calibration: Calibration | None = None
    # `xval identify`'s unknowns and their scales (None: the scene cannot be identified)
    fit: Fit | None = None

    def __post_init__(self):
        object.__setattr__(self, "channels", tuple(
            c if isinstance(c, Channel) else Channel(c) for c in self.channels))
        if type(self) is Scene and self.kind in SCENE_KINDS:
            # `Scene(kind="time", …)` (a plugin's spelling) is a TimeScene: the kind's class
            # answers what the workflows ask of it
            object.__setattr__(self, "__class__", SCENE_KINDS[self.kind])

    def unit(self, channel: str) -> str:
        """The SI unit of `channel` ("" where the scene names none)."""
        return next((c.unit for c in self.channels if c == channel), "")

    @property
    def is_time(self) -> bool:
        """A time-domain scene (`xval run`): its leaves simulate on an output grid."""
        return self.kind == "time"

    @property
    def is_modes(self) -> bool:
        """A frequency scene (`xval modes`): its leaves return modes."""
        return self.kind == "modes"

    def param(self, name):
        for p in self.params:
            if p.name == name:
                return p
        if name in self.held:
            raise BadInput(f"{name}: held at {self.held[name]!r} by the linearisation of scene "
                           f"{self.name} (not a parameter of its modes)")
        raise BadInput(f"{name}: unknown parameter of scene {self.name} "
                       f"(known: {', '.join(p.name for p in self.params)})")

    def resolve(self, overrides=None):
        """Defaults with `--set` overrides applied; every value validated. Raises BadInput."""
        values = {**self.held, **{p.name: p.default for p in self.params}}
        for name, text in (overrides or {}).items():
            values[name] = self.param(name).parse(text)
        for p in self.params:                      # defaults are checked too (campaign files)
            p.check(values[p.name])
        if self.check:
            self.check(values)
        if self.is_time:
            self.output_steps(values)              # the grid must fit before anything runs
        return values

    def resolve_many(self, base, points):
        """`resolve({**base, **point})` for every point, `base` resolved once: a map's chunk
        resolves thousands of points that differ in one or two names (the full resolve was 24
        µs a point, ~6 % of a cheap rotor map point)."""
        values = self.resolve(base)
        out = []
        for point in points:
            v = dict(values)
            for name, text in point.items():
                v[name] = self.param(name).parse(text)
            if self.check:
                self.check(v)
            if self.is_time and ("t_end" in point or "output_dt" in point):
                self.output_steps(v)
            out.append(v)
        return out

    def allowance_case_for(self, params):
        """The first allowance case that holds at `params` (None: the scene's own)."""
        return next((c for c in self.allowance_cases if c.when(params)), None)

    def power_scales(self, runs) -> dict:
        """The energy balance, a residual that stays near zero, weighed against the energy it
        balances (the largest |value| of `energy_scale_channels` over the runs) when an error
        bar's width is judged (`metrics.too_wide`)."""
        ch, of = self.energy_channel, self.energy_scale_channels
        values = [np.nanmax(np.abs(r.channels[c])) for r in runs if r.status == "ok"
                  for c in of if c in r.channels]
        return {ch: float(max(values))} if ch and values else {}

    def tolerances_for(self, params):
        """The allowances a run at `params` is judged by: the first allowance case that holds,
        else the scene's, with every entry that is a function of the parameters evaluated at
        `params`."""
        case = self.allowance_case_for(params)
        return evaluate_allowances(self.tolerances if case is None else case.tolerances,
                                   params)

    def verdicts(self, params, runs):
        """Every pair of `runs` (Trajectories, or Modes for a frequency scene) compared and
        judged against the allowances of `params` — the one way a scene judges its solvers;
        damping ratios too where the scene has an allowance for them ("damping")."""
        tol = self.tolerances_for(params)
        if not self.is_modes:
            return pairwise(runs, tol, self.power_scales(runs)) + self.formula_verdicts(
                params, runs)
        return frequency_comparisons(runs, tol) + (damping_comparisons(runs, tol)
                                                    if "damping" in tol else [])

    def modal(self) -> "Scene":
        """The frequency scene `xval modes` runs: this one, or a time scene's linearisation
        about its operating point (`Linearisation`) as a frequency scene of the same name —
        the same leaves (their `modes`), the parameters less those the linearisation holds,
        its allowances and identification hook. Raises BadInput for a time scene that does
        not linearise."""
        if self.is_modes:
            return self
        lin = self.linearisation
        if lin is None:
            raise BadInput(f"scene {self.name!r} is a time-domain scene: use `xval run "
                           f"{self.name}`")
        held = {p.name: p.default if lin.held[p.name] is None else lin.held[p.name]
                for p in self.params if p.name in lin.held}
        kept = {f.name: getattr(self, f.name) for f in fields(Scene) if f.name != "kind"}
        return ModesScene(**{
            **kept, "linearisation": None, "held": held,
            "title": f"{self.title}: damped modes about {lin.operating_point}",
            "params": tuple(p for p in self.params if p.name not in held),
            "tolerances": lin.tolerances, "allowance_cases": (), "identify": lin.identify,
            "energy_channel": None, "findings": None, "draw_3d": None, "plots": None,
            "campaign_cases": (), "extremes": (), "regime": None, "map_observables": {},
            "maps": (), "calibration": None})

    def output_steps(self, params):
        """The output grid's number of steps; BadInput unless output_dt divides t_end."""
        t_end, dt = params["t_end"], params["output_dt"]
        n = int(round(t_end / dt))
        if n < 1 or abs(n * dt - t_end) > 1e-9 * t_end:
            raise BadInput(f"output_dt: {dt:g} s must divide t_end = {t_end:g} s into whole steps")
        return n

    def output_grid(self, params):
        return np.linspace(0.0, params["t_end"], self.output_steps(params) + 1)


@dataclass(frozen=True)
class Finding:
    """One statement of the report, with the number that backs it; `at` (solver -> time in s)
    for an event, which the recording puts on the timeline."""
    name: str
    value: float | None
    unit: str
    text: str
    at: dict | None = None


@dataclass(frozen=True)
class TimeScene(Scene):
    """A scene `xval run` simulates: channels over time, compared pair by pair against the
    solvers' error estimates and the allowances. What the workflows ask of a scene's kind,
    this class and `ModesScene` answer (nothing outside compare/scenes/ tests the kind)."""
    kind: str = field(default="time", init=False)
    command: ClassVar[str] = "run"               # the command that answers the scene
    described: ClassVar[str] = "a time-domain scene"
    has_output_grid: ClassVar[bool] = True       # t_end / output_dt: budgets, settings, steps
    # its runs (Trajectories) carry per-channel error bars, kept by a perturbed run
    runs_carry_errors: ClassVar[bool] = True
    # the default campaign reports its cases' detection power (one sensitivity job each)
    power_in_campaign: ClassVar[bool] = True
    # `xval map` maps its regimes as well as its observables
    mappable: ClassVar[bool] = True
    # the IFToMM library problem it is (None: none): `xval run --out` writes its results files,
    # `xval bench` measures against its reference (`bench_reference`)
    benchmark: Benchmark | None = None
    # closed forms judged against each solver's channel (FormulaCheck): verdicts of their own
    formula_checks: tuple = ()

    def formula_verdicts(self, params, runs) -> list:
        """Each `formula_checks` entry against each run it judges (`against_formula`)."""
        out = []
        for fc in self.formula_checks:
            for tr in runs:
                if fc.solvers and tr.solver not in fc.solvers:
                    continue
                ok = tr.status == "ok"
                out.append(against_formula(
                    tr, next(c for c in self.channels if c == fc.channel), fc.label,
                    fc.formula(params, tr.t) if ok else None,
                    fc.error(params, tr.t, tr.solver) if ok else None))
        return out

    def samples_per_run(self, params) -> float:
        """Output samples per channel of one run at `params` (what a run costs)."""
        return params["t_end"] / params["output_dt"] + 1

    def either(self, time, modes):
        """`time`: of a workflow's two per-kind functions (or values), the one for this scene
        (the scene picks; it may not import the workflows that define them)."""
        return time

    def bench_reference(self, params) -> Benchmark | None:
        """What `xval bench` measures each rung's error against at `params`: the benchmark
        problem's reference where it is known there (the problem's own error), else None —
        the finest rung of the scene's first reference solver, on the key channel's final
        value."""
        bm = self.benchmark
        ref = bm and bm.reference(params, self.output_grid(params))
        held = ref and any(np.isfinite(np.asarray(ref[c], float)).any() for c in bm.columns)
        return bm if held else None


@dataclass(frozen=True)
class ModesScene(Scene):
    """A scene `xval modes` answers: frequencies, damping, Campbell diagram, critical speeds."""
    kind: str = field(default="modes", init=False)
    command: ClassVar[str] = "modes"
    described: ClassVar[str] = "a frequency scene"
    has_output_grid: ClassVar[bool] = False
    runs_carry_errors: ClassVar[bool] = False    # Modes carry no per-channel error bars
    power_in_campaign: ClassVar[bool] = False
    benchmark: ClassVar[None] = None             # no IFToMM results files (a time scene's)

    @property
    def mappable(self) -> bool:
        """Only through its map observables: a frequency scene has no regimes to map."""
        return bool(self.map_observables)

    def samples_per_run(self, params) -> int:
        """One eigen-analysis, costed like one output sample's run."""
        return 1

    def either(self, time, modes):
        """`modes`: of a workflow's two per-kind functions (or values), the one for this scene."""
        return modes


SCENE_KINDS = {"time": TimeScene, "modes": ModesScene}
