"""Campaigns: many (scene, parameters, solver) jobs on a `concurrent.futures.Executor`.

A campaign file (JSON, or TOML with comments) lists cases; a case may sweep parameters (the
product of the listed values, one case per point, named `<case>/<NAME>=<value>,…`). Everything
is validated before anything runs: the file's shape, scenes, solvers, parameters, values, the
settings and the size of the work (see `budget`); a bad file exits 2 with one line naming the
file and the key.

**Job identity.** A job's result is stored under the digest of its inputs (scene, resolved
parameters, solver(s), settings, package versions and the source code of the solver's model
package, the shared physics and the adapter) in `<campaign>/jobs/`. A rerun reuses a stored
result only when the digest matches — changed parameters run again, and going back to earlier
parameters finds their result again. A result that hit its wall-clock limit is run again.
The case folders hold links to the stored results plus the case report and recording; the
campaign report says which results were reused.

Results are written atomically (temporary name, then rename), so a kill at any moment leaves
complete files or none; a case is compared, recorded and reported as soon as its jobs are in,
and the case's `case.json` (its jobs' digests) is written last, so a case interrupted while
reporting is reported again on resume.

Executor: a local process pool by default (embedded, nothing to start); Dask distributed with
`--executor dask [--scheduler ADDR]` (a LocalCluster when no address is given). Engine
banners and warnings are captured into each job's log (`jobs/<digest>.log`), shown with
`--verbose` and listed in the report.

One campaign at a time per folder: `.lock` holds the owner's pid and host (guard.py); a second
`xval campaign` on the same folder exits 2 naming the owner, a lock whose process is dead is
taken over. Ctrl-C stops the workers (they ignore SIGINT; this process ends them), keeps every
stored result and raises `Interrupted` (the CLI prints one line and exits 130).
"""
import hashlib
import itertools
import json
import time
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import solvers
from ..analysis.trajectory import Trajectory
from ..errors import BadInput
from ..output import guard, progress
from ..output.joblog import captured, distinct_lines
from ..output.progress import PlainProgress
from ..output.store import (
    case_failed,
    link,
    mark_case,
    store_calibration,
    store_modes,
    store_sensitivity,
    store_trajectory,
)
from ..results import ModesResult, TimeResult
from ..scenes import get_scene
from . import plan as planner
from . import power, runner
from .digest import _scene_module, code_digest, job_code, job_digest
from .executors import (  # noqa: F401  (connect: the API's check)
    Interrupted,
    connect,
    execute_many,
    stop,
    terminated_as_interrupt,
    worker_pool,
)

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


# --- the jobs -------------------------------------------------------------------------------

def run_job(job: Job, store: str):
    """One job in a worker: simulate (or compute modes) and store the result under its digest;
    engine output goes to the job's log. Returns (label, status, wall_s, log text)."""
    store = Path(store)
    t0 = time.perf_counter()
    with captured(store / f"{job.key}.log") as text:
        if job.task == "calibration":
            from .calibrate import calibrate
            res = calibrate(job.scene, job.samples, job.seed)
            store_calibration(store, job.key, {"input_digest": job.digest, **res.to_json()})
            status = "ok"
        elif job.task == "sensitivity":
            sc = get_scene(job.scene)
            sens = power.sensitivities(sc, solvers.get_solver(job.solver), job.params,
                                       job.settings, sc.output_grid(job.params), job.timeout_s)
            store_sensitivity(store, job.key, {"input_digest": job.digest,
                                               "solver": job.solver, "sensitivity": sens})
            status = "ok" if sens else "error"
        elif job.solver is None:
            from .modes import run_modes
            d = store / job.key
            res = run_modes(job.scene, list(job.solvers), job.overrides, log=lambda m: None)
            res.extra["input_digest"] = job.digest
            res.extra["code_digest"] = job_code(get_scene(job.scene),
                                                [solvers.get_solver(n) for n in job.solvers])
            store_modes(d, res)
            bad = [r.status for r in res.runs.values() if r.status != "ok"]
            status = bad[0] if bad else "ok"
        else:
            sc = get_scene(job.scene)
            tr = solvers.simulate(sc, solvers.get_solver(job.solver), job.params, job.settings,
                                  job.timeout_s, estimate_error=sc.error_estimate)
            tr.stats["input_digest"] = job.digest
            tr.stats["code_digest"] = job_code(sc, [solvers.get_solver(job.solver)])
            store_trajectory(store, job.key, tr)
            status = tr.status
    return job.label, status, time.perf_counter() - t0, text[0]


