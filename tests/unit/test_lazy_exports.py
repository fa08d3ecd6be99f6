"""A leaf package's capabilities stay callable whatever is imported first: a capability's name
is never one of the package's submodules (importing such a submodule — a sibling's
`from .x import`, a test — binds the module over the name for good)."""
import importlib
import subprocess
import sys
import textwrap

import pytest

from compare.contract import lazy_exports


@pytest.mark.parametrize("engine", ["exudyn", "mujoco"])
def test_modes_stays_callable_after_the_response_module_loads(engine):
    # a fresh interpreter: the response module (which imports the linearisation) first
    code = textwrap.dedent(f"""
        import reference_models.{engine}.rotor as leaf
        import reference_models.{engine}.rotor.response
        assert callable(leaf.modes) and callable(leaf.whirl_sweep), type(leaf.modes)
    """)
    subprocess.run([sys.executable, "-c", code], check=True)


def test_a_capability_named_as_a_submodule_is_refused(tmp_path, monkeypatch):
    pkg = tmp_path / "lazyprobe"
    pkg.mkdir()
    (pkg / "modes.py").write_text("def modes():\n    return 1\n")
    (pkg / "__init__.py").write_text(
        "from compare.contract import lazy_exports\n"
        "__getattr__ = lazy_exports(__name__, {'modes': 'modes'})\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    with pytest.raises(ImportError, match="modes"):
        importlib.import_module("lazyprobe")


def test_lazy_names_load_on_first_use():
    mod = type(sys)("probe_pkg")
    mod.__path__ = []
    sys.modules["probe_pkg"] = mod
    try:
        get = lazy_exports("probe_pkg", {"dumps": "json"})
        with pytest.raises(AttributeError):
            get("loads")
    finally:
        del sys.modules["probe_pkg"]
