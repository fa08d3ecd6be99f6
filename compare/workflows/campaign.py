"""Campaigns: many (scene, parameters, solver) jobs on a `concurrent.futures.Executor`.

The campaign file, its checks and its plan are compare/workflows/campaign_plan.py's; this
module runs the planned jobs and maps and finishes each case.

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
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import solvers
from ..analysis.trajectory import Trajectory
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
from . import power, runner
from .campaign_plan import Job, check_shape, load_campaign, plan_campaign, plan_maps
from .digest import _scene_module, job_code
from .executors import (  # noqa: F401  (connect: the API's check)
    Interrupted,
    connect,
    execute_many,
    stop,
    terminated_as_interrupt,
    worker_pool,
)

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

