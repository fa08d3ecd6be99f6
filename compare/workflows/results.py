"""What the Python API returns: a run, a modes run, a summary (bench, extremes, campaign) and a
scene's description, as objects with the numbers as numpy arrays, the verdict table as text,
Markdown and HTML (Jupyter shows it), a matplotlib figure, Arrow tables, and `.save(path)`,
which writes what `xval` writes."""
from __future__ import annotations

import html
import json
import shutil
import tempfile
import weakref
from pathlib import Path

import numpy as np

from ..analysis.metrics import Comparison, ratio_text
from ..atomic import write_json
from ..errors import BadInput
from .guard import mark_incomplete
from .inputs import make_out
from .modes import DAMPED_HEADER, damped_rows
from .runner import RunResult, write_outputs

# --- tables --------------------------------------------------------------------------------

def _num(x, spec=".3g"):
    if x is None or (isinstance(x, float) and not np.isfinite(x)):
        return "—"
    return format(x, spec)


def _text(header, rows):
    cols = [header] + rows
    width = [max(len(str(r[i])) for r in cols) for i in range(len(header))]
    line = lambda r: "  ".join(str(v).ljust(w) for v, w in zip(r, width)).rstrip()
    return "\n".join([line(header), line(["-" * w for w in width])] + [line(r) for r in rows])


def _markdown(header, rows):
    esc = lambda v: str(v).replace("|", "\\|")
    return "\n".join(["| " + " | ".join(map(esc, header)) + " |",
                      "|" + "---|" * len(header)]
                     + ["| " + " | ".join(map(esc, r)) + " |" for r in rows])


def _html(header, rows):
    cell = lambda tag, v: f"<{tag}>{html.escape(str(v))}</{tag}>"
    return ("<table><thead><tr>" + "".join(cell("th", h) for h in header) + "</tr></thead>"
            "<tbody>" + "".join("<tr>" + "".join(cell("td", v) for v in r) + "</tr>"
                                for r in rows) + "</tbody></table>")


VERDICT_HEADER = ["a", "b", "channel", "max|Δ|", "error est.", "allowance", "max rel",
                  "Δ/bound", "verdict"]


def verdict_rows(comparisons: list[Comparison]) -> list[list[str]]:
    """One row per comparison: the deviation against what explains it (both solvers' error
    estimates, the scene's allowance), in SI units, and the verdict."""
    return [[c.a, c.b, c.channel, _num(c.deviation), _num(c.error_estimate),
             _num(c.allowance), _num(c.max_rel, ".2e"), ratio_text(c.ratio), c.shown]
            for c in comparisons]


def disagreement_message(result, channels=None) -> str | None:
    """The verdict table of the comparisons on `channels` (default: all) that do not agree
    (disagree, or skipped because a solver failed), or None when every one agrees. A solver
    that failed, or a run with nothing compared, is never agreement: the message says so."""
    chosen = [c for c in result.comparisons if channels is None or c.channel in channels]
    if channels is not None:
        compared = list(dict.fromkeys(c.channel for c in result.comparisons))
        unknown = sorted(set(channels) - set(compared))
        if unknown:
            raise BadInput(f"channels: {', '.join(unknown)} not compared in this run "
                           f"(compared: {', '.join(compared)})")
    bad = [c for c in chosen if c.verdict != "agree"]
    missing = [f"{s} {r.status}" + (f" ({r.reason})" if r.reason else "")
               for s, r in result.runs.items() if r.status != "ok"]
    if not bad and not missing and chosen:
        return None
    head = f"{len(bad)} of {len(chosen)} comparisons of {result.scene} do not agree"
    if missing:
        head += "; incomplete: " + ", ".join(missing)
    if not chosen:
        head += "; nothing was compared"
    rows = [r + [c.decided_by] for r, c in zip(verdict_rows(bad), bad)]
    return head + (":\n" + _text(VERDICT_HEADER + ["decided by"], rows) if bad else "")


