"""The README's Python blocks run as written, in order, in one namespace (a notebook): a block
whose first line is `# not run: <reason>` is skipped; a `test_*` function a block defines is
called with the plugin's `xval_run` fixture, as pytest would."""
import inspect
import re
from pathlib import Path

import pytest

README = Path(__file__).resolve().parents[1] / "README.md"


def python_blocks(text):
    return re.findall(r"^```python\n(.*?)^```", text, flags=re.S | re.M)


def test_the_readme_has_python_blocks():
    assert len(python_blocks(README.read_text())) >= 3


def test_readme_python_blocks_run(tmp_path, monkeypatch, xval_run):
    monkeypatch.chdir(tmp_path)                     # files a block writes stay in tmp_path
    monkeypatch.setenv("MPLBACKEND", "Agg")
    ns = {"__name__": "readme"}
    for i, block in enumerate(python_blocks(README.read_text())):
        if block.startswith("# not run:"):
            continue
        exec(compile(block, f"README.md python block {i + 1}", "exec"), ns)
    tests = [f for name, f in ns.items() if name.startswith("test_") and callable(f)]
    for f in tests:
        f(**{p: xval_run for p in inspect.signature(f).parameters if p == "xval_run"})
    assert tests, "the README shows the plugin in a test function"
    # what the blocks claim, checked against the objects they made
    assert {f"{v:.6g}" for v in ns["r"].final("omega_norm").values()} == {"90.8409"}
    assert (tmp_path / "my-run" / "report.md").exists()
    assert ns["coarse"]["quaternion"].errors["omega_norm"].max() == pytest.approx(0.03, rel=0.2)
