"""`xval diff`: which results moved between two campaigns, runs or baselines."""
from __future__ import annotations

from ..output.folders import check_out, make_out
from ..results import DiffResult
from . import Command, arg
from .common import answer


def diff(old, new, *, out=None) -> DiffResult:
    """`xval diff`: which results moved between two results — each a `Result` (a run held in
    memory too) or a path: a campaign, run or map folder, or a baseline — against their own
    error bars. With `out` the report goes to out/diff/<time>-<pid>/; `s["any_change"]`,
    `s["lines"]`."""
    from ..workflows.diff import new_diff_dir, run_diff
    if out is not None:
        check_out(str(out))
    res = run_diff(old, new)                          # bad input before anything is written
    if out is not None:
        make_out(str(out))
        res.save(new_diff_dir(out))
    return res


def main(args) -> int:
    r = diff(args.old, args.new, out=args.out)
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
          arg("--out", default="logs", metavar="DIR",
              help="the report goes to DIR/diff/<time>-<pid>/ (default: logs)"),
          arg("--json", action="store_true", help="print the diff as one JSON object")))
