"""A campaign's file and its plan: the built-in campaigns, loading a campaign file (JSON, or TOML
with comments), checking its shape, expanding sweeps into cases, and planning every case's jobs
and every map before anything runs (compare/workflows/campaign.py runs them).

A case may sweep parameters (the product of the listed values, one case per point, named
`<case>/<NAME>=<value>,…`). Everything is validated up front: the file's shape, scenes,
solvers, parameters, values, the settings and the size of the work (see `budget`); a bad file
exits 2 with one line naming the file and the key."""
import hashlib
import itertools
import json
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import solvers
from ..errors import BadInput
from ..output import progress
from ..scenes import get_scene
from . import plan as planner
from . import power
from .digest import code_digest, job_digest

TOP_KEYS = ("name", "cases", "maps", "calibrate", "max_output_gib", "max_steps", "max_jobs")
MAP_KEYS = ("name", "scene", "x", "y", "set", "solvers", "resolution", "coarse", "observable",
            "level", "engines", "y_resolution")
MAX_JOBS = 10_000          # jobs (cases × solvers) a campaign may plan before it is refused
CASE_KEYS = ("name", "scene", "set", "sweep", "solvers", "dt", "rtol", "integrator",
             "settings", "timeout_s", "power")


BUILT_IN = ("default", "long", "benchmarks")   # benchmarks: the `benchmarks` group's


def default_campaign(name: str = "default") -> dict:
    """A built-in campaign from the scenes' own cases (`Scene.campaign_cases`): "default" (every
    scene, every solver, minutes) or "long" (the cases a scene marks `"campaign": "long"`, e.g.
    the engines' full sail deployment, tens of minutes) or "benchmarks" (the cases marked
    `"campaign": "benchmarks"` and the maps of the `benchmarks` group's scenes, which the
    default campaign leaves to it)."""
    from ..scenes import SCENES
    # the default campaign's time cases report their detection power (`power`: one
    # sensitivity run per physical parameter of the case's first solver)
    camp = {"name": name,
            "cases": [{"scene": sc.name, **({"power": True} if name == "default"
                                            and sc.power_in_campaign else {}),
                       **{k: v for k, v in case.items() if k != "campaign"}}
                      for sc in SCENES.values() for case in sc.campaign_cases
                      if case.get("campaign", "default") == name]}
    if name in ("default", "benchmarks"):   # each scene's default maps (of the group)
        camp["maps"] = [{"name": f"{sc.name}-{m.name}", "scene": sc.name, "x": m.x,
                         **({"y": m.y} if m.y else {}), "set": dict(m.set),
                         "resolution": m.resolution, "coarse": list(m.coarse),
                         **({"y_resolution": m.y_resolution} if m.y_resolution else {}),
                         **({"solvers": list(m.solvers)} if m.solvers else {}),
                         **({"observable": m.observable} if m.observable else {}),
                         **({"level": m.level} if m.level is not None else {}),
                         "engines": m.engines}
                        for sc in SCENES.values() for m in sc.maps
                        if (sc.group == "benchmarks") == (name == "benchmarks")]
        # the other error rate: false alarms over sets drawn off the defaults (`xval
        # calibrate`), for each scene whose runs fit the budget
        camp["calibrate"] = [{"scene": sc.name, "samples": sc.calibration.campaign}
                             for sc in SCENES.values()
                             if name == "default" and sc.calibration
                             and sc.calibration.campaign]
    return camp


# --- the file -------------------------------------------------------------------------------

def load_campaign(path) -> dict:
    """The campaign as a dict, its shape checked (names, types, known keys); BadInput with one
    line `FILE: KEY: problem` otherwise."""
    if path is None:
        return default_campaign()
    p = Path(path)
    if str(path) in BUILT_IN and not p.exists():
        return default_campaign(str(path))
    try:
        text = p.read_text()
    except (OSError, UnicodeDecodeError) as e:
        raise BadInput(f"campaign file {path}: cannot read it "
                       f"({getattr(e, 'strerror', None) or e})") from None
    if p.suffix.lower() == ".toml":
        try:
            camp = tomllib.loads(text)
        except tomllib.TOMLDecodeError as e:
            raise BadInput(f"{path}: TOML syntax: {e}") from None
    else:
        try:
            camp = json.loads(text)
        except json.JSONDecodeError as e:
            raise BadInput(f"{path}: JSON syntax at line {e.lineno}, column {e.colno}: "
                           f"{e.msg}") from None
    check_shape(camp, str(path))
    return camp


