"""What every study returns: one `Result` family (base.py) — `TimeResult` (a run),
`ModesResult` (natural frequencies), `BenchResult`, `ExtremesResult`, `MapResult`,
`CampaignResult`, `PowerResult`, `DiffResult` (studies.py), `ResponseResult` (response.py),
`CalibrationResult` (calibrate.py) and `Baseline` — each with `to_json`/`from_json`,
`save`/`Result.load`, its tables as text, Markdown and HTML, and what `xval diff` compares
(`side()`). Importing the package registers every type, so `Result.load` can dispatch on the
"result" field of any of them."""
from .base import Result
from .baseline import Baseline
from .calibrate import CalibrationResult
from .modes import ModesResult
from .response import ResponseResult
from .scene_info import SceneInfo
from .studies import (
    BenchResult,
    CampaignResult,
    DiffResult,
    ExtremesResult,
    MapResult,
    PowerResult,
    StudyResult,
)
from .time import TimeResult

__all__ = ["Result", "TimeResult", "ModesResult", "BenchResult", "ExtremesResult",
           "MapResult", "CampaignResult", "PowerResult", "DiffResult", "Baseline",
           "ResponseResult", "CalibrationResult",
           "StudyResult", "SceneInfo"]
