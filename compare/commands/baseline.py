"""`xval baseline save DIR OUT`: a compact, committable baseline of a campaign or run folder."""
from __future__ import annotations

import os

from ..errors import BadInput
from ..output.folders import check_out
from . import Command, arg
from .common import emit_json


def main(args) -> int:
    from ..workflows.sides import save_baseline
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


COMMAND = Command(
    "baseline", order=12, main=main, docs="diff.md",
    help="save a compact baseline of a campaign or run folder",
    description="`xval baseline save DIR OUT`: a compact, committable baseline (.npz) of a "
                "campaign or run folder for `xval diff`.",
    subcommands={"save": ("write the baseline of DIR to OUT", (
        arg("folder", help="campaign folder or run folder"),
        arg("target", help="baseline file to write (.npz)"),
        arg("--json", action="store_true", help="print one JSON object")))})
