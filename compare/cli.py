"""`xval`: the command-line contract (see the README and the specs' contract.md).

Exit status: 0 every requested run finished, 1 a verdict is `disagree` or `inconclusive` and
--strict was given,
2 bad input (one line on stderr, nothing run, nothing written), 3 a solver crashed.
"""
import argparse
import contextlib
import json
import math
import os
import sys

from .atomic import clean_json
from .errors import BadInput
from .output.folders import check_out, make_out  # noqa: F401  (shared with the API)


class _Parser(argparse.ArgumentParser):
    def error(self, message):                      # one line, status 2 (not argparse's usage)
        raise BadInput(message)


STRICT = ("exit 1 on any disagree, inconclusive (one solver's error bar too wide to tell), "
          "incomplete (a solver failed or gave no answer), unconfirmed or FAILED verdict")


def strict_exit(args, problems: list[str]) -> int:
    """--strict: 1 with one line on stderr naming what failed, else 0 (as `xval diff`)."""
    if getattr(args, "strict", False) and problems:
        more = f" (+{len(problems) - 3} more)" if len(problems) > 3 else ""
        print(f"xval: --strict: {'; '.join(problems[:3])}{more}", file=sys.stderr)
        return 1
    return 0


def _log(msg):
    print(msg, file=sys.stderr, flush=True)


@contextlib.contextmanager
def stdout_to_stderr():
    """Engines print to stdout (MuJoCo warnings, Exudyn banners); keep stdout for our output."""
    sys.stdout.flush()
    saved = os.dup(1)
    os.dup2(2, 1)
    try:
        yield
    finally:
        sys.stdout.flush()
        os.dup2(saved, 1)
        os.close(saved)


def emit_json(obj):
    print(json.dumps(clean_json(obj)), flush=True)


def parse_sets(items):
    out = {}
    for item in items or []:
        name, sep, value = item.partition("=")
        if not sep or not name.strip():
            raise BadInput(f"--set {item!r}: expected NAME=VALUE")
        out[name.strip()] = value.strip()
    return out


def _positive(name):
    def conv(text):
        try:
            v = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{name} must be a number, got {text!r}") from None
        if not (math.isfinite(v) and v > 0):
            raise argparse.ArgumentTypeError(f"{name} must be a positive number, got {text!r}")
        return v
    return conv


def _positive_int(name):
    def conv(text):
        try:
            v = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{name} must be a whole number, got {text!r}") \
                from None
        if v < 1:
            raise argparse.ArgumentTypeError(f"{name} must be at least 1, got {text!r}")
        return v
    return conv


def _budget_options(sp):
    sp.add_argument("--max-output-gib", type=_positive("--max-output-gib"), metavar="GIB",
                    help="refuse to start when the output (samples × channels × solvers × 8 "
                         "bytes) would exceed GIB (default 2)")
    sp.add_argument("--max-steps", type=_positive("--max-steps"), metavar="N",
                    help="refuse to start a fixed-step run of more than N steps (t_end / dt; "
                         "default 1e9)")


def version() -> str:
    """The installed distribution's version (pyproject.toml's, as pip installed it)."""
    from importlib.metadata import PackageNotFoundError
    from importlib.metadata import version as dist_version
    try:
        return dist_version("xval")
    except PackageNotFoundError:                  # a clone used without `pip install`
        return "unknown (not installed: pip install -e .)"


