"""The import layers of ARCHITECTURE.md, checked on the source:

- leaves (custom_models/, reference_models/) import from `compare` only `compare.contract`
  and `compare.physics` — never the runner, CLI, recording, report, registry or scenes;
- `compare.contract` and `compare.physics` import nothing else from the project except the
  rotation math of custom_models (they are what leaves may share);
- nothing in compare/ outside compare/scenes/ names a scene.
"""
import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
LEAF_ALLOWED = ("compare.contract", "compare.physics")


def imports(path):
    """Absolute module names a file imports (relative imports resolved against its package)."""
    tree = ast.parse(path.read_text())
    pkg = ".".join(path.relative_to(ROOT).with_suffix("").parts[:-1])
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = pkg.split(".")[: len(pkg.split(".")) - node.level + 1]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module
            out += [mod] + [f"{mod}.{a.name}" for a in node.names]
    return out


def py_files(*dirs):
    return [p for d in dirs for p in sorted((ROOT / d).rglob("*.py"))]


@pytest.mark.parametrize("path", py_files("custom_models", "reference_models"),
                         ids=lambda p: str(p.relative_to(ROOT)))
def test_leaves_import_only_the_contract_and_shared_physics(path):
    bad = [m for m in imports(path) if m.split(".")[0] == "compare"
           and not m.startswith(LEAF_ALLOWED) and m != "compare"]
    assert not bad, f"{path.name} imports {bad}"


@pytest.mark.parametrize("path", [ROOT / "compare" / "contract.py"]
                         + py_files("compare/physics"), ids=lambda p: p.name)
def test_shared_layer_imports_no_orchestration(path):
    bad = [m for m in imports(path) if m.split(".")[0] in ("compare", "reference_models")
           and not m.startswith(LEAF_ALLOWED) and m != "compare"]
    bad += [m for m in imports(path) if m.startswith("custom_models")
            and not m.startswith("custom_models.rotation")]
    assert not bad, f"{path.name} imports {bad}"


def test_the_check_catches_a_leaf_importing_the_runner(tmp_path):
    leaf = ROOT / "custom_models" / "_layer_probe.py"
    leaf.write_text("from compare.runner import run_scene\n")
    try:
        with pytest.raises(AssertionError, match="compare.runner"):
            test_leaves_import_only_the_contract_and_shared_physics(leaf)
    finally:
        leaf.unlink()


def test_no_scene_names_in_compare_outside_scenes():
    from compare.scenes import SCENES
    names = "|".join(re.escape(n) for n in SCENES)
    hits = []
    for path in py_files("compare"):
        if "scenes" in path.relative_to(ROOT).parts:
            continue
        for i, line in enumerate(path.read_text().splitlines(), 1):
            if re.search(rf"['\"]({names})['\"]", line):
                hits.append(f"{path.relative_to(ROOT)}:{i}: {line.strip()}")
    assert not hits, "\n".join(hits)
