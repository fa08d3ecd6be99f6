"""`IdentifyResult`: unknown parameters fitted to a record (`xval identify`) — each solver's
estimates with their 95 % intervals (or "undetermined"), the verdict on each parameter per
solver pair, residuals, correlations, the profile check. `save(path)` writes report.md,
identify.json, fit.png (each solver's fit over the data) and, where a Poincaré section was
asked for, poincare.png (compare/output/identify_plot.py)."""
from __future__ import annotations

from pathlib import Path

from ..analysis.verdict import Verdict, agree_text
from .studies import StudyResult


def _num(v, unit=""):
    return "—" if v is None else f"{v:.6g}{(' ' + unit) if unit else ''}"


class _TablesReport:
    """report.md of a result made of `title()`, `tables()` and `summary_lines()`."""

    def markdown(self) -> list[str]:
        from ..output.tables import markdown
        md = [f"# {self.title()}", ""]
        for h, r in self.tables():
            md += [markdown(h, r), ""]
        return md + ["```", *self.summary_lines(), "```"]


class IdentifyResult(_TablesReport, StudyResult):
    TYPE, JSON = "identify", "identify.json"

    def __init__(self, data: dict, out_dir=None, report_md=None, record=None, curves=None):
        super().__init__(data, out_dir, report_md)
        self.record = record          # the fitted record and each solver's model curves:
        self.curves = curves or {}    # in memory only (the figure draws them)
        data.setdefault("summary", self.summary())

    def estimate(self, solver: str, parameter: str) -> dict:
        return next(e for e in self.data["estimates"]
                    if e["solver"] == solver and e["parameter"] == parameter)

    def fit(self, solver: str) -> dict:
        return next(f for f in self.data["fits"] if f["solver"] == solver)

    def summary(self) -> str:
        d = self.data
        fits = d["fits"]
        bad = [f["solver"] for f in fits if not f["converged"]]
        und = sorted({e["parameter"] for e in d["estimates"]
                      if e["converged"] and not e["identifiable"]})
        text = (f"{', '.join(d['unknowns'])} from {d['samples']} samples of "
                f"{', '.join(d['channels'])} by {len(fits)} solver(s)")
        if bad:
            text += f"; no converged fit: {', '.join(bad)}"
        if und:
            text += f"; undetermined by the data: {', '.join(und)}"
        if d["comparisons"]:
            text += "; " + agree_text(c["verdict"] for c in d["comparisons"])
        return text

    def problems(self, channels=None) -> list[str]:
        """What --strict refuses: a fit that did not converge, a refused verdict."""
        out = [f"{f['solver']}: fit did not converge ({f['why']})"
               for f in self.data["fits"] if not f["converged"]]
        return out + [f"{c['parameter']} {c['a']} vs {c['b']}: {c['verdict']}"
                      for c in self.data["comparisons"] if Verdict(c["verdict"]).refused]

    def as_json(self) -> dict:
        return self.data

    def title(self):
        return f"Identification: {self.data['scene']} from {self.data['data']}"

    def tables(self):
        d = self.data
        units = dict(zip(d["unknowns"], d["units"]))
        head = ["solver", "parameter", "estimate", "95 % interval", "identifiable"]
        rows = [[e["solver"], e["parameter"], _num(e["value"], units[e["parameter"]]),
                 "—" if e["value"] is None else
                 f"[{e['ci_low']:.6g}, {e['ci_high']:.6g}]",
                 "yes" if e["identifiable"] else ("no" if e["converged"] else "no fit")]
                for e in d["estimates"]]
        out = [(head, rows)]
        if d["comparisons"]:
            out.append((["parameter", "solvers", "difference", "bound", "verdict"],
                        [[c["parameter"], f"{c['a']} vs {c['b']}", _num(c.get("difference")),
                          _num(c.get("bound")), str(c["verdict"])]
                         for c in d["comparisons"]]))
        return out

    def summary_lines(self):
        d = self.data
        out = []
        for f in d["fits"]:
            if not f["converged"]:
                out.append(f"{f['solver']}: did not converge — {f['why']}")
                continue
            red = f["chi2"] / max(f["dof"], 1)
            rms = ", ".join(f"{c} {v:.3g}" for c, v in f["residual_rms"].items())
            out.append(f"{f['solver']}: χ²/dof {red:.3f}; residual rms {rms}; {f['runs']} "
                       f"runs in {f['wall_s']:.3g} s")
            for p in f.get("profile") or []:
                if p["confirmed"] is None:
                    continue
                ends = ", ".join(_num(p[k]) for k in ("ratio_low", "ratio_high"))
                out.append(f"  profile {p['parameter']}: Δχ²/z² at the interval's ends "
                           f"{ends} → {'confirmed' if p['confirmed'] else 'NOT confirmed'}")
        out.append(d["summary"])
        if d.get("poincare"):
            out.append(f"Poincaré section at shaft angle {d['poincare']['phase']:g} rad: "
                       f"{d['poincare']['points']} points per solver")
        return out

    def save(self, path) -> Path:
        """report.md, identify.json, fit.png (and poincare.png) in the folder `path`."""
        from ..output.identify_plot import write_identify
        self._dir = write_identify(Path(path), self)
        return self._dir


class DetectionResult(_TablesReport, StudyResult):
    """`xval identify SCENE --detection`: the smallest defect told from none, per solver, speed
    and channel set, against the noise level; the solvers' limits judged pair by pair.
    `save(path)` writes report.md, detection.json and detection.png."""
    TYPE, JSON = "detection", "detection.json"

    def __init__(self, data: dict, out_dir=None, report_md=None):
        super().__init__(data, out_dir, report_md)
        data.setdefault("summary", self.summary())

    def summary(self) -> str:
        d = self.data
        return (f"smallest {d['size']} told from none (false alarm {d['alpha']:g}, miss "
                f"{d['beta']:g}, angle searched over {d['starts']} positions): "
                + agree_text(c["verdict"] for c in d["comparisons"]))

    def problems(self, channels=None) -> list[str]:
        return [f"{c['channel']} {c['a']} vs {c['b']}: {c['verdict']}"
                for c in self.data["comparisons"] if Verdict(c["verdict"]).refused]

    def as_json(self) -> dict:
        return self.data

    def title(self):
        return f"Detection limits: {self.data['scene']}"

    def tables(self):
        d = self.data
        head = ["solver", "channels", d["speed_param"], f"steady {d['key_channel']}",
                *[f"σ×{f:g}" for f in d["noise_factors"]]]
        rows = [[r["solver"], r["set"], f"{r['speed']:g}",
                 f"{r['steady_key']:.4g}" if r["status"] == "ok" else r["status"],
                 *([f"{v:.3g}" for v in r["limit"]] if r["status"] == "ok"
                   else ["—"] * len(d["noise_factors"]))] for r in d["rows"]]
        out = [(head, rows)]
        if d["comparisons"]:
            out.append((["channels @ speed", "solvers", "Δ/limit", "bound", "verdict"],
                        [[c["channel"], f"{c['a']} vs {c['b']}", _num(c["max_rel"]),
                          _num(c["tolerance"]), str(c["verdict"])]
                         for c in d["comparisons"]]))
        return out

    def summary_lines(self):
        d = self.data
        noise = ", ".join(f"{k} {v:g}" for k, v in d["noise"].items()
                          if any(k in s for s in d["channel_sets"].values()))
        return [f"limits of {d['size']} [SI] at σ × factor (σ: {noise})", d["summary"]]

    def save(self, path) -> Path:
        from ..output.identify_plot import write_detection
        self._dir = write_detection(Path(path), self)
        return self._dir
