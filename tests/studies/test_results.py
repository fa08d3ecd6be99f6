"""The Result family read back: what `xval run` / `xval modes` wrote (another process, or the
command in this one) loads as the type it was, and its JSON is the one the command printed —
every field, so a field dropped or mis-read on the way back fails here."""
import json
from pathlib import Path

import numpy as np

import xval
from compare.atomic import clean_json
from compare.cli import main


def _same_json(a, b):
    return json.loads(json.dumps(clean_json(a))) == json.loads(json.dumps(clean_json(b)))


def test_a_run_folder_loads_as_the_command_printed_it(rotor_default_run):
    """`xval run rotor-spinup --json` (four solvers, another process): the folder it wrote
    loads as a TimeResult whose JSON is the printed one — finals, energy residuals,
    comparisons, findings, file paths."""
    obj, _ = rotor_default_run
    r = xval.load(Path(obj["report"]).parent)
    assert isinstance(r, xval.TimeResult) and obj["result"] == "time"
    assert _same_json(r.to_json(), obj)
    assert r.findings and [c.verdict for c in r.comparisons] == \
        [c["verdict"] for c in obj["comparisons"]]


def test_a_modes_folder_loads_as_the_command_printed_it_tagged_or_not(tmp_path, capsys):
    """`xval modes rotor-whirl` (critical speeds, Campbell lines): result.json loads as a
    ModesResult with the printed JSON; a result.json written before the "result" field (here:
    the field removed) still loads as one, by its content."""
    assert main(["modes", "rotor-whirl", "--solver", "closed-form", "--solver", "euler-vector",
                 "--set", "spin=41.3", "--json", "--out", str(tmp_path)]) == 0
    obj = json.loads(capsys.readouterr().out)
    folder = Path(obj["report"]).parent
    m = xval.load(folder)
    assert isinstance(m, xval.ModesResult) and _same_json(m.to_json(), obj)
    assert m.critical_speeds == obj["critical_speeds"] and len(obj["critical_speeds"]) == 2
    untagged = {k: v for k, v in obj.items() if k != "result"}
    (folder / "result.json").write_text(json.dumps(untagged))
    old = xval.load(folder / "result.json")
    assert isinstance(old, xval.ModesResult)
    np.testing.assert_array_equal(old["euler-vector"].frequencies_hz,
                                  obj["runs"][1]["frequencies_hz"])