def _stored_meta(path):
    with np.load(path, allow_pickle=False) as z:      # reads the `meta` member only
        return json.loads(str(z["meta"]))


def is_done(job, store):
    """Stored with this digest and not stopped by its wall-clock limit."""
    if job.task in ("sensitivity", "calibration"):
        f = store / f"{job.key}.{job.task}.json"
        return f.exists() and json.loads(f.read_text()).get("input_digest") == job.digest
    if job.solver is None:
        f = store / job.key / "modes.json"
        return f.exists() and json.loads(f.read_text()).get("input_digest") == job.digest
    f = store / f"{job.key}.npz"
    if not f.exists():
        return False
    meta = _stored_meta(f)
    return meta["stats"].get("input_digest") == job.digest and meta["status"] != "timeout"


def _stop_workers(ex, store):
    """Cancel what is queued and end the running jobs now. Their results are written under a
    temporary name and renamed when complete, so a stopped job leaves no result file; its
    temporary file (a dot-name) is removed here, under the folder's lock."""
    stop(ex)
    for f in store.glob(".*"):
        f.unlink(missing_ok=True)


@dataclass
class Prepared:
    """A campaign planned: its cases' jobs and its maps, everything validated."""
    camp: dict
    cases: list
    jobs: list
    maps: list


def prepare(source, timeout_s=None, max_output_gib=None, max_steps=None, max_jobs=None):
    """The campaign (a file, a built-in name, None for the default, or the dict itself)
    loaded and planned once: bad input raises BadInput before anything runs."""
    if isinstance(source, dict):
        check_shape(source, "campaign")
        camp, src = source, "campaign"
    else:
        camp, src = load_campaign(source), str(source) if source else "built-in campaign"
    cases, jobs = plan_campaign(camp, src, timeout_s, max_output_gib, max_steps, max_jobs)
    return Prepared(camp, cases, jobs, plan_maps(camp, src, max_jobs))


def run_campaign(path, out, executor="local", scheduler=None, workers=None, timeout_s=None,
                 verbose=False, max_output_gib=None, max_steps=None, view=None, max_jobs=None,
                 prepared=None, folder=None):
    """Plan (everything validated; `prepared`: planned already), run what is not stored yet,
    report each case as its jobs come in, then the campaign report, in `folder` (default
    out/campaign/<name>). Returns the summary (also in summary.json)."""
    p = prepared or prepare(path, timeout_s, max_output_gib, max_steps, max_jobs)
    camp, cases, jobs, maps = p.camp, p.cases, p.jobs, p.maps
    view = view or PlainProgress()
    out_dir = Path(folder) if folder else Path(out) / "campaign" / camp.get("name", "campaign")
    with terminated_as_interrupt(), guard.folder_lock(out_dir, "xval campaign", view.log):
        try:
            return _run_locked(camp, cases, jobs, out_dir, view, executor, scheduler, workers,
                               verbose, maps)
        except KeyboardInterrupt:
            store = out_dir / "jobs"
            n = sum(is_done(j, store) for j in jobs)
            raise Interrupted(f"{n} of {len(jobs)} jobs are stored in {store} and will be "
                              f"reused") from None


