"""`xval.calibrate(...)`: what the calibration study found over its sampled sets — the
comparisons and those that disagree, the error bars' coverage and sharpness, the widest window,
the solvers skipped (compare/workflows/calibrate.py). Held in memory; `save` writes its JSON."""
from __future__ import annotations

from .studies import StudyResult


def _g(x, fmt=".3g"):
    return "—" if x is None else format(x, fmt)


class CalibrationResult(StudyResult):
    TYPE, JSON = "calibration", "calibration.json"

    def title(self):
        return f"calibration of {self.data['scene']}"

    def tables(self):
        d = self.data
        at = d.get("widest_at") or {}
        rows = [[d["scene"], str(d["samples"]), str(d["comparisons"]), str(len(d["disagree"])),
                 _g(d["coverage"]), _g(d["sharpness"]),
                 _g(d["widest_window"]) + (f" ({' vs '.join(at['pair'])} {at['channel']}, "
                                           f"set {at['set']})" if at else ""),
                 str(len(d["skipped"]))]]
        head = ["scene", "samples", "comparisons", "disagree", "coverage", "sharpness",
                "widest window", "skipped"]
        per = [[s, str(o["pairs"]), _g(o["coverage"]), _g(o["sharpness"]),
                "; ".join(f"{n}× {why}" for why, n in o["left_out"].items()) or "—"]
               for s, o in d.get("by_solver", {}).items()]
        return [(head, rows), (["solver", "pairs", "coverage", "sharpness", "left out"], per)]

    def summary_lines(self):
        d = self.data
        out = [f"disagree: set {x['set']} {' vs '.join(x['pair'])} {x['channel']} "
               f"Δ/bound {x['ratio']:.2g} at {x['params']}" for x in d["disagree"]]
        out += [f"skipped: set {x['set']} {x['solver']} {x['status']} ({x['reason']})"
                + (f" — outside its domain: {x['declared']}" if x.get("declared") else "")
                for x in d["skipped"]]
        return out + [f"{d['wall_s']:.1f} s"]

    def problems(self, channels=None):
        """Each comparison that disagrees, and each solver that stopped where the scene
        does not say it may."""
        d = self.data
        return ([f"set {x['set']} {' vs '.join(x['pair'])} {x['channel']}: disagree "
                 f"(Δ/bound {x['ratio']:.2g})" for x in d["disagree"]]
                + [f"set {x['set']} {x['solver']} {x['status']}: {x['reason']} (not declared "
                   f"outside its domain)" for x in d["skipped"] if not x.get("declared")])
