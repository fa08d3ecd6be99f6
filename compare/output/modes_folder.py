"""The folder of `xval modes` (and of a campaign's frequency case, `ModesResult.save`):
report.md, result.json, the Campbell diagram (campbell.png, campbell.rrd) where the scene
sweeps, the mode shapes (mode_shapes.png, mode_shapes.rrd) where it draws them, else the
frequency table drawn (frequencies.png, frequencies.rrd: every case has a figure and a
recording)."""
from __future__ import annotations

from pathlib import Path

from . import campbell_plot, frequency_plot, mode_shapes, modes_report
from .study import write_study


def write_modes_folder(out_dir: Path, result) -> dict:
    """Every file of a modes result made in memory (its report's sections composed by
    modes_report.sections from the result's data; `result.drawing`: the Campbell diagram's
    (values, the lines in the figure's frame, critical speeds, events, that frame, the lines in
    the solvers' frame, where each line's root grows)). `result.out_dir` and `result.files`
    name them; returns the JSON written."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    sc, part, files = result.scene, modes_report.sections(result), {}
    md = [*part["head"]]
    repeated = mode_shapes.repeated_frequencies(list(result.runs.values()))
    if repeated:
        md += ["", "Repeated frequencies:", "", *repeated]
    if sc.mode_shape_3d:
        drawn = mode_shapes.write(out_dir, sc, result.params, list(result.runs.values()))
        if drawn:
            files["mode_shapes_recording"] = drawn["recording"]
            files["mode_shapes_figure"] = drawn["figure"]
            md += ["", "## Mode shapes", "", drawn["text"], "", "![mode shapes](mode_shapes.png)"]
    md += part["explain"]
    if result.drawing is not None and result.drawing[5]:
        values, shown, entries, events, frame, lines, growing = result.drawing
        campbell_plot.png(out_dir / "campbell.png", sc, values, shown, entries, result.params,
                          events, frame, growing)
        files["recording"] = campbell_plot.rrd(out_dir / "campbell.rrd", sc, values, lines)
    if not files:        # neither Campbell diagram nor mode shapes: the frequency table drawn
        runs = list(result.runs.values())
        png = frequency_plot.write_figure(out_dir / "frequencies.png", sc, result.params, runs,
                                          result.comparisons)
        if png:
            files["frequencies_figure"] = out_dir / png
            files["recording"] = frequency_plot.write_recording(
                out_dir / "frequencies.rrd", runs, f"frequencies-{out_dir.name}")
            md += ["", "## Frequencies", "", "Each solver's frequencies with its own error "
                   "bar, and |Δf| of every compared pair against the bound its verdict used; "
                   "`frequencies.rrd` holds them per solver on the `mode` timeline.", "",
                   f"![frequencies]({png})"]
    md += part["campbell"] + part["threshold"] + part["identify"]
    md[1:1] = ["", f"**{result.summary}**"]
    files["report"] = out_dir / "report.md"
    result.out_dir, result.files = out_dir, files
    return write_study(out_dir, md, result.to_json())
