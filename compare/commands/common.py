"""What the commands share: the arguments most of them take, the command line's output
conventions (JSON on stdout, logs and engine chatter on stderr, --strict's one line), and the
Python API's argument checks (scene parameters, the output folder)."""
from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import sys

from ..atomic import clean_json, num
from ..errors import BadInput
from . import arg

# --- arguments --------------------------------------------------------------------------------

STRICT_HELP = ("exit 1 on any disagree, inconclusive (one solver's error bar too wide to "
               "tell), incomplete (a solver failed or gave no answer), unconfirmed or FAILED "
               "verdict")
OUT_HELP = "output folder, made if missing (default: logs)"


def positive(name):
    """argparse type: a positive finite number."""
    def conv(text):
        try:
            v = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{name} must be a number, got {text!r}") from None
        if not (math.isfinite(v) and v > 0):
            raise argparse.ArgumentTypeError(f"{name} must be a positive number, got {text!r}")
        return v
    return conv


def positive_int(name):
    """argparse type: a whole number ≥ 1."""
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


SCENE = arg("scene", help="scene name (see `xval list`)")
SOLVERS = arg("--solver", action="append", default=[], metavar="NAME",
              help="run this solver; repeat for several (default: every solver of the scene)")
SETS = arg("--set", action="append", default=[], metavar="NAME=VALUE",
           help="override a scene parameter (repeatable; `xval show SCENE` lists them), in its "
                "unit or with one: --set torque=3.2, --set spin=400rpm, --set l=60cm")
JSON = arg("--json", action="store_true",
           help="print one JSON object on standard output (logs go to standard error)")
# a scene, its solvers and parameters, JSON: what every study of one scene takes
STUDY = (SCENE, SOLVERS, SETS, JSON)
OUT = arg("--out", default="logs", metavar="DIR", help=OUT_HELP)
# every command that writes a result (run, modes, response, campaign, bench, map, extremes,
# diff): --out names the result's own folder (folders.claim_out)
RESULT_OUT = (arg("--out", default=None, metavar="DIR",
                  help="the result's folder, made if missing; an existing one must be empty or "
                       "hold this command's earlier result (default: a new folder under logs/)"),
              arg("--force", action="store_true",
                  help="write into a non-empty --out folder that holds other files"))
STRICT = arg("--strict", action="store_true", help=STRICT_HELP)
TIMEOUT = arg("--timeout", type=positive("--timeout"), metavar="S",
              help="wall-clock limit per solver run: status timeout")
NO_RECORD = arg("--no-record", action="store_true", help="skip the .rrd recording")
BUDGET = (arg("--max-output-gib", type=positive("--max-output-gib"), metavar="GIB",
              help="refuse to start when the output (samples × channels × solvers × 8 bytes) "
                   "would exceed GIB (default 2)"),
          arg("--max-steps", type=positive("--max-steps"), metavar="N",
              help="refuse to start a fixed-step run of more than N steps (t_end / dt; "
                   "default 1e9)"))


def executor_args(what: str) -> tuple:
    return (arg("--executor", choices=("local", "dask"), default="local",
                help="local process pool (default) or Dask distributed"),
            arg("--scheduler", metavar="ADDR",
                help="address of a running Dask scheduler, e.g. tcp://host:8786 (with "
                     "--executor dask; default: a LocalCluster on this machine)"),
            arg("--workers", type=positive_int("--workers"), default=None, metavar="N",
                help=f"parallel {what} (default 2)"))


# --- the command line's output ----------------------------------------------------------------

def log(msg):
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


def answer(args, result, as_json=None) -> None:
    """A study's answer: its JSON (`as_json`, default `result.as_json()`) with --json, else its
    text."""
    if args.json:
        emit_json(result.as_json() if as_json is None else as_json)
    else:
        print(result)


def answered(args, result, as_json=None) -> int:
    """`answer`, then the exit status --strict gives the result's problems."""
    answer(args, result, as_json)
    return strict_exit(args, result.problems())


def parse_sets(items) -> dict:
    out = {}
    for item in items or []:
        name, sep, value = item.partition("=")
        if not sep or not name.strip():
            raise BadInput(f"--set {item!r}: expected NAME=VALUE")
        out[name.strip()] = value.strip()
    return out


def strict_exit(args, problems: list[str]) -> int:
    """--strict: 1 with one line on stderr naming what failed, else 0 (as `xval diff`)."""
    if getattr(args, "strict", False) and problems:
        more = f" (+{len(problems) - 3} more)" if len(problems) > 3 else ""
        print(f"xval: --strict: {'; '.join(problems[:3])}{more}", file=sys.stderr)
        return 1
    return 0


