"""`Result`: what every study returns (ROSS's one `Results` base). A result is held in memory;
`to_json()` is what the command's `--json` prints, with the type in its "result" field;
`save(path)` writes what the command writes with `--out` (through compare/output/);
`Result.load(path)` reads any of them back — a run, modes, bench, extremes, map, campaign,
power or diff folder, its JSON file, or a baseline — as the type its "result" field names
(folders written before that field: by their files). Views: `str()` (the tables as text),
Markdown and HTML (Jupyter), `figure()`, and `side()`: what `xval diff` compares;
`problems()`: what `--strict` and `xval.assert_agree` fail on."""
from __future__ import annotations

import dataclasses
import html
from pathlib import Path
from typing import ClassVar

import numpy as np

from ..analysis.metrics import Comparison
from ..analysis.verdict import Verdict
from ..errors import BadInput
from ..scenes import get_scene
from . import tables
from .records import Side, case_type, read_json, readable


class Result:
    TYPE: ClassVar[str] = ""                 # the JSON's "result" field
    JSON: ClassVar[str] = "result.json"      # the file `save` writes the JSON to
    TYPES: ClassVar[dict] = {}               # TYPE -> class: what `load` dispatches on
    out_dir: Path | None = None              # the folder of the result's files (None: memory)
    scene_name: str = ""
    _scene = None

    def __init_subclass__(cls, **kw):
        super().__init_subclass__(**kw)
        if cls.TYPE:
            Result.TYPES[cls.TYPE] = cls

    # --- JSON and files ------------------------------------------------------------------

    def to_json(self) -> dict:
        raise NotImplementedError

    def as_json(self) -> dict:
        """What the command's `--json` prints (= `to_json()`)."""
        return self.to_json()

    @classmethod
    def from_json(cls, obj: dict, folder=None) -> Result:
        """The result `obj` describes (`folder`: where its files are, if any); on `Result`
        itself, of the type its "result" field names."""
        if cls is Result:
            from . import every_type
            every_type()
            if obj.get("result") not in Result.TYPES:
                raise BadInput(f"not an xval result (result type {obj.get('result')!r})")
            return Result.TYPES[obj["result"]].from_json(obj, folder)
        raise NotImplementedError

    def save(self, path) -> Path:
        """Write what the command writes with `--out` into the folder `path` (made if missing);
        returns the folder."""
        raise NotImplementedError

    @staticmethod
    def load(path) -> Result:
        """A result folder, its JSON file, or a baseline file, read back."""
        from ..output import guard
        from . import every_type
        every_type()
        p = Path(path)
        if p.is_file() and p.suffix != ".json":
            return Result.TYPES["baseline"].read(p)
        if p.is_file():
            obj = read_json(p)
            return _typed(obj, p.name, p.parent, p)
        if not p.is_dir():
            raise BadInput(f"{path}: no such campaign folder, run folder or baseline file")
        if (p / "summary.json").exists() or (p / "jobs").is_dir():
            owner = guard.lock_owner(p)
            if owner:
                raise BadInput(f"{p}: a campaign is writing this folder (pid "
                               f"{owner.get('pid')} on {owner.get('host')}): diff it when it "
                               f"has finished")
            if not (p / "summary.json").exists():
                raise BadInput(f"{p}: incomplete campaign folder (no summary.json: it was "
                               f"stopped); run the same `xval campaign` again to finish it")
            return _typed(read_json(p / "summary.json"), "summary.json", p, p / "summary.json")
        if guard.is_incomplete(p):
            raise BadInput(f"{p}: incomplete run folder ({guard.MARKER} marker, no result.json: "
                           f"the run was stopped before it finished); run it again")
        # each registered type's file (result.json first: a run's, a modes result's)
        for name in dict.fromkeys(["result.json"] + [t.JSON for t in Result.TYPES.values()]):
            if (p / name).exists():
                return _typed(read_json(p / name), name, p, p / name)
        raise BadInput(f"{path}: not a campaign folder (summary.json), run folder (result.json) "
                       f"or baseline file")

    def _of(self, scene) -> str:
        """A run's or modes result's scene, given as the `Scene` or by name: its name."""
        self._scene = None if isinstance(scene, str) else scene
        return scene if isinstance(scene, str) else scene.name

    @property
    def scene(self):
        """The `Scene` (looked up by name for a result read from files)."""
        if self._scene is None:
            self._scene = get_scene(self.scene_name)
        return self._scene

    # --- views -----------------------------------------------------------------------------

    def title(self) -> str | None:
        return None

    def tables(self) -> list[tuple[list, list]]:
        """(header, rows of strings) of each table the views show."""
        return []

    def lines(self) -> list[str]:
        """Lines shown after the tables (a summary's: what the command prints)."""
        return []

    def __str__(self):
        blocks = [self.title()] if self.title() else []
        blocks += [tables.text(h, r) for h, r in self.tables()]
        return "\n\n".join(blocks + (["\n".join(self.lines())] if self.lines() else []))

    __repr__ = __str__

    def _repr_markdown_(self):
        blocks = [f"**{self.title()}**"] if self.title() else []
        blocks += [tables.markdown(h, r) for h, r in self.tables()]
        return "\n\n".join(blocks + (["```\n" + "\n".join(self.lines()) + "\n```"]
                                     if self.lines() else []))

    def _repr_html_(self):
        out = f"<p><b>{html.escape(self.title())}</b></p>" if self.title() else ""
        out += "".join(tables.html_table(h, r) for h, r in self.tables())
        return out + (f"<pre>{html.escape(chr(10).join(self.lines()))}</pre>"
                      if self.lines() else "")

    def figure(self):
        """A matplotlib Figure of the result."""
        raise BadInput(f"a {self.TYPE} result draws no figure (its report has the plots)")

    def side(self) -> Side:
        """What `xval diff` compares of this result."""
        raise BadInput(f"a {self.TYPE} result cannot be diffed (a run, modes, map or campaign "
                       f"result, or a baseline, can)")

    def where(self) -> str:
        """The result's folder, or what it is when held in memory (the diff names it)."""
        return str(self.out_dir) if self.out_dir else f"{self.TYPE} result in memory"

    # --- what --strict refuses -------------------------------------------------------------

    def problems(self, channels=None) -> list[str]:
        """What `--strict` and `xval.assert_agree` fail on, one line each ([]: nothing to
        refuse); `channels`: only the comparisons on these (a run or modes result)."""
        return []


