"""Campaigns: many (scene, overrides, solver) jobs on a `concurrent.futures.Executor`.

Jobs are pure functions of (scene, parameters, solver, settings) that write one result file
atomically; a rerun skips jobs whose file exists (resume after a kill); a crashed job is recorded
with its message and its neighbours stand. Trajectories are compared, recorded (one .rrd per
case, written by this process only) and reported after all jobs of a case are in.

Executor: a local process pool by default (embedded, nothing to start); Dask distributed with
`--executor dask [--scheduler ADDR]` (a LocalCluster when no address is given).
"""
from concurrent.futures import ProcessPoolExecutor, as_completed
import json
import multiprocessing
from pathlib import Path

from . import runner, solvers
from .atomic import write_json, write_text
from .errors import BadInput
from .scenes import get_scene
from .trajectory import Trajectory

DEFAULT_CAMPAIGN = {
    "name": "default",
    "cases": [
        {"name": "rotor-spinup-1.5Nm", "scene": "rotor-spinup"},
        {"name": "rotor-spinup-3.2Nm", "scene": "rotor-spinup",
         "set": {"torque": "3.2", "t_end": "5"}},
        {"name": "rotor-whirl", "scene": "rotor-whirl"},
        {"name": "press", "scene": "press"},
        {"name": "press-cycle", "scene": "press-cycle"},
        # full deployment: both custom variants and Exudyn (~4 min; MuJoCo needs ~15 min at
        # k = 1e7 and checks the first 2 s here)
        {"name": "sail-deploy-full", "scene": "sail-deploy",
         "solvers": ["thread-spool", "thread-spool-conservative", "exudyn"], "timeout_s": 3600},
        {"name": "sail-deploy-2s", "scene": "sail-deploy", "set": {"t_end": 2}},
    ],
}


def load_campaign(path):
    if path is None:
        return DEFAULT_CAMPAIGN
    try:
        camp = json.loads(Path(path).read_text())
        cases = camp["cases"]
        assert isinstance(cases, list) and cases
    except (OSError, ValueError, KeyError, TypeError, AssertionError) as e:
        raise BadInput(f"campaign file {path}: unreadable ({type(e).__name__}: {e})") from None
    return camp


def plan(camp, timeout_s=None):
    """Validate every case up front (bad input stops the campaign before anything runs).
    A job is (case, scene, overrides, solver, settings, timeout_s): the case's `timeout_s`,
    else the campaign-wide one."""
    jobs, cases = [], []
    names = set()
    for i, c in enumerate(camp["cases"]):
        sc = get_scene(c.get("scene", ""))
        name = c.get("name") or f"case{i}-{sc.name}"
        if name in names or "/" in name:
            raise BadInput(f"campaign case name {name!r}: duplicate or contains '/'")
        names.add(name)
        params = sc.resolve({k: str(v) for k, v in c.get("set", {}).items()})
        chosen = solvers.pick(sc, c.get("solvers"))
        settings = {s.name: solvers.settings_for(
            s, sc.name, c.get("dt"), c.get("rtol"), c.get("integrator"),
            c.get("settings", {}).get(s.name)) if sc.kind == "time" else {} for s in chosen}
        limit = c.get("timeout_s", timeout_s)
        if limit is not None and not (isinstance(limit, (int, float)) and limit > 0):
            raise BadInput(f"campaign case {name!r}: timeout_s must be a positive number of "
                           f"seconds, got {limit!r}")
        cases.append((name, sc, params, chosen))
        if sc.kind == "time":
            jobs += [(name, sc.name, c.get("set", {}), s.name, settings[s.name], limit)
                     for s in chosen]
        else:
            jobs.append((name, sc.name, c.get("set", {}), None, {}, limit))
    return cases, jobs


def run_job(case, scene_name, overrides, solver_name, settings, timeout_s, out_dir):
    """One job in a worker: simulate (or compute modes) and write the result file atomically."""
    sc = get_scene(scene_name)
    params = sc.resolve({k: str(v) for k, v in overrides.items()})
    case_dir = Path(out_dir) / case
    if solver_name is None:                      # a frequency case: one job for all solvers
        from .modes import run_modes
        obj, _, _ = run_modes(scene_name, None, {k: str(v) for k, v in overrides.items()},
                              None, log=lambda m: None, out_dir=case_dir)
        write_json(case_dir / "modes.json", obj)
        return case, None, "ok"
    tr = solvers.simulate(sc, solvers.get_solver(solver_name), params, settings, timeout_s)
    tr.save(case_dir / f"{solver_name}.npz")
    return case, solver_name, tr.status


def _job_file(out_dir, job):
    case, _, _, solver_name, _, _ = job
    return Path(out_dir) / case / (f"{solver_name}.npz" if solver_name else "modes.json")


def _done(out_dir, job):
    """A job is done when its result file exists, unless it timed out (a resume with a larger
    limit runs it again)."""
    f = _job_file(out_dir, job)
    return f.exists() and (job[3] is None or Trajectory.load(f).status != "timeout")