def _run_locked(camp, cases, jobs, out_dir, view, executor, scheduler, workers, verbose,
                maps=()):
    # summary.json is the campaign's done-marker (written last): while the campaign runs, or
    # after it was stopped, the folder has none and `xval diff` calls it incomplete
    (out_dir / "summary.json").unlink(missing_ok=True)
    store = out_dir / "jobs"
    reused = {j.label for j in jobs if is_done(j, store)}
    todo = dispatch_order([j for j in jobs if j.label not in reused])
    pending = {c.name: {j.label for j in todo if j.case == c.name} for c in cases}
    pending.update({j.case: {j.label} for j in todo if j.task == "calibration"})
    outcome, crashed = {}, {}
    t0 = time.perf_counter()
    view.log(f"campaign {camp.get('name')}: {len(jobs)} jobs in {len(cases)} cases, "
             f"{len(reused)} stored results reused (inputs unchanged)")
    view.start(len(jobs), len(reused))
    for c in cases:
        if not pending[c.name]:
            outcome[c.name] = _finish_safely(c, jobs, store, out_dir, crashed, reused, view)
    if todo:
        t_start = time.time()
        by_key = {j.key: j for j in todo}
        with worker_pool(executor, scheduler, workers,
                         on_stop=lambda ex: _stop_workers(ex, store)) as ex:
            for o in execute_many({j.key: (run_job, (j, str(store))) for j in todo}, ex,
                                  waiting=lambda keys: view.running(
                                      _started([by_key[k] for k in keys], store, t_start))):
                j = by_key[o.key]
                if o.error is None:
                    _, status, wall, text = o.value
                else:                            # a worker died: record it, keep the rest
                    crashed[j.label] = f"{type(o.error).__name__}: {o.error}".splitlines()[0]
                    status, wall, text = "crashed", None, crashed[j.label]
                view.finished(j.label, status, wall)
                if verbose and text:
                    for line in distinct_lines(text):
                        view.log(f"    {line}")
                pending[j.case].discard(j.label)
                if not pending[j.case] and j.task != "calibration":
                    case = next(c for c in cases if c.name == j.case)
                    view.note(f"writing the report of {case.name}")
                    outcome[case.name] = _finish_safely(case, jobs, store, out_dir,
                                                        crashed, reused, view)
    map_results = [_run_map(name, pl, out_dir, executor, scheduler, workers, view)
                   for name, pl in maps]
    from ..output.campaign_report import write_campaign_report
    return write_campaign_report(camp, cases, jobs, outcome, out_dir, reused, crashed,
                                 time.perf_counter() - t0, map_results,
                                 [_calibration(j, store, crashed) for j in jobs
                                  if j.task == "calibration"])


def _calibration(job, store, crashed):
    """A calibration job's result (`xval calibrate`'s JSON), or why there is none."""
    f = store / f"{job.key}.calibration.json"
    if job.label in crashed or not f.exists():
        return {"scene": job.scene, "samples": job.samples,
                "error": crashed.get(job.label, "no result file")}
    return {k: v for k, v in json.loads(f.read_text()).items() if k != "input_digest"}


def _run_map(name, pl, out_dir, executor, scheduler, workers, view):
    """A campaign's map: its points are jobs stored under a digest of their inputs (scene,
    parameters, solver, settings, package versions, the models' code), so a rerun reuses
    them as it reuses cases."""
    from .maps import map_to_folder
    view.note(f"map {name}: ~{pl['estimate']['runs']} runs")
    with progress.reporting(view=view):         # the map's run counter, through the view
        res = map_to_folder(pl, None, executor=executor, scheduler=scheduler, workers=workers,
                            store=out_dir / "jobs" / "map-points", log=view.log,
                            out_dir=out_dir / "maps" / name)
    res["name"] = name
    view.log(f"map {name}: {sum(res['runs'].values())} runs, {res['reused']} reused")
    return res


def dispatch_order(jobs):
    """Round robin over scene families (a scene module's scenes share their compiled kernels):
    on a fresh clone each worker compiles what its job needs, and two workers starting the same
    family at once compiled the same kernels twice (the sail, press and bearing solver pairs
    each paid ~10 s twice). Each family leads with its frequency cases — one job for all their
    solvers plus a Campbell sweep, the longest jobs (helicopter 26 s against ≤ 8 s for a time
    job) — in reverse registry order, which lists the simplest first: so the pool does not end
    on one worker alone."""
    families: dict = {}
    rank = {id(j): ((0, -i) if j.solver is None else (1 + (j.task != "run"), i))
            for i, j in enumerate(jobs)}
    for j in sorted(jobs, key=lambda j: rank[id(j)]):
        families.setdefault(_scene_module(get_scene(j.scene)), []).append(j)
    waves = itertools.zip_longest(*families.values())
    return [j for wave in waves for j in wave if j is not None]


def _started(jobs, store, since):
    """Jobs a worker has begun: their log was (re)created after `since`. An executor's own
    `running()` also counts jobs merely queued for a worker."""
    out = []
    for j in jobs:
        try:
            if (store / f"{j.key}.log").stat().st_mtime >= since - 1:
                out.append(j.label)
        except OSError:
            pass
    return out


# --- one case's comparison, recording and report ------------------------------------------------

