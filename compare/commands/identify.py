"""`xval identify`: a scene's unknown parameters (the bearing rotor's defect) fitted to a
measured record by each solver's model, with intervals, identifiability and a verdict per
parameter and solver pair; `--synthesise FILE` writes a record from one solver with stated
noise. The study: this module, compare/workflows/identify.py (the fit; measured.py the
records, detection.py the intervals' coverage and the detection limits),
compare/results/identify.py, docs/commands/identify.md (its figures:
compare/output/identify_plot.py)."""
from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from ..errors import BadInput
from ..output.folders import claim_out
from ..results.identify import DetectionResult, IdentifyResult
from . import Command, arg
from .common import (
    RESULT_OUT,
    STRICT,
    STUDY,
    answered,
    emit_json,
    log,
    parse_sets,
    quiet,
    stdout_to_stderr,
)


def _sigmas(items) -> dict:
    out = {}
    for k, v in parse_sets(items).items():
        try:
            out[k] = float(v)
        except ValueError:
            raise BadInput(f"--noise {k}={v}: σ must be a number") from None
        if not (math.isfinite(out[k]) and out[k] > 0):
            raise BadInput(f"--noise {k}={v}: σ must be a positive number")
    return out


def identify(scene: str, data, unknowns=None, solvers=None, *, noise: dict | None = None,
             profile: bool = True, poincare: float | None = None, out=None,
             force: bool = False, params: dict | None = None, log: Callable | None = None,
             **kw) -> IdentifyResult:
    """Fit `unknowns` (default: the scene's, e.g. the bearing defect's height, width and angle)
    to the record `data` — a CSV/.npz path or a dict {"t": …, channel: …} — with each solver's
    model (`xval identify`); σ per channel from `noise` or estimated; `poincare`: a shaft
    angle where the orbit is fitted once per revolution (its section) instead. Returns an
    `IdentifyResult` (saved in the folder `out` when given: `claim_out`'s rule)."""
    from ..workflows.identify import identify as run
    from ..workflows.measured import read_record
    from .common import overrides
    if out is not None:
        claim_out(str(out), "identify", force)
    if isinstance(data, dict):
        rec, label = {k: np.asarray(v, float) for k, v in data.items()}, "(in memory)"
    else:
        rec, label = read_record(data), str(data)
    res = run(scene, rec, unknowns, solvers, overrides(params, kw), noise, profile, label,
              poincare, log or quiet)
    if out is not None:
        res.save(out)
    return res


def synthesise(scene: str, path, solver: str, *, noise: dict | None = None, seed: int = 0,
               channels=None, params: dict | None = None, **kw):
    """Write a synthetic measured record to `path` (.npz or CSV): `solver`'s run of `scene` at
    `params`, white normal noise σ per channel (`noise`, default the scene's) from `seed`."""
    from ..output.identify_plot import write_record
    from ..workflows.measured import synthesise as synth
    from .common import overrides
    rec = synth(scene, solver, overrides(params, kw), noise, seed, channels)
    return write_record(path, rec)


def detection(scene: str, solvers=None, *, alpha: float = 0.01, beta: float = 0.05,
              out=None, force: bool = False, params: dict | None = None,
              log: Callable | None = None, **kw) -> DetectionResult:
    """The smallest defect (the scene's `Fit.size`) told from none at false-alarm rate
    `alpha` and miss rate `beta`, per solver, speed and channel set, against the noise level
    (`xval identify SCENE --detection`); the solvers' limits judged pair by pair."""
    from ..workflows.detection import detection as run
    from .common import overrides
    if out is not None:
        claim_out(str(out), "detection", force)
    res = DetectionResult(run(scene, solvers, overrides(params, kw), alpha, beta,
                              log=log or quiet))
    if out is not None:
        res.save(out)
    return res