class ComparedResult(Result):
    """A run or modes result: `runs` {solver: run with a status} and pairwise `comparisons`."""
    runs: dict
    comparisons: list

    def problems(self, channels=None) -> list[str]:
        """A solver without an answer, a comparison (on `channels`) whose verdict is refused,
        and a result with nothing compared (a skipped comparison's failed run is named)."""
        chosen = [c for c in self.comparisons if channels is None or c.channel in channels]
        return verdict_problems([(s, r.status) for s, r in self.runs.items()],
                                [(c.a, c.b, c.channel, c.verdict) for c in chosen])


def verdict_problems(statuses, comparisons) -> list[str]:
    """What --strict refuses of (solver, status) pairs and (a, b, channel, verdict) rows: a
    solver without an answer, a refused verdict (`Verdict.refused`), nothing compared."""
    out = [f"{s} {status} (incomplete)" for s, status in statuses if status != "ok"]
    out += [f"{a} vs {b} {ch}: {v}" for a, b, ch, v in comparisons if Verdict(v).refused]
    if not comparisons:
        out.append("nothing was compared (incomplete)")
    return out


def _guess(name: str, obj: dict, folder) -> str:
    """The type of a result written before the "result" field: by its file and content."""
    if name in ("summary.json", "map.json", "bench.json", "diff.json"):
        return {"summary.json": "campaign", "map.json": "map", "bench.json": "bench",
                "diff.json": "diff"}[name]
    if "results" in obj and "n_failed" in obj:
        return "extremes"
    return case_type(obj, folder)


def _typed(obj, name, folder, path) -> Result:
    if not isinstance(obj, dict):
        raise BadInput(f"{path}: not what xval writes (not a JSON object)")
    kind = obj.get("result") or _guess(name, obj, folder)
    if kind not in Result.TYPES:
        raise BadInput(f"{path}: not what xval writes (result type {kind!r})")
    with readable(path):
        return Result.TYPES[kind].from_json(obj, folder)


_FIELDS = [f.name for f in dataclasses.fields(Comparison)]


def comparisons_from_json(rows: list[dict]) -> list[Comparison]:
    """Comparisons as `Comparison.as_dict()` wrote them (a NaN was written as null)."""
    nan = lambda k, v: v if v is not None or k in ("error_estimate",) else np.nan
    return [Comparison(**{k: nan(k, d.get(k)) for k in _FIELDS if k in d}) for d in rows]
