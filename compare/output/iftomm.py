"""Results files for the IFToMM Library of Computational Benchmark Problems (`xval run --out`
on a scene that is one of its problems, `Scene.benchmark`): one text file per solver,
DIR/iftomm/<solver>.txt — a header of `#` lines (the problem, the software, the solver's
method and settings, the CPU time and the accuracy the library's summary table asks for), then
whitespace-separated columns t and the problem's monitored quantities."""
from __future__ import annotations

import importlib.metadata
from pathlib import Path

import numpy as np

from ..analysis.metrics import energy_residual
from ..atomic import atomic_path

FOLDER = "iftomm"
LIBRARY = "IFToMM Library of Computational Benchmark Problems (iftomm-multibody.org/benchmark)"


def _version() -> str:
    try:
        return importlib.metadata.version("xval")
    except importlib.metadata.PackageNotFoundError:     # a clone used without pip install
        return "unknown"


def _num(x) -> str:
    if isinstance(x, (bool, np.bool_)) or not isinstance(x, (int, float, np.number)):
        return str(x)
    return format(float(x), ".6g") if isinstance(x, (float, np.floating)) else str(x)


def output_rows(t, output_dt) -> np.ndarray:
    """The grid rows on the problem's output step (every row where `output_dt` is None or does
    not fall on the grid)."""
    t = np.asarray(t, float)
    if output_dt is None or not len(t):
        return np.arange(len(t))
    k = (t - t[0]) / output_dt
    rows = np.nonzero(np.abs(k - np.round(k)) <= 1e-6)[0]
    return rows if len(rows) > 1 else np.arange(len(t))


def accuracy(scene, params, tr) -> tuple[float | None, str]:
    """The problem's error of one run against its reference (None where not known) and the
    header's words for it."""
    bm, unit = scene.benchmark, scene.unit(scene.benchmark.columns[0])
    if tr.status != "ok":
        return None, f"not known (the run ended {tr.status})"
    dev = bm.deviation(params, tr.t, tr.channels)
    if dev is None:
        return None, "not known at these parameters (the reference holds none here)"
    return dev["error"], (
        f"{dev['error']:.6e} {unit} (largest |{', '.join(bm.columns)} − reference| over "
        f"{dev['points']} reference values; at {dev['channel']}, t = {dev['t']:g} s)")


def results_text(scene, params, tr) -> str:
    """One solver's results file."""
    bm = scene.benchmark
    _, acc = accuracy(scene, params, tr)
    settings = ", ".join(f"{k}={_num(v)}" for k, v in tr.settings.items() if v is not None)
    versions = ", ".join(f"{k} {v}" for k, v in tr.versions.items())
    units = [f"{c} [{scene.unit(c)}]" if scene.unit(c) else c for c in bm.columns]
    drift = energy_residual(tr, scene.energy_channel) if scene.energy_channel else None
    head = [
        f"{LIBRARY}, problem {bm.problem}: {scene.title}",
        f"software: xval {_version()}, solver {tr.solver}" + (f" ({versions})" if versions
                                                              else ""),
        f"method: integrator {tr.settings.get('integrator', '—')}; settings: {settings}",
        "parameters: " + ", ".join(f"{p.name}={_num(params[p.name])} {p.unit}".rstrip()
                                    for p in scene.params),
        f"status: {tr.status}" + (f" ({tr.reason})" if tr.reason else ""),
        f"CPU time: {tr.wall_s:.6g} s (the run's wall time in one process"
        + (f", compilation {tr.stats['compile_s']:.3g} s apart" if tr.stats.get("compile_s")
           else "") + ")",
        f"accuracy: {acc}",
        *([f"energy drift: {drift:.6e} J (largest |E − E(0)|, channel {scene.energy_channel})"]
          if drift is not None else []),
        f"reference: {bm.reference_name} (its own error ~{bm.uncertainty:g})",
        "columns: t [s] " + " ".join(units)]
    rows = output_rows(tr.t, bm.output_dt)
    data = np.column_stack([tr.t[rows]] + [np.asarray(tr.channels[c], float)[rows]
                                           for c in bm.columns])
    body = "\n".join(" ".join(format(x, " .16e") for x in row) for row in data)
    return "".join(f"# {h}\n" for h in head) + body + "\n"


def write_results(out_dir, scene, params, trajectories) -> dict:
    """DIR/iftomm/<solver>.txt for every run; solver -> path."""
    folder = Path(out_dir) / FOLDER
    folder.mkdir(parents=True, exist_ok=True)
    files = {}
    for tr in trajectories:
        path = folder / f"{tr.solver}.txt"
        with atomic_path(path) as tmp:
            Path(tmp).write_text(results_text(scene, params, tr), encoding="utf-8")
        files[tr.solver] = path
    return files


def read_results(path) -> tuple[list[str], list[str], np.ndarray]:
    """A results file read back: (header lines, column names, data (rows, columns))."""
    lines = Path(path).read_text(encoding="utf-8").splitlines()
    head = [x[2:] for x in lines if x.startswith("#")]
    cols = next(h for h in head if h.startswith("columns:"))[len("columns:"):].split()
    names = [c for c in cols if not c.startswith("[")]
    data = np.loadtxt(path, comments="#", ndmin=2)
    return head, names, data
