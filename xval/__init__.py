"""xval from Python: `import xval; r = xval.run("rotor-spinup", torque=3.2, t_end=5)`.

The distribution's name as an import: the same operations as the `xval` command (the command
is a thin layer over them), implemented in `compare.api`. See docs/python-api.md.
"""
from compare.api import (
    assert_agree,
    assert_matches_baseline,
    bench,
    campaign,
    diff,
    extremes,
    load,
    map,
    modes,
    power,
    response,
    run,
    scenes,
    show,
)
from compare.errors import BadInput
from compare.results import (
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

XvalError = BadInput            # one exception type for bad arguments; either name catches it

__all__ = ["run", "modes", "response", "bench", "extremes", "map", "campaign", "diff", "power",
           "scenes",
           "show", "load", "assert_agree", "assert_matches_baseline", "BadInput", "XvalError",
           "Result", "TimeResult", "ModesResult", "BenchResult", "ExtremesResult", "MapResult",
           "CampaignResult", "PowerResult", "DiffResult", "ResponseResult", "SceneInfo"]
