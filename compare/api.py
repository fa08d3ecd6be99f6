"""The Python API (`import xval`): the same engine as the `xval` command, which is a thin layer
over these functions. Every call returns a `Result` (compare/results/); bad arguments raise
`BadInput` with the command's one-line message, before anything runs or is written.

Files: with `out=FOLDER` a call writes what the command writes there (a run: the .npz per
solver, run.rrd, report.md with plots, result.json, in FOLDER/runs/<scene>-<stamp>-<pid>/).
Without `out` a run, modes, extremes, power or diff result is held in memory and nothing is
written; a bench, map or campaign (which store what they compute as they go, to resume from)
works in a temporary folder that goes away with the result. `result.save(path)` writes the
files then; `xval.load(path)` reads any of them back.
"""
from __future__ import annotations

import contextlib
import shutil
from collections.abc import Callable
from pathlib import Path

from .errors import BadInput
from .output.folders import check_out, make_out, temporary_folder
from .results import (
    BenchResult,
    CampaignResult,
    DiffResult,
    ExtremesResult,
    MapResult,
    ModesResult,
    PowerResult,
    ResponseResult,
    Result,
    SceneInfo,
    TimeResult,
)
from .results.tables import disagreement_message
from .workflows.inputs import positive, positive_int
from .workflows.plan import names as _names
from .workflows.plan import per_solver_settings  # noqa: F401  (the API's documented helper)


def _overrides(params: dict | None, kw: dict) -> dict:
    """Scene parameters from `params={...}` and keywords (either, not the same name twice);
    values as the scene reads them from `--set` or a campaign file (numbers, strings, lists
    for vectors)."""
    twice = sorted(set(params or {}) & set(kw))
    if twice:
        raise BadInput(f"{twice[0]}: given twice (params= and a keyword)")
    return {**(params or {}), **kw}


def _quiet(msg):
    pass


@contextlib.contextmanager
def _removed_on_error(temporary):
    """A temporary folder does not outlive a call that fails."""
    try:
        yield
    except BaseException:
        if temporary:
            shutil.rmtree(temporary, ignore_errors=True)
        raise


def _out(out):
    """(folder, temporary folder or None): `out` checked, or a fresh temporary folder."""
    if out is None:
        tmp = temporary_folder()
        return tmp, tmp
    check_out(str(out))
    return str(out), None


def run(scene: str, solvers=None, settings: dict | None = None, *, dt=None, rtol=None,
        integrator: str | None = None, out=None, record: bool | None = None,
        timeout=None, max_output_gib=None, max_steps=None, estimate_errors: bool = True,
        params: dict | None = None, log: Callable | None = None, **kw) -> TimeResult:
    """Simulate a time-domain scene with each solver (default: every solver of the scene),
    compare them pairwise, and return a `TimeResult`.

    Scene parameters as keywords (`torque=3.2, t_end=5`) or `params={...}`. `settings`: one
    dict for every solver or one per solver name (see `per_solver_settings`), passed to the
    leaves as they are; `dt` / `rtol` / `integrator` as `--dt` / `--rtol` / `--integrator`
    (which also switch an adaptive default to a fixed-step method and back). `out`: write the
    run's files there (default: nothing kept); `record`: the rerun recording (default: when
    `out` is given; the report is written whenever `out` is). `timeout`: wall-clock limit per
    solver (s). `estimate_errors=False` skips the tighter rerun that estimates each solver's
    own error (half the time; the verdicts then weigh the deviation against the scene's
    allowance alone). `log`: a callable for progress lines (default: silent)."""
    from .scenes import get_scene
    from .workflows import runner
    from .workflows.plan import Knobs, Limits, plan
    sc = get_scene(scene)
    if not sc.is_time:
        raise BadInput(f"scene {sc.name!r} is a frequency scene: use `xval modes {sc.name}`")
    if out is not None:
        check_out(str(out))
    if record and out is None:
        raise BadInput("record=True needs out=FOLDER (or call .save(path) on the result)")
    knobs = Knobs(positive("--dt", dt), positive("--rtol", rtol), integrator)
    limits = Limits(positive("--max-output-gib", max_output_gib),
                    positive("--max-steps", max_steps))
    # everything checked (solvers, budgets, parameters, settings) before anything runs
    pl = plan(sc, _overrides(params, kw), _names(solvers), settings, knobs, limits,
              timeout_s=positive("--timeout", timeout), estimate_errors=estimate_errors)
    log = log or _quiet
    out_dir = None
    if out is not None:
        make_out(str(out))
        out_dir = runner.new_run_dir(out, sc.name)
    if knobs.rtol is not None:
        for s in pl.solvers:
            if not s.info(sc).adaptive:
                log(f"{s.name}: no error-controlled integrator, --rtol ignored (fixed step kept)")
    try:                 # with `out` the report is written, as by `xval run`; else nothing
        return runner.execute(pl, out_dir, record=out is not None if record is None else record,
                              report=out is not None, log=log)
    except OSError as e:                 # disk full / read-only: one line, folder stays marked
        from .output.guard import write_failure
        if write_failure(e) is None:
            raise
        raise BadInput(f"{write_failure(e)}; {out_dir} is left marked incomplete") from None


