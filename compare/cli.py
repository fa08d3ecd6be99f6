"""`xval`: the command-line contract (see the README and the specs' contract.md).

Exit status: 0 every requested run finished, 1 a verdict is `disagree` and --strict was given,
2 bad input (one line on stderr, nothing run, nothing written), 3 a solver crashed.
"""
import argparse
import contextlib
import json
import math
import os
import sys

import numpy as np

from .errors import BadInput


class _Parser(argparse.ArgumentParser):
    def error(self, message):                      # one line, status 2 (not argparse's usage)
        raise BadInput(message)


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


def clean_json(x):
    """JSON without NaN/Infinity (they become null) and with numpy values as plain Python."""
    if isinstance(x, dict):
        return {str(k): clean_json(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [clean_json(v) for v in x]
    if isinstance(x, np.ndarray):
        return clean_json(x.tolist())
    if isinstance(x, np.generic):
        x = x.item()
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x


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


def build_parser():
    p = _Parser(prog="xval", description="Cross-validate multibody dynamics solvers.")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)
    sub.add_parser("list", help="scenes and solvers")
    sp = sub.add_parser("show", help="parameters of a scene")
    sp.add_argument("scene")
    sp.add_argument("--json", action="store_true")

    def common(sp):
        sp.add_argument("scene")
        sp.add_argument("--solver", action="append", default=[])
        sp.add_argument("--set", action="append", default=[], metavar="NAME=VALUE")
        sp.add_argument("--json", action="store_true")

    sp = sub.add_parser("run", help="simulate a scene with several solvers and compare them")
    common(sp)
    g = sp.add_mutually_exclusive_group()
    g.add_argument("--dt", type=_positive("--dt"))
    g.add_argument("--rtol", type=_positive("--rtol"))
    sp.add_argument("--integrator")
    sp.add_argument("--out", default="logs")
    sp.add_argument("--strict", action="store_true", help="exit 1 when a verdict is disagree")
    sp.add_argument("--no-record", action="store_true", help="skip the .rrd recording")
    sp.add_argument("--timeout", type=_positive("--timeout"), metavar="S",
                    help="wall-clock limit per solver run: status timeout")

    sp = sub.add_parser("modes", help="natural frequencies")
    common(sp)
    sp.add_argument("--out", default="logs")
    sp.add_argument("--strict", action="store_true")

    sp = sub.add_parser("campaign", help="run a campaign file (default: built-in) into a report")
    sp.add_argument("file", nargs="?")
    sp.add_argument("--executor", choices=("local", "dask"), default="local")
    sp.add_argument("--scheduler")
    sp.add_argument("--workers", type=int, default=None)
    sp.add_argument("--out", default="logs")
    sp.add_argument("--json", action="store_true")
    sp.add_argument("--timeout", type=_positive("--timeout"), metavar="S",
                    help="wall-clock limit per job unless its case sets timeout_s")

    sp = sub.add_parser("bench", help="speed/accuracy (work-precision) sweep")
    common(sp)
    sp.add_argument("--repeats", type=int, default=3)
    sp.add_argument("--vary", metavar="NAME=V1,V2,...",
                    help="trade a model parameter instead of the step: each solver's default "
                         "settings at each value, errors against the reference at the --set "
                         "value (e.g. --vary stiffness=1e5,1e6)")
    sp.add_argument("--out", default="logs")
    return p


def cmd_list(args):
    from .scenes import SCENES
    from .solvers import REGISTRY, solvers_for
    for sc in SCENES.values():
        print(f"scene  {sc.name:20s} {sc.kind:5s}  solvers: "
              f"{', '.join(s.name for s in solvers_for(sc.name))}  — {sc.title}")
    for s in REGISTRY.values():
        print(f"solver {s.name:20s} scenes: {', '.join(s.leaves)}  — {s.doc}")
    return 0


def cmd_show(args):
    from .scenes import get_scene
    sc = get_scene(args.scene)
    if args.json:
        emit_json({"scene": sc.name, "title": sc.title, "kind": sc.kind,
                   "channels": list(sc.channels), "tolerances": sc.tolerances,
                   "params": [{"name": p.name, "default": p.default, "unit": p.unit,
                               "range": p.describe_range(), "doc": p.doc} for p in sc.params]})
        return 0
    print(f"{sc.name}: {sc.title}\n  source: {sc.source}")
    for p in sc.params:
        d = ",".join(f"{x:g}" for x in p.default) if p.kind == "vector" else p.default
        print(f"  {p.name:16s} = {str(d):14s} {p.unit:9s} {p.describe_range():18s} {p.doc}")
    if sc.channels:
        print(f"  channels: {', '.join(sc.channels)}")
    return 0


def cmd_run(args):
    from .scenes import get_scene
    from . import solvers, runner
    sc = get_scene(args.scene)
    if sc.kind != "time":
        raise BadInput(f"scene {sc.name!r} is a frequency scene: use `xval modes {sc.name}`")
    params = sc.resolve(parse_sets(args.set))
    chosen = solvers.pick(sc, args.solver)
    # settings are resolved (and checked) for every solver before anything runs
    settings = {s.name: solvers.settings_for(s, sc.name, args.dt, args.rtol, args.integrator)
                for s in chosen}
    if args.rtol is not None:
        for s in chosen:
            if not getattr(s.leaf(sc.name), "ADAPTIVE", ()):
                _log(f"{s.name}: no error-controlled integrator, --rtol ignored (fixed step kept)")
    out_dir = runner.new_run_dir(args.out, sc.name)
    with stdout_to_stderr():
        res = runner.run_scene(sc, params, chosen, lambda s: settings[s.name], out_dir,
                               record=not args.no_record, log=_log, timeout_s=args.timeout)
    return _finish(args, res.as_json(), res.trajectories, res.comparisons)


def _finish(args, obj, results, comparisons):
    if args.json:
        emit_json(obj)
    else:
        for r in obj["runs"]:
            print(f"{r['solver']:14s} {r['status']:8s} wall {r['wall_s']:.3g} s  "
                  + "  ".join(f"{k}={v:.6g}" for k, v in (r.get("final") or {}).items()
                              if v is not None))
        for c in comparisons:
            print(f"{c.a} vs {c.b} {c.channel}: max rel {c.max_rel:.2e} → {c.verdict}")
        for k in ("recording", "report"):
            if obj.get(k):
                print(f"{k}: {obj[k]}")
    if any(r.status == "error" for r in results):
        return 3
    if args.strict and any(c.verdict == "disagree" for c in comparisons):
        return 1
    return 0


def cmd_modes(args):
    from .modes import run_modes
    with stdout_to_stderr():
        obj, results, comparisons = run_modes(args.scene, args.solver, parse_sets(args.set),
                                              args.out, log=_log)
    return _finish(args, obj, results, comparisons)


def cmd_campaign(args):
    from .campaign import run_campaign
    with stdout_to_stderr():
        summary = run_campaign(args.file, args.out, executor=args.executor,
                               scheduler=args.scheduler, workers=args.workers, log=_log,
                               timeout_s=args.timeout)
    if args.json:
        emit_json(summary)
    else:
        print(f"campaign: {summary['n_jobs']} jobs, {summary['n_skipped']} already done, "
              f"{summary['n_failed']} with a failed solver")
        print(f"report: {summary['report']}")
    return 3 if summary["n_crashed"] else 0


def cmd_bench(args):
    from .bench import run_bench
    with stdout_to_stderr():
        obj = run_bench(args.scene, args.solver, parse_sets(args.set), args.out,
                        repeats=args.repeats, log=_log, vary=args.vary)
    if args.json:
        emit_json(obj)
    else:
        for line in obj["summary_lines"]:
            print(line)
        print(f"report: {obj['report']}")
    return 0


COMMANDS = {"list": cmd_list, "show": cmd_show, "run": cmd_run, "modes": cmd_modes,
            "campaign": cmd_campaign, "bench": cmd_bench}


def main(argv=None):
    import warnings
    from numba.core.errors import NumbaPerformanceWarning
    warnings.simplefilter("ignore", NumbaPerformanceWarning)   # hints for us, noise for users
    try:
        args = build_parser().parse_args(argv)
        return COMMANDS[args.command](args)
    except BadInput as e:
        print(f"xval: error: {e}", file=sys.stderr)
        return 2


def entry():
    sys.exit(main())