class _Folder:
    """Where a result's files are. A run made without `out` works in a temporary folder that
    goes away with the result object (nothing is left under logs/); `.save(path)` keeps it."""

    def __init__(self, out_dir, temporary=None):
        self.out_dir = Path(out_dir) if out_dir else None
        self.temporary = temporary             # the temporary folder holding out_dir, if any
        if temporary:
            weakref.finalize(self, shutil.rmtree, str(temporary), True)


def temporary_folder() -> Path:
    return Path(tempfile.mkdtemp(prefix="xval-"))


def _repath(obj, old: str, new: str):
    if isinstance(obj, dict):
        return {k: _repath(v, old, new) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_repath(v, old, new) for v in obj]
    if isinstance(obj, str) and obj.startswith(old):
        return new + obj[len(old):]
    return obj


def copy_folder(src: Path, dest, data: dict) -> tuple[Path, dict]:
    """The result's folder copied to `dest` (made if missing), the paths in its JSON files and
    in `data` pointing at the copy."""
    make_out(str(dest))
    dest = Path(dest)
    shutil.copytree(src, dest, dirs_exist_ok=True)
    for f in dest.glob("*.json"):
        write_json(f, _repath(json.loads(f.read_text()), str(src), str(dest)))
    return dest, _repath(data, str(src), str(dest))


def _arrow_rows(rows: list[dict]):
    import pyarrow as pa
    return pa.Table.from_pylist(rows)


def _pandas(table):
    try:
        import pandas  # noqa: F401
    except ImportError:
        raise ImportError("to_pandas() needs pandas, an optional extra: pip install "
                          "'xval[pandas]' (or use to_arrow())") from None
    return table.to_pandas()


# --- a time-domain run ---------------------------------------------------------------------

class TimeResult:
    """`xval.run(...)`: per solver a `Trajectory` (`r["quaternion"].t`, `.channels[...]`,
    `.errors[...]` — the solver's own error estimate on the grid —, `.status`, `.wall_s`,
    `.settings`, `.stats`), the pairwise `comparisons` with their verdicts, the `findings`."""

    def __init__(self, result: RunResult, temporary=None):
        self.result = result
        self.scene = result.scene.name
        self.params = result.params
        self.runs = {tr.solver: tr for tr in result.trajectories}
        self.comparisons = result.comparisons
        self.findings = result.findings
        self._folder = _Folder(result.out_dir, temporary)
        self.files = {} if temporary else dict(result.files)

    out_dir = property(lambda self: None if self._folder.temporary else self._folder.out_dir)
    solvers = property(lambda self: list(self.runs))
    t = property(lambda self: next(iter(self.runs.values())).t)
    ok = property(lambda self: all(tr.status == "ok" for tr in self.runs.values()))
    disagreements = property(lambda self: [c for c in self.comparisons
                                           if c.verdict == "disagree"])

    def __getitem__(self, solver):
        try:
            return self.runs[solver]
        except KeyError:
            raise KeyError(f"no run of {solver!r} (ran: {', '.join(self.runs)})") from None

    def final(self, channel: str) -> dict:
        """The last value of `channel` per solver."""
        return {s: float(tr.channels[channel][-1]) for s, tr in self.runs.items()}

    def as_json(self) -> dict:
        """What `xval run --json` prints."""
        return self.result.as_json()

    def _solver_table(self):
        chs = list(self.result.scene.channels)
        rows = [[s, tr.status, _num(tr.wall_s)] + [_num(tr.channels[c][-1], ".6g")
                                                   if c in tr.channels else "—" for c in chs]
                for s, tr in self.runs.items()]
        return ["solver", "status", "wall [s]"] + [f"{c} (end)" for c in chs], rows

    def _title(self):
        n_ok = sum(c.verdict == "agree" for c in self.comparisons)
        return (f"{self.scene}: {len(self.runs)} solvers, {n_ok} of {len(self.comparisons)} "
                "comparisons agree")

    def __str__(self):
        return "\n\n".join([self._title(), _text(*self._solver_table()),
                            _text(VERDICT_HEADER, verdict_rows(self.comparisons))])

    __repr__ = __str__

    def _repr_markdown_(self):
        return "\n\n".join([f"**{self._title()}**", _markdown(*self._solver_table()),
                            _markdown(VERDICT_HEADER, verdict_rows(self.comparisons))])

    def _repr_html_(self):
        return (f"<p><b>{html.escape(self._title())}</b></p>" + _html(*self._solver_table())
                + _html(VERDICT_HEADER, verdict_rows(self.comparisons)))

    def plot(self, channels=None):
        """A matplotlib Figure: each channel (default: all) per solver, the closed form dashed
        where the scene has one — the report's channel plot."""
        from ..output.report import channels_figure
        known = self.result.scene.channels
        for c in channels or ():
            if c not in known:
                raise BadInput(f"channel {c!r}: not a channel of {self.scene} "
                               f"(channels: {', '.join(known)})")
        return channels_figure(self.result, channels)

    def to_arrow(self, what: str = "trajectories"):
        """"trajectories": one row per solver and time (`solver`, `t`, each channel, and
        `error.<channel>` where the solver's error was estimated, else null);
        "comparisons": one row per comparison."""
        if what == "comparisons":
            return _arrow_rows([c.as_dict() for c in self.comparisons])
        if what != "trajectories":
            raise BadInput(f"to_arrow: {what!r} is not 'trajectories' or 'comparisons'")
        import pyarrow as pa
        chs = list(self.result.scene.channels)
        errs = [c for c in chs if any(c in tr.errors for tr in self.runs.values())]
        parts = []
        for s, tr in self.runs.items():
            n = len(tr.t)
            cols = {"solver": pa.array([s] * n), "t": pa.array(tr.t)}
            cols.update({c: pa.array(tr.channels[c]) for c in chs})
            cols.update({f"error.{c}": pa.array(tr.errors[c]) if c in tr.errors
                         else pa.nulls(n, pa.float64()) for c in errs})
            parts.append(pa.table(cols))
        return pa.concat_tables(parts)

    def to_pandas(self, what: str = "trajectories"):
        return _pandas(self.to_arrow(what))

    def save(self, path) -> Path:
        """Write what `xval run --out` writes into the folder `path` (made if missing): one
        .npz per solver, run.rrd, report.md with its plots, result.json."""
        make_out(str(path))
        path = Path(path)
        marker = mark_incomplete(path)              # as a run folder: until result.json
        files = {tr.solver: tr.save(path / f"{tr.solver}.npz")
                 for tr in self.result.trajectories}
        r = self.result
        write_outputs(RunResult(r.scene, r.params, r.trajectories, r.comparisons, r.findings,
                                path, files))
        marker.unlink()
        return path