def _is_num(x):
    return isinstance(x, (int, float)) and not isinstance(x, bool) and np.isfinite(x)


def check_shape(camp, src):
    def bad(key, problem):
        raise BadInput(f"{src}: {key}: {problem}")

    if not isinstance(camp, dict):
        bad("top level", "must be a table/object with `cases`")
    for k in camp:
        if k not in TOP_KEYS:
            bad(k, f"unknown key (known: {', '.join(TOP_KEYS)})")
    if "name" in camp and not _safe_name(camp["name"]):
        bad("name", f"{camp['name']!r} must be a non-empty string without '/'")
    for k in ("max_output_gib", "max_steps"):
        if k in camp and not (_is_num(camp[k]) and camp[k] > 0):
            bad(k, f"must be a positive number, got {camp[k]!r}")
    if "max_jobs" in camp and not (isinstance(camp["max_jobs"], int) and camp["max_jobs"] > 0):
        bad("max_jobs", f"must be a positive whole number, got {camp['max_jobs']!r}")
    maps = camp.get("maps", [])
    if not isinstance(maps, list):
        bad("maps", "must be a list of maps ([[maps]] in TOML)")
    for i, m in enumerate(maps):
        if not isinstance(m, dict):
            bad(f"maps[{i}]", "must be a table/object")
        for k in m:
            if k not in MAP_KEYS:
                bad(f"maps[{i}].{k}", f"unknown key (known: {', '.join(MAP_KEYS)})")
        for k in ("scene", "x"):
            if not isinstance(m.get(k), str):
                bad(f"maps[{i}].{k}", "missing or not a string")
        if "name" in m and not _safe_name(m["name"]):
            bad(f"maps[{i}].name", f"{m['name']!r} must be a non-empty string without '/'")
    cals = camp.get("calibrate", [])
    if not isinstance(cals, list):
        bad("calibrate", "must be a list of {scene, samples, seed} ([[calibrate]] in TOML)")
    for i, c in enumerate(cals):
        if not (isinstance(c, dict) and isinstance(c.get("scene"), str)
                and set(c) <= {"scene", "samples", "seed"}):
            bad(f"calibrate[{i}]", "must be a table with `scene` and optionally `samples`, "
                                   "`seed`")
        for k, lo in (("samples", 1), ("seed", 0)):
            if k in c and not (isinstance(c[k], int) and c[k] >= lo):
                bad(f"calibrate[{i}].{k}", f"must be a whole number ≥ {lo}, got {c[k]!r}")
    cases = camp.get("cases")
    if (not isinstance(cases, list) or not cases) and not maps:
        bad("cases", "missing or empty: a list of cases ([[cases]] in TOML)")
    cases = cases or []
    if not isinstance(cases, list):
        bad("cases", "must be a list of cases ([[cases]] in TOML)")
    for i, c in enumerate(cases):
        at = f"cases[{i}]"
        if not isinstance(c, dict):
            bad(at, "must be a table/object")
        for k in c:
            if k not in CASE_KEYS:
                bad(f"{at}.{k}", f"unknown key (known: {', '.join(CASE_KEYS)})")
        if "scene" not in c:
            bad(f"{at}.scene", "missing")
        if not isinstance(c["scene"], str):
            bad(f"{at}.scene", f"must be a scene name, got {c['scene']!r}")
        if "name" in c and not _safe_name(c["name"]):
            bad(f"{at}.name", f"{c['name']!r} must be a non-empty string without '/'")
        for k in ("set", "sweep", "settings"):
            if k in c and not isinstance(c[k], dict):
                bad(f"{at}.{k}", "must be a table/object")
        if "solvers" in c and not (isinstance(c["solvers"], list) and c["solvers"]
                                   and all(isinstance(s, str) for s in c["solvers"])):
            bad(f"{at}.solvers", "must be a non-empty list of solver names")
        if "power" in c and not isinstance(c["power"], bool):
            bad(f"{at}.power", f"must be true or false, got {c['power']!r}")
        for k in ("dt", "rtol", "timeout_s"):
            if k in c and not (_is_num(c[k]) and c[k] > 0):
                bad(f"{at}.{k}", f"must be a positive number, got {c[k]!r}")
        if "integrator" in c and not isinstance(c["integrator"], str):
            bad(f"{at}.integrator", f"must be a name, got {c['integrator']!r}")
        for name, values in c.get("sweep", {}).items():
            sweep_values(values, f"{src}: {at}.sweep.{name}")
        for name, st in c.get("settings", {}).items():
            if not isinstance(st, dict):
                bad(f"{at}.settings.{name}", "must be a table of settings for that solver")


