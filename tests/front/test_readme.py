"""The Python blocks of the README and of docs/python-api.md run as written: each page's blocks
in order, in one namespace (a notebook); a block whose first line is `# not run: <reason>` is
skipped; a `test_*` function a block defines is called with the plugin's `xval_run` fixture, as
pytest would. What the blocks claim is then checked against the objects they made."""
import inspect
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
README = ROOT / "README.md"
API_PAGE = ROOT / "docs" / "python-api.md"


def python_blocks(text):
    return re.findall(r"^```python\n(.*?)^```", text, flags=re.S | re.M)


def run_page(page, xval_run=None):
    """Run `page`'s Python blocks as notebook cells; the namespace they leave."""
    ns = {"__name__": page.stem}
    for i, block in enumerate(python_blocks(page.read_text())):
        if block.startswith("# not run:"):
            continue
        exec(compile(block, f"{page.name} python block {i + 1}", "exec"), ns)
    for name, f in list(ns.items()):
        if name.startswith("test_") and callable(f):
            f(**{p: xval_run for p in inspect.signature(f).parameters if p == "xval_run"})
    return ns


@pytest.fixture
def notebook(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)                     # files a block writes stay in tmp_path
    monkeypatch.setenv("MPLBACKEND", "Agg")
    return tmp_path


def test_the_pages_have_python_blocks():
    assert len(python_blocks(README.read_text())) >= 1
    assert len(python_blocks(API_PAGE.read_text())) >= 3


def passage_final_omega(r):
    """|ω| at 5 s of the paper's passage case, every solver, to six digits."""
    return {f"{v:.6g}" for v in r.final("omega_norm").values()}


def test_readme_python_blocks_run(notebook):
    ns = run_page(README)
    assert passage_final_omega(ns["r"]) == {"90.8409"}


def test_python_api_page_blocks_run(notebook, xval_run):
    ns = run_page(API_PAGE, xval_run)
    assert any(name.startswith("test_") for name in ns), "the page shows the plugin in a test"
    assert passage_final_omega(ns["r"]) == {"90.8409"}
    assert (notebook / "my-run" / "report.md").exists()
    assert ns["coarse"]["quaternion"].errors["omega_norm"].max() == pytest.approx(0.03, rel=0.2)