def warn_workers(args):
    """--workers above the cores this process may use: one line, then carry on (the jobs
    share the cores: no faster, more memory)."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    if args.workers and not args.scheduler and cores and args.workers > cores:
        print(f"xval: warning: --workers {args.workers} is more than the {cores} cores here: "
              f"the jobs share them (no faster, more memory)", file=sys.stderr)


def build_parser():
    p = _Parser(prog="xval", description="Cross-validate multibody dynamics solvers: the same "
                "scene through our implementations of published methods, Exudyn and MuJoCo, "
                "compared in numbers, plots and rerun recordings.",
                epilog="Exit status: 0 finished, 1 a verdict is disagree or inconclusive under "
                       "--strict, 2 bad input (one line, nothing run), 3 a solver crashed.")
    p.add_argument("--version", action="version", version=f"xval {version()}",
                   help="print the installed version and exit")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser,
                           metavar="COMMAND")
    sub.add_parser("list", help="list scenes and solvers",
                   description="List every scene with its solvers, and every solver.")
    sp = sub.add_parser("show", help="parameters of a scene: default, unit, admissible range",
                        description="Every parameter of a scene with default, unit and "
                                    "admissible range, its channels and the papers it comes "
                                    "from.")
    sp.add_argument("scene", help="scene name (see `xval list`)")
    sp.add_argument("--json", action="store_true", help="print one JSON object instead")

    def common(sp):
        sp.add_argument("scene", help="scene name (see `xval list`)")
        sp.add_argument("--solver", action="append", default=[], metavar="NAME",
                        help="run this solver; repeat for several (default: every solver of "
                             "the scene)")
        sp.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                        help="override a scene parameter (repeatable; `xval show SCENE` "
                             "lists them), e.g. --set torque=3.2")
        sp.add_argument("--json", action="store_true",
                        help="print one JSON object on standard output (logs go to "
                             "standard error)")

    out_help = "output folder, made if missing (default: logs)"
    sp = sub.add_parser("run", help="simulate a scene with several solvers and compare them",
                        description="Simulate a time-domain scene with each solver, compare "
                                    "the trajectories pairwise, record (rerun .rrd) and report "
                                    "(Markdown with plots).")
    common(sp)
    g = sp.add_mutually_exclusive_group()
    g.add_argument("--dt", type=_positive("--dt"), metavar="S",
                   help="fixed step in seconds (an adaptive default switches to its fixed-step "
                        "method, e.g. rk4)")
    g.add_argument("--rtol", type=_positive("--rtol"),
                   help="relative tolerance for the error-controlled integrators (fixed-step "
                        "solvers keep their step and say so)")
    sp.add_argument("--integrator", metavar="NAME",
                    help="integrator of every chosen solver (each must offer it)")
    sp.add_argument("--out", default="logs", metavar="DIR", help=out_help)
    sp.add_argument("--strict", action="store_true", help=STRICT)
    sp.add_argument("--no-record", action="store_true", help="skip the .rrd recording")
    sp.add_argument("--timeout", type=_positive("--timeout"), metavar="S",
                    help="wall-clock limit per solver run: status timeout")
    _budget_options(sp)

    sp = sub.add_parser("modes", help="natural frequencies, Campbell diagram, critical speeds",
                        description="Natural frequencies from every solver that linearises, "
                                    "matched mode by mode; Campbell diagram for rotor scenes.")
    common(sp)
    sp.add_argument("--out", default="logs", metavar="DIR", help=out_help)
    sp.add_argument("--strict", action="store_true", help=STRICT)
    sp.add_argument("--campbell-frame", choices=("fixed", "rotating"), default=None,
                    help="draw the Campbell figure in this frame (default: the frame the "
                         "scene's solvers report; the other where the modes whirl)")

    sp = sub.add_parser("response", help="unbalance response vs speed: frequency domain vs "
                        "time domain",
                        description="Steady unbalance response (amplitude and phase lag vs "
                                    "spin, through the first critical speed) from every solver "
                                    "that takes the unbalance into its linear model and from "
                                    "the time-domain solvers run at constant spin to steady "
                                    "state (1× fit), judged speed by speed against the error "
                                    "bars; peak, amplification factor Q, half-power ζ against "
                                    "the modal ζ; Bode and polar plots.")
    common(sp)
    sp.add_argument("--speeds", type=_positive_int("--speeds"), default=24, metavar="N",
                    help="number of speeds, half of them within ±3ζ of the critical "
                         "(default 24)")
    sp.add_argument("--out", default="logs", metavar="DIR", help=out_help)
    sp.add_argument("--strict", action="store_true", help=STRICT)

    sp = sub.add_parser("campaign", help="run a campaign file (default: built-in) into a report",
                        description="Run every case of a campaign file (JSON or TOML; "
                                    "default: the built-in campaign) as parallel jobs, reuse "
                                    "results whose inputs did not change, and write one "
                                    "report.")
    sp.add_argument("file", nargs="?", help="campaign file, .json or .toml (default: built-in)")
    sp.add_argument("--executor", choices=("local", "dask"), default="local",
                    help="local process pool (default) or Dask distributed")
    sp.add_argument("--scheduler", metavar="ADDR",
                    help="address of a running Dask scheduler, e.g. tcp://host:8786 (with "
                         "--executor dask; default: a LocalCluster on this machine)")
    sp.add_argument("--workers", type=_positive_int("--workers"), default=None, metavar="N",
                    help="parallel jobs (default 2)")
    sp.add_argument("--out", default="logs", metavar="DIR", help=out_help)
    sp.add_argument("--json", action="store_true", help="print the summary as one JSON object")
    sp.add_argument("--timeout", type=_positive("--timeout"), metavar="S",
                    help="wall-clock limit per job unless its case sets timeout_s")
    sp.add_argument("--max-jobs", type=_positive_int("--max-jobs"), default=None,
                    metavar="N", help="refuse to start a campaign of more than N jobs (cases × "
                                      "sweep points × solvers; default 10000)")
    sp.add_argument("--verbose", action="store_true",
                    help="show each job's engine messages (banners, warnings) as it finishes; "
                         "they are always in the job's log and the report")
    sp.add_argument("--baseline", metavar="DIR",
                    help="after the run, diff against this campaign folder or baseline file "
                         "(report in <campaign>/diff/; exit 1 when results moved beyond "
                         "their error bars)")
    sp.add_argument("--strict", action="store_true", help=STRICT)
    _budget_options(sp)

    sp = sub.add_parser("bench", help="speed/accuracy (work-precision) sweep",
                        description="Work-precision: each solver along its accuracy knob (step "
                                    "or tolerance; frequency scenes: mesh, segments or root "
                                    "tolerance), error of the key channel's final value "
                                    "(frequency scenes: the largest relative frequency error, "
                                    "and the paper's computing times against each solver's "
                                    "defaults) against a tight reference, median wall time.")
    common(sp)
    sp.add_argument("--repeats", type=_positive_int("--repeats"), default=3, metavar="N",
                    help="timed runs per rung; the median counts (default 3)")
    sp.add_argument("--points", type=_positive_int("--points"), metavar="N",
                    help="throughput instead: each solver's points per second over N points "
                         "of the scene's default map (the map's batch path)")
    sp.add_argument("--vary", metavar="NAME=V1,V2,...",
                    help="trade a model parameter instead of the step: each solver's default "
                         "settings at each value, errors against the reference at the --set "
                         "value (e.g. --vary stiffness=1e5,1e6)")
    sp.add_argument("--out", default="logs", metavar="DIR", help=out_help)
    _budget_options(sp)

    sp = sub.add_parser("map", help="regimes or an observable over one or two parameters",
                        description="Map a scene's regimes (or a scalar observable) over a "
                                    "parameter line or plane: a coarse grid, then bisection "
                                    "where neighbours differ, every solver's boundary located "
                                    "on its own and compared with error bars.")
    common(sp)
    sp.add_argument("--x", required=True, metavar="NAME=LO:HI", help="the x axis")
    sp.add_argument("--y", metavar="NAME=LO:HI", help="the y axis (a 2-D map)")
    sp.add_argument("--resolution", type=_positive("--resolution"), default=1e-3,
                    help="bracket of every crossing as a fraction of the x range "
                         "(default 1e-3)")
    sp.add_argument("--y-resolution", type=_positive("--y-resolution"), default=None,
                    help="a 2-D map adds rows where neighbouring rows' crossings differ, down "
                         "to this fraction of the y range (default: 1/64, or --resolution "
                         "where coarser)")
    sp.add_argument("--coarse", metavar="NX[,NY]",
                    help="the coarse grid: points along x and rows along y (default 17,9)")
    sp.add_argument("--accurate-everywhere", action="store_true",
                    help="run every coarse point at the accurate setting (default: a cheap "
                         "tolerance first, the accurate one next to a regime change)")
    sp.add_argument("--observable", metavar="NAME",
                    help="map a scalar observable of the scene instead of its regime")
    sp.add_argument("--level", type=float, metavar="V",
                    help="with --observable: locate where it crosses V")
    sp.add_argument("--engines", choices=("boundary", "everywhere"), default="boundary",
                    help="engines refine the custom solvers' boundary (default) or map the "
                         "whole plane")
    sp.add_argument("--executor", choices=("local", "dask"), default="local",
                    help="local process pool (default) or Dask distributed")
    sp.add_argument("--scheduler", metavar="ADDR", help="a running Dask scheduler's address")
    sp.add_argument("--workers", type=_positive_int("--workers"), default=None, metavar="N",
                    help="parallel workers (default 2)")
    sp.add_argument("--max-jobs", type=_positive_int("--max-jobs"), default=None,
                    metavar="N", help="refuse to start a map estimated above N runs "
                                      "(default 100000)")
    sp.add_argument("--no-record", action="store_true", help="skip the .rrd recording")
    sp.add_argument("--out", default="logs", metavar="DIR", help=out_help)
    sp.add_argument("--strict", action="store_true", help=STRICT)

    sp = sub.add_parser("power", help="detection power: the smallest error of one solver's "
                        "parameter that a verdict sees",
                        description="For each physical parameter and each solver in turn, the "
                                    "smallest relative change of that parameter reaching that "
                                    "solver only that turns an agreeing verdict into disagree "
                                    "(finite-difference estimate, one confirming run, bisection "
                                    "where the response is not linear).")
    common(sp)
    sp.add_argument("--parameter", action="append", default=[], metavar="NAME",
                    help="only this parameter; repeatable (default: every continuous physical "
                         "parameter of the scene)")
    sp.add_argument("--timeout", type=_positive("--timeout"), metavar="S",
                    help="wall-clock limit per solver run: status timeout")

    sp = sub.add_parser("extremes", help="numerical stability at the extremes of a scene",
                        description="Run every extreme case of the scene's spec with every "
                                    "solver: each ends within tolerance of an independent check "
                                    "(energy balance, a second solver, a closed form) or with "
                                    "an honest status (diverged / unstable / singular / "
                                    "timeout) and the time and reason.")
    sp.add_argument("scene", help="scene name (see `xval list`)")
    sp.add_argument("--solver", action="append", default=[], metavar="NAME",
                    help="run this solver; repeat for several (default: every solver)")
    sp.add_argument("--all", action="store_true",
                    help="include the long cases (e.g. a 1000 s horizon) and the long runs "
                         "of some solvers (an engine at the step that resolves the case)")
    sp.add_argument("--strict", action="store_true",
                    help="exit 1 on any FAILED, error or stale declaration (a case declaring "
                         "a solver's known failure whose run now passes); a declared "
                         "FAILED (known), explained in the scene file, does not count")
    sp.add_argument("--timeout", type=_positive("--timeout"), metavar="S",
                    help="wall-clock limit per solver run: status timeout")
    sp.add_argument("--out", default="logs", metavar="DIR", help=out_help)
    sp.add_argument("--json", action="store_true",
                    help="print one JSON object on standard output")
    sp = sub.add_parser("diff", help="which results moved between two campaigns, runs or "
                        "baselines, against their own error bars",
                        description="Compare two campaign folders, run folders or baselines: "
                                    "every case × solver × channel (modes, critical speeds, map "
                                    "boundaries) against the runs' own error estimates, with "
                                    "what differs in the inputs. Exit 0 nothing changed, 1 "
                                    "changes found, 2 bad input.")
    sp.add_argument("old", help="campaign folder, run folder or baseline file")
    sp.add_argument("new", help="campaign folder, run folder or baseline file")
    sp.add_argument("--out", default="logs", metavar="DIR",
                    help="the report goes to DIR/diff/<time>-<pid>/ (default: logs)")
    sp.add_argument("--json", action="store_true", help="print the diff as one JSON object")
    sp = sub.add_parser("baseline", help="save a compact baseline of a campaign or run folder",
                        description="`xval baseline save DIR OUT`: a compact, committable "
                                    "baseline (.npz) of a campaign or run folder for `xval "
                                    "diff`.")
    bsub = sp.add_subparsers(dest="action", required=True, parser_class=_Parser,
                             metavar="ACTION", help="save (the only action)")
    bp = bsub.add_parser("save", help="write the baseline of DIR to OUT")
    bp.add_argument("folder", help="campaign folder or run folder")
    bp.add_argument("target", help="baseline file to write (.npz)")
    bp.add_argument("--json", action="store_true", help="print one JSON object")
    return p


def cmd_diff(args):
    from . import api
    r = api.diff(args.old, args.new, out=args.out)
    if args.json:
        emit_json(r.data)
    else:
        print(r)                                      # the counts, the changes, notes, report
    return 1 if r["any_change"] else 0


def cmd_baseline(args):
    from .workflows.sides import save_baseline
    target = os.path.abspath(args.target)
    if os.path.isdir(target):
        raise BadInput(f"{args.target}: is a folder; name the baseline file to write")
    check_out(os.path.dirname(target))
    obj = save_baseline(args.folder, target)
    if args.json:
        emit_json(obj)
    else:
        print(f"baseline {obj['baseline']}: {obj['bytes'] / 1e6:.2f} MB, {obj['cases']} cases, "
              f"{obj['samples_kept']} of {obj['samples_full']} samples kept")
    return 0


def cmd_extremes(args):
    from . import api
    check_out(args.out)
    with stdout_to_stderr():
        r = api.extremes(args.scene, args.solver, include_slow=args.all, timeout=args.timeout,
                         out=args.out, log=_log)
    if args.json:
        emit_json(r.as_json())
    else:
        print(r)
    return strict_exit(args, r.problems())


def cmd_list(args):
    from .output.citations import cite_short
    from .scenes import ORIGIN, SCENES
    from .solvers import REGISTRY, solvers_for
    for sc in SCENES.values():
        plug = f"  [plug-in: {ORIGIN[sc.name][0]}]" if sc.name in ORIGIN else ""
        print(f"scene  {sc.name:20s} {sc.kind:5s}  solvers: "
              f"{', '.join(s.name for s in solvers_for(sc.name))}  — {sc.title}{plug}")
    for s in REGISTRY.values():
        print(f"solver {s.name:20s} scenes: {', '.join(s.leaves)}  — {cite_short(s.doc)}")
    return 0


def cmd_show(args):
    from . import api
    info = api.show(args.scene)
    if args.json:
        emit_json(info.as_json())
    else:
        print(info)
    return 0


def cmd_run(args):
    from . import api
    with stdout_to_stderr():
        r = api.run(args.scene, args.solver, dt=args.dt, rtol=args.rtol,
                    integrator=args.integrator, out=args.out, record=not args.no_record,
                    timeout=args.timeout, max_output_gib=args.max_output_gib,
                    max_steps=args.max_steps, params=parse_sets(args.set), log=_log)
    return _finish(args, r)


def _finish(args, result):
    """Print a run or modes result; its exit status."""
    obj = result.as_json()
    if args.json:
        emit_json(obj)
    else:
        for r in obj["runs"]:
            print(f"{r['solver']:14s} {r['status']:8s} wall {r['wall_s']:.3g} s  "
                  + "  ".join(f"{k}={v:.6g}" for k, v in (r.get("final") or {}).items()
                              if v is not None))
        for c in result.comparisons:
            print(f"{c.a} vs {c.b} {c.channel}: max rel {c.max_rel:.2e} → {c.verdict}")
        if obj.get("summary"):             # a modes run: incomplete, unpaired, unconfirmed
            print(obj["summary"])
        for k in ("recording", "report"):
            if obj.get(k):
                print(f"{k}: {obj[k]}")
    if any(run.status == "error" for run in result.runs.values()):
        return 3
    return strict_exit(args, result.problems())


def cmd_modes(args):
    from . import api
    check_out(args.out)
    with stdout_to_stderr():
        r = api.modes(args.scene, args.solver, out=args.out, params=parse_sets(args.set),
                      log=_log, campbell_frame=args.campbell_frame)
    rc = _finish(args, r)
    if not args.json:
        from .results.modes import threshold_lines
        for line in threshold_lines(r.extra.get("threshold")):
            print(line)
    return rc


def cmd_response(args):
    from . import api
    check_out(args.out)
    with stdout_to_stderr():
        r = api.response(args.scene, args.solver, speeds=args.speeds, out=args.out,
                         params=parse_sets(args.set), log=_log)
    if args.json:
        emit_json(r.as_json())
    else:
        print(r)
    return strict_exit(args, r.problems())


def cmd_campaign(args):
    from . import api
    from .output.progress import busy, progress_view
    from .workflows.campaign import Interrupted
    check_out(args.out)
    if args.baseline:                  # bad input before anything is written
        from .results import Result
        from .workflows.campaign import load_campaign
        Result.load(args.baseline)
        own = os.path.join(args.out, "campaign", load_campaign(args.file).get("name", "campaign"))
        if os.path.exists(own) and os.path.samefile(args.baseline, own):
            raise BadInput(f"--baseline {args.baseline}: is the folder this campaign writes (it "
                           f"would be diffed against itself): save it first with `xval "
                           f"baseline save {args.baseline} base.npz` and pass base.npz")
    warn_workers(args)
    try:
        with stdout_to_stderr():
            r = api.campaign(args.file, executor=args.executor, scheduler=args.scheduler,
                             workers=args.workers, timeout=args.timeout, out=args.out,
                             verbose=args.verbose, max_output_gib=args.max_output_gib,
                             max_steps=args.max_steps, max_jobs=args.max_jobs,
                             progress=progress_view, checking=busy)
    except Interrupted as e:             # Ctrl-C: workers stopped, finished jobs kept
        again = " ".join(["xval campaign"] + ([args.file] if args.file else [])
                         + ["--out", args.out])
        print(f"xval: interrupted: {e}; resume with: {again}", file=sys.stderr)
        return 130
    summary = r.data
    if args.baseline:
        from .workflows.diff import run_diff
        d = run_diff(args.baseline, r)
        d.save(r.out_dir / "diff")
        if not args.json:
            print(d)
        summary["diff"] = {k: d[k] for k in ("summary", "lines", "report", "any_change")}
    if args.json:
        emit_json(summary)
    else:
        print(r)                       # the one-line summary and the report's path
    if summary["n_crashed"]:
        return 3
    if summary.get("diff", {}).get("any_change"):
        return 1
    return strict_exit(args, r.problems())


def cmd_bench(args):
    from . import api
    check_out(args.out)
    with stdout_to_stderr():
        r = api.bench(args.scene, args.solver, repeats=args.repeats, vary=args.vary,
                      out=args.out, max_output_gib=args.max_output_gib,
                      max_steps=args.max_steps, params=parse_sets(args.set), log=_log,
                      points=args.points)
    if args.json:
        emit_json(r.as_json())
    else:
        print(r)
    return 0


def _coarse(text):
    try:
        vals = tuple(int(v) for v in text.split(","))
    except ValueError:
        raise BadInput(f"--coarse {text!r}: expected NX or NX,NY (whole numbers)") from None
    if len(vals) not in (1, 2):
        raise BadInput(f"--coarse {text!r}: expected NX or NX,NY")
    return vals if len(vals) == 2 else (vals[0], 9)


def cmd_map(args):
    import shlex

    from . import api
    from .workflows.executors import Interrupted
    check_out(args.out)
    coarse = _coarse(args.coarse) if args.coarse else None
    if coarse and not args.y:
        coarse = (coarse[0], 1)
    warn_workers(args)
    try:
        with stdout_to_stderr():
            r = api.map(args.scene, args.x, args.y, args.solver, resolution=args.resolution,
                        coarse=coarse, observable=args.observable, level=args.level,
                        engines=args.engines, executor=args.executor,
                        scheduler=args.scheduler, workers=args.workers,
                        max_jobs=args.max_jobs, record=not args.no_record, out=args.out,
                        params=parse_sets(args.set), log=_log,
                        y_resolution=args.y_resolution,
                        adaptive=not args.accurate_everywhere)
    except Interrupted as e:             # Ctrl-C / SIGTERM: workers stopped, points kept
        print(f"xval: interrupted: {e}; resume with: {shlex.join(['xval', *args.argv])}",
              file=sys.stderr)
        return 130
    if args.json:
        emit_json(r.data)
    else:
        print(r)
    return strict_exit(args, r.problems())


def cmd_power(args):
    from . import api
    with stdout_to_stderr():
        r = api.power(args.scene, args.solver, parameters=args.parameter,
                      timeout=args.timeout, params=parse_sets(args.set), log=_log)
    if args.json:
        emit_json(r.data)
    else:
        print(r)
    return strict_exit(args, r.problems())


COMMANDS = {"list": cmd_list, "show": cmd_show, "run": cmd_run, "modes": cmd_modes,
            "campaign": cmd_campaign, "map": cmd_map, "bench": cmd_bench,
            "extremes": cmd_extremes, "diff": cmd_diff, "baseline": cmd_baseline,
            "power": cmd_power, "response": cmd_response}


def main(argv=None):
    import warnings
    # numba's performance hints are for us, noise for users (matched by module: importing numba
    # here to name the class would cost a second before every one-line answer)
    warnings.filterwarnings("ignore", module=r"numba(\.|$)")
    try:
        args = build_parser().parse_args(argv)
        args.argv = list(sys.argv[1:] if argv is None else argv)
        return COMMANDS[args.command](args)
    except BadInput as e:
        print(f"xval: error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:          # Ctrl-C outside a campaign's jobs: one line, no traceback
        print("xval: interrupted", file=sys.stderr)
        return 130


def entry():
    try:
        sys.exit(main())
    except BrokenPipeError:            # `xval list | head`: the reader left, nothing to say
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        sys.exit(0)