def modes(scene: str, solvers=None, *, out=None, params: dict | None = None,
          log: Callable | None = None, campbell_frame: str | None = None,
          **kw) -> ModesResult:
    """Natural frequencies from every solver that linearises (default: all of the scene's),
    matched mode by mode; the Campbell diagram and critical speeds where the scene sweeps (the
    figure in `campbell_frame`, "fixed" or "rotating"; default: the solvers' frame), the mode
    shapes where it draws them. Returns a `ModesResult`."""
    from .workflows.modes import run_modes
    from .workflows.runner import new_run_dir
    overrides = _overrides(params, kw)
    names = _names(solvers)
    if out is not None:
        check_out(str(out))
    res = run_modes(scene, names, overrides, log=log or _quiet, campbell_frame=campbell_frame)
    if out is not None:
        res.save(new_run_dir(out, res.scene_name))
    return res


def response(scene: str, solvers=None, *, speeds: int = 24, out=None,
             params: dict | None = None, log: Callable | None = None,
             **kw) -> ResponseResult:
    """The steady unbalance response vs spin through the first critical speed (`xval
    response`): every solver that takes the unbalance into its linear model (frequency
    domain) and the scene's time solvers at constant spin (time domain), judged speed by speed
    on amplitude and phase; peaks, Q, half-power ζ. Returns a `ResponseResult`."""
    from .workflows.response import run_response
    from .workflows.runner import new_run_dir
    overrides = _overrides(params, kw)
    n = positive_int("--speeds", speeds)
    if out is not None:
        check_out(str(out))
    res = run_response(scene, _names(solvers), overrides, n, log=log or _quiet)
    if out is not None:
        res.save(new_run_dir(out, scene))
    return res


def bench(scene: str, solvers=None, *, repeats: int = 3, vary=None, out=None,
          max_output_gib=None, max_steps=None, params: dict | None = None,
          log: Callable | None = None, points: int | None = None, **kw) -> BenchResult:
    """Work-precision sweep (`xval bench`): each solver along its accuracy knob, error of the
    key channel against a tight reference, median wall time of `repeats` runs. `vary`: trade a
    model parameter instead, as `"stiffness=1e5,1e6"` or `{"stiffness": [1e5, 1e6]}`.
    `points=N`: throughput instead — each solver's points per second over N points of the
    scene's first default map."""
    from .workflows.bench import run_bench, run_throughput
    positive_int("--repeats", repeats)
    if points is not None:              # throughput: points per second over the default map
        positive_int("--points", points)
        out, temporary = _out(out)
        with _removed_on_error(temporary):
            obj = run_throughput(scene, _names(solvers), _overrides(params, kw), out, points,
                                 log=log or _quiet, make_out=make_out)
        return BenchResult(obj, Path(obj["report"]).parent, temporary)
    max_output_gib, max_steps = (positive("--max-output-gib", max_output_gib),
                                 positive("--max-steps", max_steps))
    if isinstance(vary, dict):
        if len(vary) != 1:
            raise BadInput(f"--vary: one parameter, got {len(vary)}")
        (name, values), = vary.items()
        vary = f"{name}={','.join(repr(v) for v in values)}"
    overrides = _overrides(params, kw)
    out, temporary = _out(out)
    with _removed_on_error(temporary):
        obj = run_bench(scene, _names(solvers), overrides, out, repeats=repeats,
                        log=log or _quiet, vary=vary, max_output_gib=max_output_gib,
                        max_steps=max_steps, make_out=make_out)
    return BenchResult(obj, Path(obj["report"]).parent, temporary)


