"""`xval.calibrate(...)`: what the calibration study found over its sampled sets — the
comparisons and those that disagree, the error bars' coverage and sharpness, the widest window,
the solvers skipped (compare/workflows/calibrate.py). Held in memory; `save` writes its JSON."""
from __future__ import annotations

from ..output.tables import calibration_tables
from .studies import StudyResult, calibration_problems


class CalibrationResult(StudyResult):
    TYPE, JSON = "calibration", "calibration.json"

    def title(self):
        return f"calibration of {self.data['scene']}"

    def tables(self):
        return calibration_tables(self.data)

    def summary_lines(self):
        d = self.data
        out = [f"disagree: set {x['sample']} {x['a']} vs {x['b']} {x['channel']} "
               f"Δ/bound {x['ratio']:.2g} at {x['params']}" for x in d["disagree"]]
        out += [f"explained: set {x['sample']} {x['a']} vs {x['b']} {x['channel']} "
                f"Δ/bound {x['ratio']:.2g}: {x['why']}" for x in d.get("explained", [])]
        out += [f"skipped: set {x['sample']} {x['solver']} {x['status']} ({x['reason']})"
                + (f" — outside its domain: {x['declared']}" if x.get("declared") else "")
                for x in d["skipped"]]
        sweep = d.get("campbell")
        if sweep:
            out.append(f"Campbell sweeps: {sweep['comparisons']} comparisons over "
                       f"{sweep['sets']} sets ("
                       + ", ".join(f"{n} {v}" for v, n in sweep["verdicts"].items())
                       + f"), {sweep['unconfirmed']} critical speeds unconfirmed")
        return out + [f"{d['wall_s']:.1f} s"]

    def markdown(self):
        """The report `save` writes beside the JSON: the tables and the findings."""
        from ..output.tables import markdown
        blocks = [f"# {self.title()}", ""]
        for header, rows in self.tables():
            blocks += [markdown(header, rows), ""]
        return blocks + [f"- {line}" for line in self.summary_lines()]

    def problems(self, channels=None):
        return calibration_problems(self.data)
