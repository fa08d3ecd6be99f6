"""The studies' results: bench, extremes, map, campaign, power, diff. Each holds the dict its
command's `--json` prints (`s["n_failed"]`, `.data`) and prints the lines the command prints
(`str(s)`, the report's path last).

A study made without `out` is held in memory and writes its files with `save(path)` (a bench
or a map through the writer it was made with). Made with `out`, a bench, map or campaign
writes as it goes (a bench's trajectories, a map's and a campaign's stored points, which a
stopped run resumes from), and `save(path)` copies its folder."""
from __future__ import annotations

from pathlib import Path

from ..analysis.verdict import Verdict, agree_text
from .base import Result, verdict_problems
from .records import Side, case_type, modes_case, read_maps, readable, time_case


class StudyResult(Result):
    """A study's summary: `data` (the JSON), `lines()` (what the command prints), `report`
    (the report's path, once written), `out_dir`."""

    def __init__(self, data: dict, out_dir=None, report_md=None, writer=None):
        self.data = data
        data["result"] = self.TYPE
        self.report_md = report_md            # a report held in memory (Markdown lines)
        self._dir = Path(out_dir) if out_dir else None
        # writer(folder) -> data: writes a study held in memory (a bench's, a map's files)
        self._writer = writer

    out_dir = property(lambda self: self._dir)
    report = property(lambda self: Path(self.data["report"]) if self.data.get("report")
                      and self._dir is not None else None)

    def __getitem__(self, key):
        return self.data[key]

    def keys(self):
        return self.data.keys()

    def to_json(self) -> dict:
        return self.data

    @classmethod
    def from_json(cls, obj: dict, folder=None):
        return cls(obj, folder)

    def summary_lines(self) -> list[str]:
        return []

    def markdown(self) -> list[str] | None:
        """The report of a study held in memory (None: its JSON alone)."""
        return self.report_md

    def lines(self):
        if self._dir is None and self._writer is not None:
            return self.summary_lines() + ["report: not kept (held in memory); "
                                           "result.save(FOLDER) writes it"]
        return self.summary_lines() + ([f"report: {self.report}"] if self.report else [])

    def save(self, path) -> Path:
        """Write the command's files into the folder `path`: the study's folder copied (its
        paths in `data` follow), or, for a study held in memory, its report and JSON."""
        from ..output.folders import copy_folder, write_result_json
        from ..output.study import write_study
        if self._dir is not None:
            dest, self.data = copy_folder(self._dir, path, self.data)
            self._dir = dest
            return dest
        if self._writer is not None:
            from ..output.folders import make_out
            make_out(str(path))
            self.data = self._writer(Path(path))
            self._dir = Path(path)
            return self._dir
        md = self.markdown()
        if md is not None:
            from ..output.folders import make_out
            make_out(str(path))
            write_study(Path(path), md, self.data, self.JSON)
        else:
            write_result_json(path, self.JSON, self.data)
        self._dir = Path(path)
        return self._dir


class BenchResult(StudyResult):
    """`xval.bench(...)`: the work-precision rows, the summary per error level, the observed
    orders (or the throughput rows)."""
    TYPE, JSON = "bench", "bench.json"

    def summary_lines(self):
        return list(self.data["summary_lines"])


KNOWN = "FAILED (known)"            # an extreme case's declared failure: reported, not refused


def extremes_problems(rows) -> list[dict]:
    """The rows `--strict` refuses: FAILED (not a declared one), error, stale declarations."""
    return [r for r in rows if r["outcome"] != KNOWN
            and r["outcome"].startswith(("FAILED", "error", "stale"))]


def map_problems(data: dict) -> list[str]:
    """A map's refused verdicts: a pair whose boundaries disagree, that one solver could not
    answer, or whose crossing vanished at the tighter setting."""
    return [f"{v['a']} vs {v['b']}: {v['verdict']}" for v in data.get("verdicts", [])
            if Verdict(v["verdict"]).refused]


class ExtremesResult(StudyResult):
    """`xval.extremes(...)`: per case and solver the outcome, its number and why."""
    TYPE = "extremes"

    def summary_lines(self):
        return [f"{r['case']:32s} {r['solver']:26s} {r['outcome']:18s} {r['detail']}"
                for r in self.data["results"]]

    def markdown(self):
        from ..output.study import extremes_markdown
        return extremes_markdown(self.data)

    def problems(self, channels=None):
        return [f"{x['case']} {x['solver']}: {x['outcome']}"
                for x in extremes_problems(self.data["results"])]


class PowerResult(StudyResult):
    """`xval.power(...)`: per parameter and solver the smallest change a verdict sees."""
    TYPE = "power"

    def summary_lines(self):
        d = self.data
        return [f"{r['parameter']:20s} {r['solver']:26s} "
                + (f"ε* {r['epsilon']:.2g}  ({' vs '.join(r['pair'])}, {r['channel']}; "
                   f"{r['how']})"
                   if r["epsilon"] is not None else f"—  ({r['how']})")
                for r in d["power"]] + [d["summary"], f"{d['runs']} runs, {d['wall_s']:.1f} s"]


