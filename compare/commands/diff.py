"""`xval diff`: which results moved between two campaigns, runs or baselines."""
from __future__ import annotations

from ..output.folders import claim_out
from ..results import DiffResult
from . import Command, arg
from .common import RESULT_OUT, answer


def diff(old, new, *, out=None, force: bool = False) -> DiffResult:
    """`xval diff`: which results moved between two results — each a `Result` (a run held in
    memory too) or a path: a campaign, run or map folder, or a baseline — against their own
    error bars; `s["any_change"]`, `s["lines"]`. With `out` the report and diff.json go into
    that folder (an existing one must be empty or hold an earlier diff, unless `force`)."""
    from ..workflows.diff import run_diff
    if out is not None:
        claim_out(str(out), "diff", force)
    res = run_diff(old, new)                          # bad input before anything is written
    if out is not None:
        res.save(out)
    return res


def main(args) -> int:
    from ..workflows.diff import new_diff_dir
    # without --out a new folder under logs/diff/ (the default place since the first release)
    r = diff(args.old, args.new, out=args.out or new_diff_dir("logs"), force=args.force)
    answer(args, r, r.data)                           # the counts, the changes, notes, report
    return 1 if r["any_change"] else 0


COMMAND = Command(
    "diff", order=11, main=main, api=diff, result=DiffResult, docs="diff.md",
    help="which results moved between two campaigns, runs or baselines, against their own "
         "error bars",
    description="Compare two campaign folders, run folders or baselines: every case × solver "
                "× channel (modes, critical speeds, map boundaries) against the runs' own "
                "error estimates, with what differs in the inputs. Exit 0 nothing changed, 1 "
                "changes found, 2 bad input.",
    args=(arg("old", help="campaign folder, run folder or baseline file"),
          arg("new", help="campaign folder, run folder or baseline file"),
          *RESULT_OUT,
          arg("--json", action="store_true", help="print the diff as one JSON object")))
