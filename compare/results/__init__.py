"""What every study returns: one `Result` family (base.py) — `TimeResult` (a run),
`ModesResult` (natural frequencies), `BenchResult`, `ExtremesResult`, `MapResult`,
`CampaignResult`, `PowerResult`, `DiffResult` (studies.py), `ResponseResult` (response.py),
`CalibrationResult` (calibrate.py) and `Baseline` — each with `to_json`/`from_json`,
`save`/`Result.load`, its tables as text, Markdown and HTML, and what `xval diff` compares
(`side()`). Importing the package registers every type, so `Result.load` can dispatch on the
"result" field of any of them."""
import importlib
import pkgutil

from ..contract import lazy_exports

# each type's module loads on first use (`xval run` needs TimeResult alone); `every_type`
# loads them all for `Result.load`, which dispatches on the JSON's "result" field
LAZY = {"Result": "base", "Baseline": "baseline", "CalibrationResult": "calibrate",
        "ModesResult": "modes", "ResponseResult": "response", "SceneInfo": "scene_info",
        "TimeResult": "time", **{n: "studies" for n in (
            "BenchResult", "CampaignResult", "DiffResult", "ExtremesResult", "MapResult",
            "PowerResult", "StudyResult")}}
__getattr__ = lazy_exports(__name__, LAZY)


def every_type() -> None:
    """Import every Result type, each module in this package (a type registers itself in
    `Result.TYPES`)."""
    for m in pkgutil.iter_modules(__path__):
        importlib.import_module(f"{__name__}.{m.name}")


__all__ = list(LAZY)