class MapResult(StudyResult):
    """`xval.map(...)`: every solver's crossings (`s["boundaries"]`), the pairwise verdicts
    (`s["verdicts"]`), the points."""
    TYPE, JSON = "map", "map.json"

    def summary_lines(self):
        from ..output.map_plot import status_line
        d, out = self.data, []
        for s, cs in d["boundaries"].items():
            for c in cs:
                row = "" if c["y"] is None else f" at {d['y']['name']} = {c['y']:.6g}"
                out.append(f"{s:14s} {c['from']} → {c['to']}{row}: {d['x']['name']} in "
                           f"[{c['bracket'][0]:.6g}, {c['bracket'][1]:.6g}]")
        return out + [f"{v['a']} vs {v['b']}: {v['verdict']} — {'; '.join(v['why'])}"
                      for v in d["verdicts"]] + [status_line(d)]

    def problems(self, channels=None):
        return map_problems(self.data)

    def side(self) -> Side:
        if self._dir is None:
            return Side(self.where(), "map", {}, {self.data.get("scene", "map"): {
                "scene": self.data.get("scene"), "boundaries": self.data["boundaries"]}})
        return Side(self._dir, "map", {}, read_maps(self._dir))


def calibration_problems(d: dict) -> list[str]:
    """A calibration's refusals: each comparison that disagrees, and each solver that stopped
    where the scene does not say it may."""
    return ([f"set {x['sample']} {x['a']} vs {x['b']} {x['channel']}: disagree "
             f"(Δ/bound {x['ratio']:.2g})" for x in d["disagree"]]
            + [f"set {x['sample']} {x['solver']} {x['status']}: {x['reason']} (not declared "
               f"outside its domain)" for x in d["skipped"] if not x.get("declared")])


def _calibration_line(d):
    """The false-alarm rate over the campaign's calibration jobs (none: no line)."""
    cal = d.get("calibration") or []
    if not cal:
        return []
    done = [c for c in cal if "error" not in c]
    cover = [c["coverage"] for c in done if c.get("coverage") is not None]
    return [f"calibration: {sum(len(c['disagree']) for c in done)} of "
            f"{sum(c['comparisons'] for c in done)} comparisons disagree over "
            f"{sum(c['samples'] for c in done)} parameter sets off the defaults "
            f"({len(done)} of {len(cal)} scenes"
            + (f"; error-bar coverage ≥ {min(cover):.2g}" if cover else "") + ")"]


class CampaignResult(StudyResult):
    """`xval.campaign(...)`: the campaign's summary — jobs run and reused, every case's
    result, the maps."""
    TYPE, JSON = "campaign", "summary.json"

    def summary_lines(self):
        d = self.data
        verdicts = [x["verdict"] for c in d.get("cases", []) for x in c.get("comparisons", [])]
        maps = [(m.get("status") or {}).get("status") for m in d.get("maps", [])]
        return [f"campaign {d['name']}: {d['n_jobs']} jobs ({d['n_run']} run, "
                f"{d['n_reused']} reused), {d['n_failed']} cases with a failed solver, "
                f"{d['n_crashed']} crashed jobs; {d['wall_s']:.1f} s",
                agree_text(verdicts) + (f"; maps: {maps.count(Verdict.AGREE)} of {len(maps)} "
                                        "agree" if maps else "")] + _calibration_line(d)

    def problems(self, channels=None):
        """Every case's error, failed solvers and refused verdicts, every map's, and every
        calibration's error or disagreement."""
        out = []
        for c in self.data.get("cases", []):
            if "error" in c:
                out.append(f"{c['case']}: {c['error']}")
            if c.get("runs") or "error" not in c:
                out += [f"{c['case']}: {p}" for p in verdict_problems(
                    [(r["solver"], r["status"]) for r in c.get("runs", [])],
                    [(x["a"], x["b"], x["channel"], x["verdict"])
                     for x in c.get("comparisons", [])])]
        for m in self.data.get("maps", []):
            out += [f"map {m.get('map')}: {p}" for p in map_problems(m)]
        for c in self.data.get("calibration", []):
            if "error" in c:
                out.append(f"calibration of {c['scene']}: {c['error']}")
            else:
                out += [f"calibration of {c['scene']}: {p}" for p in calibration_problems(c)]
        return out

    def side(self) -> Side:
        p = self._dir
        cases = {}
        with readable(p / "summary.json"):
            for obj in self.data["cases"]:
                name = obj["case"]
                cases[name] = (modes_case(name, obj) if case_type(obj, p / name) == "modes"
                               else time_case(name, obj, p / name))
        return Side(p, "campaign", cases, read_maps(p))


class DiffResult(StudyResult):
    """`xval.diff(old, new)`: which results moved (`s["any_change"]`, `s["lines"]`), per case ×
    solver × channel against both sides' error bars; `plots`: the data of the changed
    channels' plots, drawn by `save`."""
    TYPE, JSON = "diff", "diff.json"

    def __init__(self, data: dict, out_dir=None, plots: dict | None = None):
        super().__init__(data, out_dir)
        self.plots = plots or {}

    def summary_lines(self):
        d, s = self.data, self.data["summary"]
        return ([f"{s['changed']} changed, {s['unchanged']} unchanged, {s['new']} new, "
                 f"{s['gone']} gone (runs); {s['channels_changed']} channels changed"]
                + list(d["lines"]) + [f"note: {n}" for n in d["notes"][:20]])

    def save(self, path) -> Path:
        """report.md, diff.json and the plots of the channels that moved most."""
        from ..output.diff_report import write_diff_report
        from ..output.folders import make_out
        if self._dir is not None:
            return super().save(path)
        make_out(str(path))
        self._dir = Path(path)
        self.data = write_diff_report(self._dir, self.data, self.plots)
        return self._dir