def extremes(scene: str, solvers=None, *, include_slow: bool = False, timeout=None, out=None,
             log: Callable | None = None) -> ExtremesResult:
    """Every extreme case of the scene's spec with every solver (`xval extremes`; the long
    cases with `include_slow=True`, the command's `--all`)."""
    from .workflows.extremes import extremes_dir, run_extremes
    timeout = positive("--timeout", timeout)
    names = _names(solvers)
    if out is not None:
        check_out(str(out))
    res = run_extremes(scene, names, include_slow=include_slow, timeout_s=timeout,
                       log=log or _quiet)
    if out is not None:
        res.save(extremes_dir(out, scene))
    return res


def power(scene: str, solvers=None, *, parameters=None, timeout=None,
          params: dict | None = None, log: Callable | None = None, **kw) -> PowerResult:
    """Detection power (`xval power`): for each continuous physical parameter and each solver,
    the smallest relative change ε* reaching that solver only that turns an agreeing verdict
    into disagree. Returns a `PowerResult` (`s["power"]`, `s["summary"]`)."""
    from .workflows.power import run_power
    overrides = _overrides(params, kw)
    if timeout is not None:
        timeout = positive("timeout", timeout)
    return run_power(scene, overrides, _names(solvers), list(parameters or []), timeout,
                     log=log or _quiet)


def map(scene: str, x: str, y: str | None = None, solvers=None, *,
        resolution: float = 1e-3, coarse=None, observable: str | None = None, level=None,
        engines: str = "boundary", executor: str = "local", scheduler: str | None = None,
        workers: int | None = None, max_jobs=None, record: bool = True, out=None,
        params: dict | None = None, log: Callable | None = None, y_resolution=None,
        adaptive: bool = True, **kw) -> MapResult:
    """A map (`xval map`): the scene's regimes, or `observable`, over `x` (and `y`), each
    "NAME=LO:HI"; every solver's crossings with brackets ≤ resolution × the x range, their
    error estimates and the pairwise verdicts (`s["boundaries"]`, `s["verdicts"]`); a 2-D
    map traces its boundary in y down to `y_resolution` × the y range (default 1/64, or the
    resolution where coarser).
    `adaptive=False`: every coarse point at the accurate setting (not only those next to a
    regime change)."""
    from .workflows.maps import map_to_folder, plan_map
    if executor not in ("local", "dask"):
        raise BadInput(f"--executor: {executor!r} is not local or dask")
    if scheduler and executor != "dask":
        raise BadInput("--scheduler needs --executor dask")
    positive_int("--workers", workers)
    plan = plan_map(scene, x, y, _overrides(params, kw), _names(solvers),
                    positive("--resolution", resolution), coarse, observable, level, engines,
                    positive_int("--max-jobs", max_jobs),
                    None if y_resolution is None else positive("--y-resolution", y_resolution),
                    adaptive=adaptive)
    (log or _quiet)(f"map {scene}: ~{plan['estimate']['runs']} runs planned "
                    f"(~{plan['estimate']['seconds']:.3g} s of solver time)")
    out, temporary = _out(out)
    make_out(str(out))
    with _removed_on_error(temporary):
        # points stored under the folder by the digest of their inputs: a stopped map resumes
        obj = map_to_folder(plan, out, executor=executor, scheduler=scheduler,
                            workers=workers, record=record, log=log or _quiet,
                            store=Path(out) / "maps" / "points")
    obj["report"] = obj["files"]["report"]
    return MapResult(obj, Path(obj["folder"]), temporary)