def main(args) -> int:
    noise = _sigmas(args.noise)
    if args.detection:
        if args.data or args.synthesise:
            raise BadInput("--detection maps the detection limits; it takes no record")
        with stdout_to_stderr():
            r = detection(args.scene, args.solver or None, alpha=args.alpha, beta=args.beta,
                          out=args.out, force=args.force, params=parse_sets(args.set),
                          log=log)
        return answered(args, r)
    if args.synthesise:
        if len(args.solver) != 1:
            raise BadInput("--synthesise: name the one solver that makes the record "
                           "(--solver NAME)")
        if args.data:
            raise BadInput("--synthesise writes a record; --data fits one (not both)")
        with stdout_to_stderr():
            path = synthesise(args.scene, args.synthesise, args.solver[0], noise=noise,
                              seed=args.seed, channels=args.channel or None,
                              params=parse_sets(args.set))
        if args.json:
            emit_json({"scene": args.scene, "record": str(path), "solver": args.solver[0],
                       "seed": args.seed})
        else:
            print(f"record: {path}")
        return 0
    if not args.data:
        raise BadInput("--data FILE: the record to fit (or --synthesise FILE to make one)")
    with stdout_to_stderr():
        r = identify(args.scene, args.data, args.unknown or None, args.solver or None,
                     noise=noise, profile=not args.no_profile, poincare=args.poincare,
                     out=args.out, force=args.force,
                     params=parse_sets(args.set), log=log)
    return answered(args, r)


COMMAND = Command(
    "identify", order=6, main=main, api=identify, result=IdentifyResult, docs="identify.md",
    help="fit unknown parameters (a bearing defect) to a measured record, every solver",
    description="Fit a scene's unknown parameters (bearing-rotor: the defect's height, width "
                "and angle) to a measured record — CSV with a header row or .npz, columns t "
                "[s] and any of the scene's channels — with each solver's runs as the model "
                "(scipy least_squares, multi-start across a periodic unknown): estimates with "
                "95 %% intervals from the Jacobian, checked by the profile of the cost; an "
                "unknown the data do not determine is reported as such; the estimates judged "
                "solver against solver. --synthesise FILE writes a record from one solver "
                "with stated noise instead.",
    args=(*STUDY,
          arg("--data", metavar="FILE", help="the record to fit (.csv with a header row, or "
              ".npz): column t [s] and channels of the scene"),
          arg("--unknown", action="append", default=[], metavar="NAME",
              help="a parameter to fit (repeatable; default: the scene's, e.g. defect_height, "
                   "defect_width, defect_angle); the others at their --set or default values"),
          arg("--noise", action="append", default=[], metavar="CHANNEL=SIGMA",
              help="the noise σ of a channel (repeatable); a channel without one: estimated "
                   "from the record and the fit's residuals. With --synthesise: the noise "
                   "added (default the scene's)"),
          arg("--poincare", type=float, metavar="ANGLE",
              help="fit the orbit as its stroboscopic Poincaré section: the scene's section "
                   "channels (bearing-rotor: journal a's x, y) sampled once per revolution "
                   "where its angle (spin_angle) passes ANGLE + 2πk [rad], the record holding "
                   "all three; poincare.png and poincare.rrd show it"),
          arg("--no-profile", action="store_true",
              help="skip the profile-likelihood check of the intervals"),
          arg("--synthesise", metavar="FILE",
              help="write a synthetic record from --solver's run at the --set parameters "
                   "with --noise and --seed, and stop"),
          arg("--detection", action="store_true",
              help="map the smallest defect told from none (false alarm --alpha, miss --beta) "
                   "against noise level, speed and observed channels, every solver, instead "
                   "of fitting a record"),
          arg("--alpha", type=float, default=0.01, help="--detection's false-alarm rate "
              "(default 0.01)"),
          arg("--beta", type=float, default=0.05, help="--detection's miss rate "
              "(default 0.05)"),
          arg("--seed", type=int, default=0, help="the synthetic noise's seed (default 0)"),
          arg("--channel", action="append", default=[], metavar="NAME",
              help="with --synthesise: a channel to record (repeatable; default the scene's "
                   "measured set)"),
          *RESULT_OUT, STRICT))