def _safe_name(x):
    return isinstance(x, str) and x.strip() != "" and "/" not in x and not x.startswith(".")


def sweep_values(spec, where):
    """A sweep's values: a non-empty list, or {start, stop, num} (evenly spaced, both ends)."""
    if isinstance(spec, list) and spec:
        return spec
    if isinstance(spec, dict) and set(spec) == {"start", "stop", "num"} \
            and _is_num(spec["start"]) and _is_num(spec["stop"]) \
            and isinstance(spec["num"], int) and spec["num"] >= 2:
        return [float(v) for v in np.linspace(spec["start"], spec["stop"], spec["num"])]
    raise BadInput(f"{where}: must be a non-empty list of values or "
                   f"{{start, stop, num ≥ 2}}, got {spec!r}")


def value_text(v):
    """A parameter value as it appears in a sweep point's name: 1.5, 3, 0,0,-9.81."""
    if isinstance(v, (list, tuple)):
        return ",".join(value_text(x) for x in v)
    if isinstance(v, float):
        return f"{v:.12g}"
    return str(v)


# --- the plan -------------------------------------------------------------------------------

@dataclass
class Case:
    name: str                       # `<case>` or `<case>/<NAME>=<value>,…` for a sweep point
    scene: object
    params: dict                    # resolved
    solvers: list                   # Solver objects
    sweep_parent: str | None = None
    point: dict = field(default_factory=dict)        # swept name -> value


@dataclass
class Job:
    case: str
    scene: str
    params: dict
    overrides: dict
    solver: str | None              # None: a frequency case, one job for all its solvers
    solvers: tuple
    settings: dict
    timeout_s: float | None
    digest: str
    # "run", "sensitivity": the solver's response to each physical parameter, from which
    # the case's detection power is estimated (`power.sensitivities`), or "calibration": the
    # scene's `xval calibrate` over `samples` sets drawn with `seed`
    task: str = "run"
    samples: int = 0
    seed: int = 0

    @property
    def label(self):
        if self.task == "calibration":
            return self.case
        return f"{self.case}/{self.solver or 'modes'}" + (
            "" if self.task == "run" else f" {self.task}")

    @property
    def key(self):
        return self.digest[:24]


def _prefixed(where, fn, *args, **kw):
    try:
        return fn(*args, **kw)
    except BadInput as e:
        raise BadInput(f"{where}: {e}") from None


