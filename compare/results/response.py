"""`ResponseResult`: an unbalance response (`xval response`) — amplitude and phase vs speed
from every solver, the verdicts speed by speed, the peaks. Its text table gives rad/s and rpm
side by side; `save(path)` writes report.md, response.json and the Bode and polar plots
(compare/output/response_plot.py)."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..analysis.verdict import Verdict
from .studies import StudyResult

RPM = 60 / (2 * math.pi)


def time_label(name: str) -> str:
    """A time solver's curve, told from the same solver's frequency-domain one."""
    return f"{name} (time)"


class ResponseResult(StudyResult):
    TYPE, JSON = "response", "response.json"

    @property
    def solvers(self) -> list[str]:
        """The curves' labels: frequency-domain solvers, then time-domain ones."""
        return list(self.data["frequency"]) + [time_label(n) for n in self.data["time"]]

    def curve(self, name) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(speeds [rad/s], complex amplitudes, error bars) of one solver (NaN where a time
        run failed)."""
        d = self.data
        if name in d["frequency"]:
            f = d["frequency"][name]
            return (np.array(d["speeds_rad_s"]), np.array(f["re"]) + 1j * np.array(f["im"]),
                    np.array(f["error"]))
        rows = d["time"][name.removesuffix(time_label(""))]
        ok = [r["status"] == "ok" for r in rows]
        a = np.array([complex(r["re"], r["im"]) if k else np.nan for r, k in zip(rows, ok)])
        return (np.array([r["speed_rad_s"] for r in rows]), a,
                np.array([r["error"] if k else np.nan for r, k in zip(rows, ok)]))

    def lag_deg(self, a) -> np.ndarray:
        from ..analysis.response import lag_deg
        return lag_deg(a, self.data["high_spot"])

    def worst(self, kind="frequency-time") -> dict | None:
        """The verdict of `kind` whose amplitude difference comes closest to its bar."""
        vs = [v for v in self.data["verdicts"] if v["kind"] == kind and "amplitude_diff" in v]
        return max(vs, key=lambda v: v["amplitude_diff"] / max(v["amplitude_bar"], 1e-300),
                   default=None)

    def problems(self, channels=None) -> list[str]:
        """What --strict refuses: a disagreement, a speed a solver gave no answer at."""
        return [f"{v['a']} vs {v['b']} at {v['speed_rad_s']:.6g} rad/s: {v['verdict']}"
                for v in self.data["verdicts"] if Verdict(v["verdict"]).refused]

    def table_lines(self) -> list[str]:
        names = self.solvers
        head = f"{'rad/s':>9s} {'rpm':>8s} " + " ".join(f"{n[:22]:>22s}" for n in names)
        out = [f"|a| = {self.data['amplitude']}; lag [deg] of the high spot behind the heavy "
               "spot", head]
        curves = {n: self.curve(n) for n in names}
        for i, w in enumerate(self.data["speeds_rad_s"]):
            cells = []
            for n in names:
                a = curves[n][1][i]
                cells.append(f"{abs(a):11.5e} {float(self.lag_deg(a)):9.4f}°" if np.isfinite(a)
                             else f"{'—':>22s}")
            out.append(f"{w:9.4f} {w * RPM:8.2f} " + " ".join(cells))
        return out

    def summary_lines(self):
        d = self.data
        out = self.table_lines()
        crit = d["critical_rad_s"]
        out.append(f"first critical (closed form) {crit:.6g} rad/s = {crit * RPM:.2f} rpm; "
                   f"synchronous ζ = {d['zeta_synchronous']:.4g}")
        for n, pk in d["peaks"].items():
            if pk is None:
                out.append(f"{n}: no peak with both half-power points among the speeds")
                continue
            modal = pk.get("zeta_modal_forward")
            out.append(f"{n}: peak {pk['peak_rad_s']:.6g} rad/s ({pk['peak_rad_s'] * RPM:.2f} "
                       f"rpm), |a| {pk['peak_amplitude']:.6g}; Q = {pk['Q']:.4g}, half-power "
                       f"ζ = {pk['zeta_half_power']:.4g}"
                       + (f", modal ζ (forward whirl there) = {modal:.4g}" if modal else "")
                       + (f" (located on the {pk['located']})" if pk.get("located") else ""))
        for kind in ("frequency", "frequency-time"):
            vs = [v for v in d["verdicts"] if v["kind"] == kind]
            if not vs:
                continue
            n_ok = Verdict.tally(v["verdict"] for v in vs)[Verdict.AGREE]
            amp = max(vs, key=lambda v: v.get("amplitude_rel", -1))
            ph = max(vs, key=lambda v: v.get("phase_diff_deg", -1))
            w = self.worst(kind)
            out.append(f"{kind}: {n_ok}/{len(vs)} agree; largest Δ|a|/|a| "
                       f"{amp['amplitude_rel']:.3g} (bar {amp['amplitude_bar_rel']:.3g}; "
                       f"{amp['a']} vs {amp['b']} at {amp['speed_rad_s']:.6g} rad/s), largest "
                       f"Δphase {ph['phase_diff_deg']:.3g}° (bar {ph['phase_bar_deg']:.3g}°; "
                       f"{ph['a']} vs {ph['b']} at {ph['speed_rad_s']:.6g} rad/s); closest to "
                       f"its bar: {w['a']} vs {w['b']} at {w['speed_rad_s']:.6g} rad/s, "
                       f"{w['amplitude_diff'] / max(w['amplitude_bar'], 1e-300):.2f} of it")
        n = len(d["speeds_rad_s"])
        cost = [f"{k} {f['wall_s'] / n * 1e3:.3g} ms" for k, f in d["frequency"].items()]
        cost += [f"{time_label(k)} {np.mean([r.get('wall_s', np.nan) for r in rows]):.3g} s"
                 for k, rows in d["time"].items()]
        out.append("cost per speed (with each error estimate): " + ", ".join(cost))
        for v in d["verdicts"]:
            if v["verdict"] == Verdict.INCOMPLETE:
                out.append(f"{v['a']} at {v['speed_rad_s']:.6g} rad/s: {v['why']}")
        return out

    def markdown(self) -> list[str]:
        d = self.data
        from ..output.report import header_lines
        from ..scenes import get_scene
        scene = get_scene(d["scene"])
        md = [f"# Unbalance response: {d['scene']}", "",
              *header_lines(scene, d.get("params"), inputs=scene.response.set),
              f"{d['amplitude']}; phase: lag of the high spot behind the heavy spot. Time "
              f"domain: {d['drive']}.", "", "```", *self.summary_lines(), "```", ""]
        rows = [v for v in d["verdicts"] if v["kind"] == "frequency-time"]
        if rows:
            md += ["## Frequency domain vs time domain", "",
                   "| rad/s | rpm | solvers | Δ|a| / |a| | bar | Δphase ° | bar ° | verdict |",
                   "|---|---|---|---|---|---|---|---|"]
            md += [f"| {v['speed_rad_s']:.5g} | {v['speed_rad_s'] * RPM:.1f} | {v['a']} vs "
                   f"{v['b']} | {v['amplitude_rel']:.2e} | {v['amplitude_bar_rel']:.2e} | "
                   f"{v['phase_diff_deg']:.2e} | {v['phase_bar_deg']:.2e} | {v['verdict']} |"
                   for v in rows]
        return md

    def save(self, path) -> Path:
        """report.md, response.json, bode.png and polar.png in the folder `path`."""
        from ..output.response_plot import write_response
        self._dir = write_response(Path(path), self)
        return self._dir