def _finish_safely(case, jobs, store, out_dir, crashed, reused, view):
    """A case whose comparison or report fails is recorded as such; the other cases stand."""
    try:
        return finish_case(case, jobs, store, out_dir, crashed, reused, view)
    except Exception as e:
        import traceback
        msg = f"report failed: {type(e).__name__}: {e}".splitlines()[0]
        log = case_failed(out_dir / case.name, traceback.format_exc())
        view.log(f"{case.name}: {msg} (traceback in {log})")
        for j in jobs:
            if j.case == case.name:
                crashed.setdefault(j.label, msg)
        return {"result": case.scene.either(time=TimeResult.TYPE, modes=ModesResult.TYPE),
                "scene": case.scene.name, "params": case.params, "runs": [],
                "comparisons": [], "findings": [], "error": msg}

def finish_case(case, jobs, store, out_dir, crashed, reused, view):
    """Link the stored results into the case folder, compare, record and report them (unless
    the same results were reported already). Returns the case's result dict."""
    everything = [j for j in jobs if j.case == case.name]
    mine = [j for j in everything if j.task == "run"]
    case_dir = out_dir / case.name
    key = hashlib.sha256(" ".join(j.digest for j in everything).encode()).hexdigest()
    marker = case_dir / "case.json"
    if mine[0].solver is None:
        return _finish_modes(case, mine[0], store, case_dir, crashed)
    done_before = marker.exists() and json.loads(marker.read_text()).get("jobs") == key \
        and (case_dir / "result.json").exists() \
        and not any(j.label in crashed for j in everything)
    if done_before:
        return json.loads((case_dir / "result.json").read_text())
    trs, files = [], {}
    for j in mine:
        f = store / f"{j.key}.npz"
        if f.exists() and j.label not in crashed:
            trs.append(Trajectory.load(f))
            files[j.solver] = link(f, case_dir / f"{j.solver}.npz")
        else:
            t = case.scene.output_grid(case.params)
            trs.append(Trajectory(case.scene.name, j.solver, t,
                                  {c: np.full(len(t), np.nan) for c in case.scene.channels},
                                  status="error",
                                  reason=crashed.get(j.label, "no result file")))
    sens = next((j for j in everything if j.task == "sensitivity"), None)
    with captured(case_dir / "report.log") as text:
        res = runner.finish_run(case.scene, case.params, trs, files, case_dir,
                                power=_case_power(sens, store, crashed))
    if text[0]:
        view.log(f"{case.name}: report phase said: {distinct_lines(text[0], 3)[0]} "
                 f"(see {case_dir / 'report.log'})")
    mark_case(case_dir, key, {j.solver: j.digest for j in mine})
    return res.as_json()


def _case_power(job, store, crashed):
    """The case's detection power estimated from its sensitivity job, as a function of the
    comparisons (None: the case asked for none; a failed job gives no rows, and says so)."""
    if job is None:
        return None
    f = store / f"{job.key}.sensitivity.json"
    if job.label in crashed or not f.exists():
        why = crashed.get(job.label, "no result file")
        return lambda comparisons: ([], f"not measured: the sensitivity job failed ({why})")
    sens = json.loads(f.read_text())["sensitivity"]
    if not sens:
        return lambda comparisons: ([], f"not measured: {job.solver}'s nominal run failed")

    def rows(comparisons):
        r = power.estimated(comparisons, sens, job.solver)
        return [x.as_dict() for x in r], power.summary(r)
    return rows


def _finish_modes(case, job, store, case_dir, crashed):
    src = store / job.key
    if job.label in crashed or not (src / "modes.json").exists():
        return {"result": ModesResult.TYPE, "scene": case.scene.name, "params": case.params,
                "runs": [], "comparisons": [], "findings": [],
                "error": crashed.get(job.label, "no result file")}
    for f in sorted(src.iterdir()):
        if f.is_file() and not f.name.startswith("."):
            link(f, case_dir / f.name)
    obj = json.loads((case_dir / "modes.json").read_text())
    obj["report"] = str(case_dir / "report.md")
    for key in ("recording", "mode_shapes_recording", "mode_shapes_figure",
                "frequencies_figure"):
        if obj.get(key):
            obj[key] = str(case_dir / Path(obj[key]).name)
    obj.setdefault("findings", [])
    return obj