# --- natural frequencies -------------------------------------------------------------------

class ModesResult:
    """`xval.modes(...)`: per solver the `Modes` (`r["mstmm"].frequencies_hz`, `.labels`,
    `.status`, `.wall_s`), the mode-by-mode `comparisons`, the Campbell lines and critical
    speeds where the scene sweeps (`critical_speeds`, `campbell`), and the JSON of `xval
    modes --json` (`as_json()`)."""

    FREQ_HEADER = ["solver", "status", "wall [s]", "frequencies [Hz] (labels)"]

    def __init__(self, obj: dict, results: list, comparisons: list, out_dir,
                 temporary=None):
        self._obj = obj
        self.scene = obj["scene"]
        self.params = obj["params"]
        self.runs = {r.solver: r for r in results}
        self.comparisons = comparisons
        self.critical_speeds = obj.get("critical_speeds", {})
        self.campbell = obj.get("campbell")
        self._folder = _Folder(out_dir, temporary)

    out_dir = property(lambda self: None if self._folder.temporary else self._folder.out_dir)
    solvers = property(lambda self: list(self.runs))
    disagreements = property(lambda self: [c for c in self.comparisons
                                           if c.verdict == "disagree"])

    def __getitem__(self, solver):
        return self.runs[solver]

    def as_json(self) -> dict:
        return self._obj

    def _freq_rows(self):
        return [[s, m.status, _num(m.wall_s),
                 ", ".join(f"{f:.6g}" + (f" ({lb})" if lb else "")
                           for f, lb in zip(m.frequencies_hz,
                                            m.labels or [""] * len(m.frequencies_hz)))
                 or (m.reason or "")] for s, m in self.runs.items()]

    status = property(lambda self: self._obj.get("status"))

    def _title(self):
        return f"{self.scene}: {len(self.runs)} solvers, {self._obj.get('summary')}"

    def _crit(self):
        return [f"critical {s}: " + ", ".join(f"{k} {v:.6f}" for k, v in c.items())
                for s, c in self.critical_speeds.items() if c]

    def _damped(self, table):
        """The damped modes (ζ, log dec, rad/s and rpm beside Hz), where a solver gives ζ."""
        rows = damped_rows(list(self.runs.values()))
        return [table(DAMPED_HEADER, rows)] if rows else []

    def __str__(self):
        return "\n\n".join([self._title(), _text(self.FREQ_HEADER, self._freq_rows()),
                            *self._damped(_text),
                            _text(VERDICT_HEADER, verdict_rows(self.comparisons))]
                           + (["\n".join(self._crit())] if self._crit() else []))

    __repr__ = __str__

    def _repr_markdown_(self):
        return "\n\n".join([f"**{self._title()}**", _markdown(self.FREQ_HEADER,
                                                             self._freq_rows()),
                            *self._damped(_markdown),
                            _markdown(VERDICT_HEADER, verdict_rows(self.comparisons))]
                           + ["\n".join(f"- {x}" for x in self._crit())])

    def _repr_html_(self):
        return (f"<p><b>{html.escape(self._title())}</b></p>"
                + _html(self.FREQ_HEADER, self._freq_rows())
                + _html(VERDICT_HEADER, verdict_rows(self.comparisons))
                + "".join(f"<p>{html.escape(x)}</p>" for x in self._crit()))

    def plot(self):
        """A matplotlib Figure: the Campbell diagram where the scene sweeps, else each
        solver's frequencies side by side."""
        from matplotlib.figure import Figure
        fig = Figure(figsize=(7.5, 4.8))
        ax = fig.subplots()
        if self.campbell and self.campbell["lines_hz"]:
            x = self.campbell["values"]
            for k, (s, lines) in enumerate(self.campbell["lines_hz"].items()):
                for j, (key, f) in enumerate(lines.items()):
                    ax.plot(x, f, lw=1, ls=["-", "--", ":", "-."][k % 4], color=f"C{j % 10}",
                            label=f"{s}: {key}")
            ax.set_xlabel(self.campbell["parameter"])
            ax.legend(fontsize=6, ncol=2)
        else:
            for i, m in enumerate(self.runs.values()):
                ax.plot([i] * len(m.frequencies_hz), m.frequencies_hz, "_", ms=30, mew=2)
            ax.set_xticks(range(len(self.runs)), list(self.runs))
            ax.set_yscale("log")
        ax.set_ylabel("frequency [Hz]")
        ax.grid(alpha=0.3)
        ax.set_title(self.scene)
        fig.tight_layout()
        return fig

    def to_arrow(self, what: str = "frequencies"):
        """"frequencies": one row per solver and mode; "comparisons": one per comparison."""
        if what == "comparisons":
            return _arrow_rows([c.as_dict() for c in self.comparisons])
        if what != "frequencies":
            raise BadInput(f"to_arrow: {what!r} is not 'frequencies' or 'comparisons'")
        return _arrow_rows([{"solver": s, "mode": i + 1,
                             "label": (m.labels[i] if i < len(m.labels) else "") or "",
                             "frequency_hz": float(f)}
                            for s, m in self.runs.items()
                            for i, f in enumerate(m.frequencies_hz)])

    def to_pandas(self, what: str = "frequencies"):
        return _pandas(self.to_arrow(what))

    def save(self, path) -> Path:
        """The folder `xval modes --out` writes (report, result.json, Campbell diagram and
        recording, mode shapes), copied to `path`."""
        return copy_folder(self._folder.out_dir, path, self._obj)[0]


