"""`xval list`: every scene with its solvers, and every solver."""
from __future__ import annotations

from . import Command


def scenes() -> dict[str, list[str]]:
    """Every scene (as `xval list` shows them) with the names of its solvers."""
    from ..scenes import SCENES
    from ..solvers import solvers_for
    return {name: [s.name for s in solvers_for(name)] for name in SCENES}


def main(args) -> int:
    from ..output.citations import cite_short
    from ..scenes import ORIGIN, SCENES
    from ..solvers import REGISTRY, solvers_for
    for sc in SCENES.values():
        plug = f"  [plug-in: {ORIGIN[sc.name][0]}]" if sc.name in ORIGIN else ""
        print(f"scene  {sc.name:20s} {sc.kind:5s}  solvers: "
              f"{', '.join(s.name for s in solvers_for(sc.name))}  — {sc.title}{plug}")
    groups = {}
    for sc in SCENES.values():
        if sc.group:
            groups.setdefault(sc.group, []).append(sc.name)
    for g, names in groups.items():
        print(f"group  {g:20s} scenes: {', '.join(names)}")
    for s in REGISTRY.values():
        print(f"solver {s.name:20s} scenes: {', '.join(s.leaves)}  — {cite_short(s.doc)}")
    return 0


COMMAND = Command("list", order=1, main=main, api=scenes, docs="list-show.md",
                  help="list scenes and solvers",
                  description="List every scene with its solvers, and every solver.")
