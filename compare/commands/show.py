"""`xval show SCENE`: a scene's parameters, channels and sources."""
from __future__ import annotations

from ..results import SceneInfo
from . import Command
from .common import JSON, SCENE, answer


def show(scene: str) -> SceneInfo:
    """A scene's parameters (default, unit, admissible range, meaning), channels and sources;
    `str()` is what `xval show` prints, `.as_json()` what `xval show --json` prints."""
    from ..scenes import get_scene
    return SceneInfo(get_scene(scene))


def main(args) -> int:
    answer(args, show(args.scene))
    return 0


COMMAND = Command(
    "show", order=2, main=main, api=show, result=SceneInfo, docs="list-show.md",
    help="parameters of a scene: default, unit, admissible range",
    description="Every parameter of a scene with default, unit and admissible range, its "
                "channels and the papers it comes from.",
    args=(SCENE, JSON))