# --- bench, extremes, campaign -------------------------------------------------------------

class Summary:
    """`xval.bench/extremes/campaign(...)`: the dict `--json` prints (`s["..."]`, `.data`),
    the lines the command prints (`str(s)`), the report's path and `.save(path)`."""

    def __init__(self, kind: str, data: dict, out_dir, temporary=None):
        self.kind, self.data = kind, data
        self._folder = _Folder(out_dir, temporary)

    out_dir = property(lambda self: None if self._folder.temporary else self._folder.out_dir)
    report = property(lambda self: Path(self.data["report"]) if self.data.get("report")
                      else None)

    def __getitem__(self, key):
        return self.data[key]

    def keys(self):
        return self.data.keys()

    def as_json(self) -> dict:
        return self.data

    @property
    def lines(self) -> list[str]:
        """What `xval <kind>` prints, before the report's path."""
        d = self.data
        if self.kind == "bench":
            return list(d["summary_lines"])
        if self.kind == "extremes":
            return [f"{r['case']:32s} {r['solver']:26s} {r['outcome']:18s} {r['detail']}"
                    for r in d["results"]]
        if self.kind == "diff":
            s = d["summary"]
            return ([f"{s['changed']} changed, {s['unchanged']} unchanged, {s['new']} new, "
                     f"{s['gone']} gone (runs); {s['channels_changed']} channels changed"]
                    + list(d["lines"]) + [f"note: {n}" for n in d["notes"][:20]])
        if self.kind == "power":
            return [f"{r['parameter']:20s} {r['solver']:26s} "
                    + (f"ε* {r['epsilon']:.2g}  ({' vs '.join(r['pair'])}, {r['channel']}; "
                       f"{r['how']})"
                       if r["epsilon"] is not None else f"—  ({r['how']})")
                    for r in d["power"]] + [d["summary"], f"{d['runs']} runs, "
                                                         f"{d['wall_s']:.1f} s"]
        if self.kind == "map":
            from ..output.map_plot import status_line
            out = []
            for s, cs in d["boundaries"].items():
                for c in cs:
                    row = "" if c["y"] is None else f" at {d['y']['name']} = {c['y']:.6g}"
                    out.append(f"{s:14s} {c['from']} → {c['to']}{row}: {d['x']['name']} in "
                               f"[{c['bracket'][0]:.6g}, {c['bracket'][1]:.6g}]")
            return out + [f"{v['a']} vs {v['b']}: {v['verdict']} — {'; '.join(v['why'])}"
                          for v in d["verdicts"]] + [status_line(d)]
        return [f"campaign {d['name']}: {d['n_jobs']} jobs ({d['n_run']} run, "
                f"{d['n_reused']} reused), {d['n_failed']} cases with a failed solver, "
                f"{d['n_crashed']} crashed jobs; {d['wall_s']:.1f} s"]

    def __str__(self):
        return "\n".join(self.lines + ([f"report: {self.report}"] if self.report else []))

    __repr__ = __str__

    def _repr_markdown_(self):
        return "```\n" + "\n".join(self.lines) + "\n```" + \
            (f"\n\nreport: `{self.report}`" if self.report else "")

    def save(self, path) -> Path:
        """The folder the command writes (report, plots, result/summary JSON), copied to
        `path`; the paths in `data` follow."""
        if self._folder.out_dir is None:
            raise BadInput(f"nothing to save: this {self.kind} wrote no files (give out=FOLDER)")
        dest, self.data = copy_folder(self._folder.out_dir, path, self.data)
        self._folder = _Folder(dest)
        return dest


# --- a scene -------------------------------------------------------------------------------

class SceneInfo:
    """`xval.show(scene)`: what `xval show` prints (`str`), its JSON (`as_json()`), and the
    `Scene` itself (`.scene`)."""

    def __init__(self, scene):
        self.scene = scene

    def as_json(self) -> dict:
        from ..output.citations import papers_in
        sc = self.scene
        return {"scene": sc.name, "title": sc.title, "kind": sc.kind,
                "sources": papers_in(sc.source) or [sc.source],
                "channels": list(sc.channels), "tolerances": sc.tolerances,
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
                + _markdown(["parameter", "default", "unit", "range", "meaning"], rows)
                + (f"\n\nchannels: {', '.join(sc.channels)}" if sc.channels else ""))
