"""`xval.show(scene)`: a scene's description (not a study's result: nothing to save)."""
from __future__ import annotations

from . import tables


class SceneInfo:
    """What `xval show` prints (`str`), its JSON (`as_json()`), and the `Scene` itself
    (`.scene`)."""

    def __init__(self, scene):
        self.scene = scene

    def as_json(self) -> dict:
        from ..output.citations import papers_in
        sc = self.scene
        return {"scene": sc.name, "title": sc.title, "kind": sc.kind,
                "sources": papers_in(sc.source) or [sc.source],
                "channels": list(sc.channels),
                "tolerances": sc.tolerances_for(sc.resolve({})),   # at the defaults
                "params": [{"name": p.name, "default": p.default, "unit": p.unit,
                            "range": p.describe_range(), "doc": p.doc} for p in sc.params]}

    def __str__(self):
        from ..output.citations import papers_in
        sc = self.scene
        out = [f"{sc.name}: {sc.title}"]
        out += [f"  source: {ref}" for ref in papers_in(sc.source) or [sc.source]]
        for p in sc.params:
            d = p.shown_default()
            out.append(f"  {p.name:16s} = {str(d):14s} {p.unit:9s} {p.describe_range():18s} "
                       f"{p.doc}")
        if sc.channels:
            out.append(f"  channels: {', '.join(sc.channels)}")
        return "\n".join(out)

    __repr__ = __str__

    def _repr_markdown_(self):
        sc = self.scene
        rows = [[p.name, p.shown_default(), p.unit, p.describe_range(), p.doc] for p in sc.params]
        return (f"**{sc.name}**: {sc.title}\n\n"
                + tables.markdown(["parameter", "default", "unit", "range", "meaning"], rows)
                + (f"\n\nchannels: {', '.join(sc.channels)}" if sc.channels else ""))