def warn_workers(args):
    """--workers above the cores this process may use: one line, then carry on (the jobs
    share the cores: no faster, more memory)."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    if args.workers and not args.scheduler and cores and args.workers > cores:
        print(f"xval: warning: --workers {args.workers} is more than the {cores} cores here: "
              f"the jobs share them (no faster, more memory)", file=sys.stderr)


# --- the Python API's checks ------------------------------------------------------------------

def overrides(params: dict | None, kw: dict) -> dict:
    """Scene parameters from `params={...}` and keywords (either, not the same name twice);
    values as the scene reads them from `--set` or a campaign file (numbers, strings, lists
    for vectors)."""
    twice = sorted(set(params or {}) & set(kw))
    if twice:
        raise BadInput(f"{twice[0]}: given twice (params= and a keyword)")
    return {**(params or {}), **kw}


def quiet(msg):
    pass


def result_folder(args):
    """A run's, modes' or response's folder: `--out DIR`, else a new one under logs/runs/ (the
    scene name checked first: an unknown scene is one line before anything is made)."""
    from ..scenes import get_scene
    from ..workflows.runner import new_run_dir
    return args.out or new_run_dir("logs", get_scene(args.scene).name)


def mode_lines(run: dict) -> list[str]:
    """A modes run's answer per mode: its frequency in Hz and rad/s, and where the solver gives
    them ζ, log dec and whirl (ROSS's conventions)."""
    from ..physics.whirl import shown_label
    out = []
    zeta, dec = run.get("zeta"), run.get("log_dec")
    for k, (label, f) in enumerate(zip(run.get("labels") or [], run.get("frequencies_hz") or [])):
        whirl = (run.get("whirl") or [None] * (k + 1))[k]
        label = shown_label(label, whirl)
        line = f"{label or f'mode {k + 1}'}: {f:.8g} Hz ({2 * math.pi * f:.8g} rad/s)"
        if zeta is not None:
            line += f", ζ {num(zeta[k], '.3g')}, log dec {num(dec[k], '.3g')}"
        out.append(line + (f", {whirl} whirl" if whirl and whirl != "—"
                           and whirl not in (label or "") else ""))
    return out


def verdict_line(comparisons) -> str:
    """The answer in one line: how many agree (how many marginally) and the comparison that
    came closest to its bound."""
    from ..analysis.verdict import Verdict, agree_text
    line = agree_text(c.verdict for c in comparisons)
    marginal = sum(Verdict(c.verdict).marginal(c.ratio) for c in comparisons)
    judged = [c for c in comparisons if c.verdict != Verdict.SKIPPED and c.ratio == c.ratio]
    worst = max(judged, key=lambda c: c.ratio, default=None)
    return (line + (f" ({marginal} marginal)" if marginal else "")
            + (f"; worst Δ/bound {worst.ratio:.2g} ({worst.a} vs {worst.b} {worst.channel})"
               if worst else ""))


def compared_answer(args, result) -> int:
    """Print a run or modes result (each solver's status and final values, each comparison, the
    summary, the files); its exit status: 3 where a solver crashed, --strict's rule else."""
    obj = result.as_json()
    if args.json:
        emit_json(obj)
    else:
        for r in obj["runs"]:
            bar = r.get("final_error") or {}
            cost = (r.get("stats") or {}).get("error_estimate_s")
            print(f"{r['solver']:14s} {r['status']:8s} wall {r['wall_s']:.3g} s"
                  + (f" (error bar {cost:.3g} s)" if cost else "") + "  "
                  + "  ".join(f"{k}={v:.6g}" + (f"±{bar[k]:.1g}" if bar.get(k) else "")
                              for k, v in (r.get("final") or {}).items() if v is not None))
            for line in mode_lines(r):
                print(f"    {line}")
        for name, entries in ((obj.get("campbell") or {}).get("critical_speeds") or {}).items():
            print(f"{name} critical speeds: " + ", ".join(
                f"{e['name']} {e['speed_rad_s']:.6g} rad/s ({e['speed_rpm']:.6g} rpm)"
                for e in entries))
        for c in result.comparisons:
            print(f"{c.a} vs {c.b} {c.channel}: max rel {c.max_rel:.2e} → {c.shown}")
        print(obj.get("summary") or verdict_line(result.comparisons))
        for k in ("recording", "report"):
            if obj.get(k):
                print(f"{k}: {obj[k]}")
    if any(run.status == "error" for run in result.runs.values()):
        return 3
    return strict_exit(args, result.problems())