def plan_campaign(camp, src="built-in campaign", timeout_s=None, max_output_gib=None,
                  max_steps=None, max_jobs=None):
    """Validate every case and sweep point up front (bad input stops the campaign before
    anything runs) and list the jobs."""
    max_output_gib = max_output_gib or camp.get("max_output_gib")
    max_steps = max_steps or camp.get("max_steps")
    max_jobs = max_jobs or camp.get("max_jobs") or MAX_JOBS
    # the size of the work first, from the sweeps' lengths alone: a sweep of a million points
    # is refused in milliseconds, before any point is built or checked
    n_jobs = 0
    for i, c in enumerate(camp.get("cases", [])):
        n = 1
        for spec in c.get("sweep", {}).values():
            n *= (spec["num"] if isinstance(spec, dict) and isinstance(spec.get("num"), int)
                  else len(spec) if isinstance(spec, list) else 1)
        n_jobs += n * len(c.get("solvers")
                          or _prefixed(f"{src}: cases[{i}].scene", get_scene, c["scene"]).leaves)
    if n_jobs > max_jobs:
        raise BadInput(f"{src}: {n_jobs} jobs (cases × sweep points × solvers) exceed the "
                       f"budget of {max_jobs}: shorten the sweeps or set max_jobs "
                       f"(or --max-jobs)")
    cases, jobs, names = [], [], set()
    bar = progress.task("planning", len(camp.get("cases", [])), "cases")
    for i, c in enumerate(camp.get("cases", [])):
        at = f"{src}: cases[{i}]"
        sc = _prefixed(f"{at}.scene", get_scene, c["scene"])
        name = c.get("name") or f"case{i}-{sc.name}"
        if name in names:
            raise BadInput(f"{at}.name: duplicate case name {name!r}")
        names.add(name)
        _prefixed(f"{at}.solvers", solvers.pick, sc, c.get("solvers"))
        sweep = c.get("sweep", {})
        for pname, spec in sweep.items():           # names and values, one by one
            param = _prefixed(f"{at}.sweep", sc.param, pname)
            for v in sweep_values(spec, f"{at}.sweep.{pname}"):
                _prefixed(f"{at}.sweep.{pname}", param.parse, v)
        for pname, v in c.get("set", {}).items():
            param = _prefixed(f"{at}.set", sc.param, pname)
            _prefixed(f"{at}.set.{pname}", param.parse, v)
        grids = [sweep_values(sweep[k], "") for k in sweep]
        runs = c.get("solvers") or list(sc.leaves)      # settings for others are ignored
        knobs = _prefixed(at, planner.Knobs, c.get("dt"), c.get("rtol"), c.get("integrator"))
        limits = planner.Limits(max_output_gib, max_steps)
        for combo in itertools.product(*grids) if sweep else [()]:
            point = dict(zip(sweep, combo))
            pname = name + ("/" + ",".join(f"{k}={value_text(v)}" for k, v in point.items())
                            if point else "")
            where = f"{at}" + (f" sweep point {pname}" if point else "")
            overrides = {**c.get("set", {}), **point}
            pl = _prefixed(where, planner.plan, sc, overrides, c.get("solvers"),
                           {k: v for k, v in c.get("settings", {}).items() if k in runs},
                           knobs, limits, timeout_s=c.get("timeout_s", timeout_s))
            cases.append(Case(pname, sc, pl.params, list(pl.solvers), name if point else None,
                              point))
            if pl.t_out is None:                  # a frequency case: one job, all its solvers
                jobs.append(Job(pname, sc.name, pl.params, overrides, None, tuple(pl.names), {},
                                pl.timeout_s, pl.digest()))
                continue
            for s in pl.solvers:
                jobs.append(Job(pname, sc.name, pl.params, overrides, s.name, (s.name,),
                                pl.settings[s.name], pl.timeout_s, pl.only(s).digest()))
            if c.get("power") and len(pl.solvers) > 1:
                s = pl.solvers[0]            # the registry lists a scene's own solvers first
                d = hashlib.sha256(f"{pl.only(s).digest()}|sensitivity|{power.H!r}".encode())
                jobs.append(Job(pname, sc.name, pl.params, overrides, s.name, (s.name,),
                                pl.settings[s.name], pl.timeout_s, d.hexdigest(),
                                "sensitivity"))
        bar.advance()
    bar.close()
    for i, c in enumerate(camp.get("calibrate", [])):
        sc = _prefixed(f"{src}: calibrate[{i}].scene", get_scene, c["scene"])
        n, seed = c.get("samples", 2), c.get("seed", 0)
        chosen = [solvers.get_solver(s) for s in sc.leaves]
        code = code_digest({"compare.workflows.calibrate"})
        d = hashlib.sha256(f"calibration|{n}|{seed}|{code}|"
                           f"{job_digest(sc, sc.resolve({}), chosen, {})}".encode())
        jobs.append(Job(f"calibration/{sc.name}", sc.name, {}, {}, None, tuple(sc.leaves), {},
                        timeout_s, d.hexdigest(), "calibration", n, seed))
    return cases, jobs


def plan_maps(camp, src="built-in campaign", max_jobs=None):
    """Every `[[maps]]` entry planned (validated, its work estimated) before anything runs."""
    from .maps import plan_map
    out, names = [], set()
    for i, m in enumerate(camp.get("maps", [])):
        at = f"{src}: maps[{i}]"
        name = m.get("name") or f"map{i}-{m['scene']}"
        if name in names:
            raise BadInput(f"{at}.name: duplicate map name {name!r}")
        names.add(name)
        pl = _prefixed(at, plan_map, m["scene"], m["x"], m.get("y"), m.get("set"),
                       m.get("solvers"), m.get("resolution", 1e-3),
                       m.get("coarse"), m.get("observable"), m.get("level"),
                       m.get("engines", "boundary"), max_jobs or camp.get("max_jobs"),
                       m.get("y_resolution"))
        out.append((name, pl))
    return out