def make_executor(kind, scheduler, workers):
    if kind == "dask":
        try:
            from distributed import Client, LocalCluster
        except ImportError:
            raise BadInput("--executor dask needs the optional extra: pip install "
                           "'xval[dask]'") from None
        client = Client(scheduler) if scheduler else Client(LocalCluster(
            n_workers=workers or 2, threads_per_worker=1, dashboard_address=None))
        return client.get_executor(), client
    # spawn: engines start threads; a forked child would inherit a half-initialised state
    return ProcessPoolExecutor(max_workers=workers or 2,
                               mp_context=multiprocessing.get_context("spawn")), None


def run_campaign(path, out, executor="local", scheduler=None, workers=None, log=print,
                 timeout_s=None):
    camp = load_campaign(path)
    cases, jobs = plan(camp, timeout_s)
    out_dir = Path(out) / "campaign" / camp.get("name", "campaign")
    todo = [j for j in jobs if not _done(out_dir, j)]
    log(f"campaign {camp.get('name')}: {len(jobs)} jobs, {len(jobs) - len(todo)} already done")
    crashed = {}
    if todo:
        ex, client = make_executor(executor, scheduler, workers)
        try:
            futures = {ex.submit(run_job, *j, str(out_dir)): j for j in todo}
            for f in as_completed(futures):
                j = futures[f]
                try:
                    case, solver, status = f.result()
                    log(f"  {case} {solver or 'modes'}: {status}")
                except Exception as e:           # a worker died: record it, keep the rest
                    crashed[(j[0], j[3])] = f"{type(e).__name__}: {e}"
                    log(f"  {j[0]} {j[3]}: crashed ({e})")
        finally:
            ex.shutdown(wait=True)
            if client is not None:
                client.close()
    return _report(camp, cases, out_dir, crashed, len(jobs) - len(todo), log)


def _report(camp, cases, out_dir, crashed, n_skipped, log):
    lines = [f"# Campaign `{camp.get('name')}`", "",
             "| case | scene | solvers ok | failed | verdicts | report |", "|---|---|---|---|---|---|"]
    summary = {"name": camp.get("name"), "n_jobs": 0, "n_skipped": n_skipped, "n_failed": 0,
               "n_crashed": len(crashed), "cases": []}
    for name, sc, params, chosen in cases:
        case_dir = out_dir / name
        if sc.kind == "modes":
            summary["n_jobs"] += 1
            f = case_dir / "modes.json"
            if not f.exists():
                lines.append(f"| {name} | {sc.name} | — | crashed | — | — |")
                continue
            obj = json.loads(f.read_text())
            verdicts = [c["verdict"] for c in obj["comparisons"]]
            ok = [r["solver"] for r in obj["runs"] if r["status"] == "ok"]
            bad = [r["solver"] for r in obj["runs"] if r["status"] != "ok"]
            rel = Path(obj["report"]).relative_to(out_dir) if obj.get("report") else ""
            lines.append(f"| {name} | {sc.name} | {', '.join(ok)} | {', '.join(bad) or '—'} | "
                         f"{verdicts.count('agree')} agree, {verdicts.count('disagree')} disagree"
                         f" | [report]({rel}) |")
            summary["cases"].append({"case": name, "scene": sc.name, "modes": obj})
            continue
        trs, files = [], {}
        for s in chosen:
            summary["n_jobs"] += 1
            f = case_dir / f"{s.name}.npz"
            if f.exists():
                trs.append(Trajectory.load(f))
                files[s.name] = f
            else:
                msg = crashed.get((name, s.name), "no result file")
                t = sc.output_grid(params)
                import numpy as np
                trs.append(Trajectory(sc.name, s.name, t, {c: np.full(len(t), np.nan)
                                                          for c in sc.channels},
                                      status="error", reason=msg))
        res = runner.finish_run(sc, params, trs, files, case_dir)
        obj = res.as_json()
        failed = [t.solver for t in trs if t.status != "ok"]
        summary["n_failed"] += bool(failed)
        v = [c.verdict for c in res.comparisons]
        lines.append(f"| {name} | {sc.name} | {', '.join(t.solver for t in trs if t.status == 'ok')}"
                     f" | {', '.join(failed) or '—'} | {v.count('agree')} agree, "
                     f"{v.count('disagree')} disagree | [report]({name}/report.md) |")
        summary["cases"].append({"case": name, **obj})
        for fnd in res.findings:
            lines_f = summary.setdefault("_findings", [])
            lines_f.append(f"- **{name}**: {fnd.text}")
    lines += ["", "## Findings", ""] + summary.pop("_findings", [])
    report = out_dir / "report.md"
    write_text(report, "\n".join(lines) + "\n")
    summary["report"] = str(report)
    write_json(out_dir / "summary.json", summary)
    log(f"campaign report: {report}")
    return summary