def campaign(path_or_dict=None, *, executor: str = "local", scheduler: str | None = None,
             workers: int | None = None, timeout=None, out=None, verbose: bool = False,
             max_output_gib=None, max_steps=None, max_jobs=None,
             progress: Callable | None = None,
             checking: Callable = contextlib.nullcontext) -> CampaignResult:
    """A campaign (`xval campaign`): a .json/.toml file, a built-in name ("default", "long";
    None is the default campaign) or the campaign as a dict (the file's shape). Stored results
    are reused only in a folder given as `out`. `progress()`: a context giving the progress
    view, entered once the plan is checked (compare.output.progress.progress_view; default
    plain lines on stderr); `checking(text)`: a context shown while the plan is checked (the
    command's spinner)."""
    from .workflows import campaign as camp
    if executor not in ("local", "dask"):
        raise BadInput(f"--executor: {executor!r} is not local or dask")
    positive_int("--workers", workers)
    timeout = positive("--timeout", timeout)
    max_output_gib, max_steps = (positive("--max-output-gib", max_output_gib),
                                 positive("--max-steps", max_steps))
    if out is not None:
        check_out(str(out))
    if scheduler and executor != "dask":
        raise BadInput("--scheduler needs --executor dask")
    if isinstance(path_or_dict, dict):
        camp.check_shape(path_or_dict, "campaign")
    # everything is validated before the output folder is made or anything runs; planned once
    with checking("checking the campaign, loading the models, planning the jobs …"):
        prepared = camp.prepare(path_or_dict, timeout, max_output_gib, max_steps,
                                positive_int("--max-jobs", max_jobs))
    if scheduler:                      # reachable before anything is written
        with checking(f"connecting to {scheduler} …"):
            camp.connect(scheduler).close()
    out, temporary = _out(out)
    make_out(str(out))
    with _removed_on_error(temporary), (progress or contextlib.nullcontext)() as view:
        summary = camp.run_campaign(None, out, executor=executor, scheduler=scheduler,
                                    workers=workers, verbose=verbose, view=view,
                                    prepared=prepared)
    return CampaignResult(summary, Path(summary["report"]).parent, temporary)


def diff(old, new, *, out=None) -> DiffResult:
    """`xval diff`: which results moved between two results — each a `Result` (a run held in
    memory too) or a path: a campaign, run or map folder, or a baseline — against their own
    error bars. With `out` the report goes to out/diff/<time>-<pid>/; `s["any_change"]`,
    `s["lines"]`."""
    from .workflows.diff import new_diff_dir, run_diff
    if out is not None:
        check_out(str(out))
    res = run_diff(old, new)                          # bad input before anything is written
    if out is not None:
        make_out(str(out))
        res.save(new_diff_dir(out))
    return res


def load(path) -> Result:
    """A result saved by `.save(path)` or written by the command (a run, modes, bench,
    extremes, map, campaign, power or diff folder, its JSON file, or a baseline), read back
    as the type it was."""
    return Result.load(path)


def scenes() -> dict[str, list[str]]:
    """Every scene (as `xval list` shows them) with the names of its solvers."""
    from .scenes import SCENES
    from .solvers import solvers_for
    return {name: [s.name for s in solvers_for(name)] for name in SCENES}


def show(scene: str) -> SceneInfo:
    """A scene's parameters (default, unit, admissible range, meaning), channels and sources;
    `str()` is what `xval show` prints, `.as_json()` what `xval show --json` prints."""
    from .scenes import get_scene
    return SceneInfo(get_scene(scene))


# set by the pytest plugin's --xval-create-baselines: write a missing baseline
CREATE_BASELINES = {"on": False}


def assert_matches_baseline(result, baseline, create: bool = False):
    """Fails (AssertionError) with the diff table when `result` (an `xval.run` result, in
    memory or saved, or a run or campaign folder) moved beyond its own error bars against
    `baseline` (a file written by `xval baseline save`, or a folder), as `xval diff BASELINE
    RESULT` would. A missing baseline fails — a check with nothing to check against must not
    pass — unless told to create it (`create=True` or `pytest --xval-create-baselines`): then
    it is written from the result and the check fails once more, asking for it to be
    reviewed."""
    from .workflows.diff import check_baseline
    __tracebackhide__ = True
    if not Path(baseline).exists() and not (create or CREATE_BASELINES["on"]):
        raise AssertionError(f"baseline {baseline} is missing: create it with "
                             "assert_matches_baseline(..., create=True) or pytest "
                             "--xval-create-baselines, review it and commit it")
    table, written = check_baseline(result, baseline)
    if written:
        raise AssertionError(written)
    if table:
        raise AssertionError(f"moved against the baseline {baseline}:\n{table}")


def assert_agree(result, channels=None):
    """Assert that every comparison of `result` (a run or modes result) on `channels`
    (default: all) agrees; the failure message is the verdict table of the pairs that do
    not — deviation, both solvers' error estimates, the allowance, what decided."""
    if isinstance(channels, str):
        channels = [channels]
    msg = disagreement_message(result, channels)
    if msg:
        raise AssertionError(msg)
