"""`xval modes`: natural frequencies from every solver that linearises, matched mode by mode."""
from __future__ import annotations

from collections.abc import Callable

from ..output.folders import claim_out
from ..results import ModesResult
from ..workflows.plan import names
from . import Command, arg
from .common import (
    RESULT_OUT,
    STRICT,
    STUDY,
    compared_answer,
    log,
    overrides,
    parse_sets,
    quiet,
    result_folder,
    stdout_to_stderr,
)


def modes(scene: str, solvers=None, *, out=None, params: dict | None = None,
          log: Callable | None = None, campbell_frame: str | None = None,
          force: bool = False, **kw) -> ModesResult:
    """Natural frequencies from every solver that linearises (default: all of the scene's),
    matched mode by mode; the Campbell diagram and critical speeds where the scene sweeps (the
    figure in `campbell_frame`, "fixed" or "rotating"; default: the solvers' frame), the mode
    shapes where it draws them. `out`: the folder its files are written into (empty or an
    earlier modes result, unless `force`). Returns a `ModesResult`."""
    from ..workflows.modes import run_modes
    if out is not None:
        claim_out(str(out), "modes", force)
    res = run_modes(scene, names(solvers), overrides(params, kw), log=log or quiet,
                    campbell_frame=campbell_frame)
    if out is not None:
        res.save(out)
    return res


def main(args) -> int:
    from ..results.modes import threshold_lines
    out = result_folder(args)
    with stdout_to_stderr():
        r = modes(args.scene, args.solver, out=out, params=parse_sets(args.set), log=log,
                  campbell_frame=args.campbell_frame, force=args.force)
    rc = compared_answer(args, r)
    if not args.json:
        for line in threshold_lines(r.extra.get("threshold")):
            print(line)
    return rc


COMMAND = Command(
    "modes", order=4, main=main, api=modes, result=ModesResult, docs="modes.md",
    help="natural frequencies, Campbell diagram, critical speeds",
    description="Natural frequencies from every solver that linearises, matched mode by mode; "
                "Campbell diagram for rotor scenes.",
    args=(*STUDY, *RESULT_OUT, STRICT,
          arg("--campbell-frame", choices=("fixed", "rotating"), default=None,
              help="draw the Campbell figure in this frame (default: the frame the scene's "
                   "solvers report; the other where the modes whirl)")))
