import json
import os
import subprocess
import sys

import pytest

os.environ.setdefault("MPLCONFIGDIR", os.path.join(os.path.dirname(__file__), "..", "logs",
                                                   ".mplconfig"))


def xval(*args, cwd=None):
    """Run the installed command line as a user would: (exit status, stdout, stderr)."""
    p = subprocess.run([sys.executable, "-m", "compare", *args], capture_output=True,
                       text=True, cwd=cwd, timeout=900)
    return p.returncode, p.stdout, p.stderr


@pytest.fixture(scope="session")
def rotor_default_run(tmp_path_factory):
    """`xval run rotor-spinup --json` with every solver, once per test session."""
    out = tmp_path_factory.mktemp("run")
    rc, so, se = xval("run", "rotor-spinup", "--json", "--out", str(out))
    assert rc == 0, se
    return json.loads(so), out


def pytest_addoption(parser):
    parser.addoption("--update-golden", action="store_true",
                     help="rewrite tests/golden/*.json from the current solvers (review the diff)")
