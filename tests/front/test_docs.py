"""The documentation (docs/, mkdocs.yml): the site builds with `mkdocs build --strict` — every
page in the nav, every link, anchor and snippet resolves, the API reference is read from
`xval`'s docstrings, the tutorial page is made from its notebook and each command's options from
the CLI — and the tutorial notebook runs as a plain script in an empty folder, as a reader
would run it (its own asserts check the solvers against the closed forms)."""
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
TUTORIAL = ROOT / "docs" / "tutorials" / "own_system.py"
BUILDERS = ("mkdocs", "material", "mkdocstrings", "mkdocstrings_handlers.python", "jupytext")


def _env():
    # this checkout's xval first (a worktree beside an editable install elsewhere)
    path = os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))
    return {**os.environ, "PYTHONPATH": path, "NO_MKDOCS_2_WARNING": "1", "MPLBACKEND": "Agg"}


def test_the_docs_build_strictly(tmp_path):
    for module in BUILDERS:
        pytest.importorskip(module, reason="the docs need the test extra: "
                                           "pip install -e '.[test]'")
    site = tmp_path / "site"
    r = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-d", str(site)],
                       cwd=ROOT, env=_env(), capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-4000:]
    # the pages made while building: the tutorial from its notebook, options from the CLI
    tutorial = (site / "tutorials" / "own_system" / "index.html").read_text()
    assert "ten minutes" in tutorial and "assert_agree" in tutorial
    assert "usage: xval run" in (site / "commands" / "run" / "index.html").read_text()
    assert 'id="xval.run"' in (site / "reference" / "index.html").read_text()


def test_the_tutorial_runs_as_a_script(tmp_path):
    r = subprocess.run([sys.executable, str(TUTORIAL)], cwd=tmp_path, env=_env(),
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-4000:]
    assert "closed form" in r.stdout                  # it reached its closed-form checks
