"""`xval campaign`: every case of a campaign file as parallel jobs, resumable, one report."""
from __future__ import annotations

import contextlib
import os
import sys
from collections.abc import Callable
from pathlib import Path

from ..errors import BadInput
from ..output.folders import claim_out, make_out
from ..results import CampaignResult
from ..workflows.inputs import positive, positive_int
from . import Command, arg
from .common import (
    BUDGET,
    RESULT_OUT,
    STRICT,
    emit_json,
    executor_args,
    stdout_to_stderr,
    strict_exit,
    warn_workers,
)
from .common import positive as positive_arg
from .common import positive_int as positive_int_arg


def campaign(path_or_dict=None, *, executor: str = "local", scheduler: str | None = None,
             workers: int | None = None, timeout=None, out=None, verbose: bool = False,
             max_output_gib=None, max_steps=None, max_jobs=None,
             progress: Callable | None = None,
             checking: Callable = contextlib.nullcontext, force: bool = False) -> CampaignResult:
    """A campaign (`xval campaign`): a .json/.toml file, a built-in name ("default", "long";
    None is the default campaign) or the campaign as a dict (the file's shape). `out`: the
    campaign's folder (empty, or a campaign folder: its stored results are reused; other files
    only with `force`); without it logs/campaign/<name>, as the command's (a campaign's
    jobs hand their results back through its folder, which a rerun resumes from).
    `progress()`: a context giving the progress view, entered once the plan is checked
    (compare.output.progress.progress_view; default plain lines on stderr); `checking(text)`:
    a context shown while the plan is checked (the command's spinner)."""
    from ..workflows import campaign as camp
    if executor not in ("local", "dask"):
        raise BadInput(f"--executor: {executor!r} is not local or dask")
    positive_int("--workers", workers)
    timeout = positive("--timeout", timeout)
    max_output_gib, max_steps = (positive("--max-output-gib", max_output_gib),
                                 positive("--max-steps", max_steps))
    if out is not None:
        claim_out(str(out), "campaign", force)
    if scheduler and executor != "dask":
        raise BadInput("--scheduler needs --executor dask")
    if isinstance(path_or_dict, dict):
        from ..workflows.campaign_plan import check_shape
        check_shape(path_or_dict, "campaign")
    # everything is validated before the output folder is made or anything runs; planned once
    with checking("checking the campaign, loading the models, planning the jobs …"):
        prepared = camp.prepare(path_or_dict, timeout, max_output_gib, max_steps,
                                positive_int("--max-jobs", max_jobs))
    if scheduler:                      # reachable before anything is written
        with checking(f"connecting to {scheduler} …"):
            camp.connect(scheduler).close()
    if out is None:     # its jobs' store, as the command's: a rerun resumes it
        out = os.path.join("logs", "campaign", prepared.camp.get("name", "campaign"))
        claim_out(out, "campaign", force)
    make_out(str(out))
    with (progress or contextlib.nullcontext)() as view:
        summary = camp.run_campaign(None, out, executor=executor, scheduler=scheduler,
                                    workers=workers, verbose=verbose, view=view,
                                    prepared=prepared, folder=out)
    return CampaignResult(summary, Path(summary["report"]).parent)


def main(args) -> int:
    from ..output.progress import busy, progress_view
    from ..workflows.campaign import Interrupted
    from ..workflows.campaign_plan import load_campaign
    # without --out the campaign's folder is logs/campaign/<name> (resumed when run again)
    own = args.out or os.path.join("logs", "campaign",
                                   load_campaign(args.file).get("name", "campaign"))
    if args.baseline:                  # bad input before anything is written
        from ..results import Result
        Result.load(args.baseline)
        if os.path.exists(own) and os.path.samefile(args.baseline, own):
            raise BadInput(f"--baseline {args.baseline}: is the folder this campaign writes (it "
                           f"would be diffed against itself): save it first with `xval "
                           f"baseline save {args.baseline} base.npz` and pass base.npz")
    warn_workers(args)
    try:
        with stdout_to_stderr():
            r = campaign(args.file, executor=args.executor, scheduler=args.scheduler,
                         workers=args.workers, timeout=args.timeout, out=own,
                         force=args.force,
                         verbose=args.verbose, max_output_gib=args.max_output_gib,
                         max_steps=args.max_steps, max_jobs=args.max_jobs,
                         progress=progress_view, checking=busy)
    except Interrupted as e:             # Ctrl-C: workers stopped, finished jobs kept
        again = " ".join(["xval campaign"] + ([args.file] if args.file else [])
                         + (["--out", args.out] if args.out else []))
        print(f"xval: interrupted: {e}; resume with: {again}", file=sys.stderr)
        return 130
    summary = r.data
    if args.baseline:
        from ..workflows.diff import run_diff
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


COMMAND = Command(
    "campaign", order=6, main=main, api=campaign, result=CampaignResult, docs="campaign.md",
    help="run a campaign file (default: built-in) into a report",
    description="Run every case of a campaign file (JSON or TOML; default: the built-in "
                "campaign) as parallel jobs, reuse results whose inputs did not change, and "
                "write one report.",
    args=(arg("file", nargs="?", help="campaign file, .json or .toml (default: built-in)"),
          *executor_args("jobs"), *RESULT_OUT,
          arg("--json", action="store_true", help="print the summary as one JSON object"),
          arg("--timeout", type=positive_arg("--timeout"), metavar="S",
              help="wall-clock limit per job unless its case sets timeout_s"),
          arg("--max-jobs", type=positive_int_arg("--max-jobs"), default=None, metavar="N",
              help="refuse to start a campaign of more than N jobs (cases × sweep points × "
                   "solvers; default 10000)"),
          arg("--verbose", action="store_true",
              help="show each job's engine messages (banners, warnings) as it finishes; they "
                   "are always in the job's log and the report"),
          arg("--baseline", metavar="DIR",
              help="after the run, diff against this campaign folder or baseline file (report "
                   "in <campaign>/diff/; exit 1 when results moved beyond their error bars)"),
          STRICT, *BUDGET))
