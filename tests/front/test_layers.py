"""The import layers of ARCHITECTURE.md, checked on the source:

- leaves (custom_models/, reference_models/) import from `compare` only `compare.contract`
  and `compare.physics` — never the runner, CLI, recording, report, registry or scenes;
- `compare.contract` and `compare.physics` import nothing else from the project (they are what
  leaves may share; the rotation math lives there too);
- inside compare/, each room imports only from its own layer or the ones below it (LAYERS),
  and no module imports one that imports it back (no cycle, lazy imports in functions counted);
- nothing in compare/ or xval/ outside compare/scenes/ names a scene or tests a scene's (or a
  parameter's) kind: the scene answers (`TimeScene`/`ModesScene`: `command`, `either`, ...;
  `Param.is_numeric`, ...), and `Scene.is_time`/`is_modes` are for compare/scenes/ alone;
- a leaf's attributes are read only by compare/leafinfo.py and compare/solvers.py (`LeafInfo`);
- xval/ (the front door) is held by the same rules as compare/.
"""
import ast
import re
import shutil
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
LEAF_ALLOWED = ("compare.contract", "compare.physics")
# compare/'s rooms, lowest first (ARCHITECTURE.md): a module may import its own layer and below
LAYERS = (("shared", ("compare.contract", "compare.errors", "compare.atomic", "compare.physics")),
          ("values", ("compare.analysis",)),
          ("scenes and registry", ("compare.scenes", "compare.solvers", "compare.leafinfo")),
          ("output", ("compare.output",)),
          ("results", ("compare.results",)),
          ("orchestration", ("compare.workflows",)),
          ("front door", ("compare.commands", "compare.cli", "compare.api",
                          "compare.pytest_plugin", "compare.__main__", "xval")))


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
    bad += [m for m in imports(path) if m.startswith("custom_models")]
    assert not bad, f"{path.name} imports {bad}"


def scratch_root(tmp_path, monkeypatch, *copied):
    """A scratch checkout under tmp_path that the checks read as ROOT (the source tree is never
    written): the folders `copied` copied from the real one, compare/workflows/ made."""
    for d in copied:
        shutil.copytree(ROOT / d, tmp_path / d, ignore=shutil.ignore_patterns("__pycache__"))
    (tmp_path / "compare" / "workflows").mkdir(parents=True, exist_ok=True)
    monkeypatch.setitem(globals(), "ROOT", tmp_path)
    return tmp_path


def test_the_check_catches_a_leaf_importing_the_runner(tmp_path, monkeypatch):
    leaf = scratch_root(tmp_path, monkeypatch) / "custom_models" / "_layer_probe.py"
    leaf.parent.mkdir(parents=True)
    leaf.write_text("from compare.workflows.runner import run_scene\n")
    with pytest.raises(AssertionError, match="compare.workflows.runner"):
        test_leaves_import_only_the_contract_and_shared_physics(leaf)


def docstring_lines(path):
    """The line numbers of a file's docstrings (an example there may name a scene)."""
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) \
                and node.body and isinstance(node.body[0], ast.Expr) \
                and isinstance(node.body[0].value, ast.Constant) \
                and isinstance(node.body[0].value.value, str):
            out |= set(range(node.body[0].lineno, node.body[0].end_lineno + 1))
    return out


def test_no_scene_names_in_compare_outside_scenes():
    from compare.scenes import SCENES
    names = "|".join(re.escape(n) for n in SCENES)
    hits = []
    for path in py_files("compare", "xval"):
        if "scenes" in path.relative_to(ROOT).parts:
            continue
        docs = docstring_lines(path)
        for i, line in enumerate(path.read_text().splitlines(), 1):
            if i not in docs and re.search(rf"['\"]({names})['\"]", line):
                hits.append(f"{path.relative_to(ROOT)}:{i}: {line.strip()}")
    assert not hits, "\n".join(hits)


def module_name(path):
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def layer(mod):
    for i, (_, prefixes) in enumerate(LAYERS):
        if any(mod == p or mod.startswith(p + ".") for p in prefixes):
            return i
    return None


COMPARE = {module_name(p): p for p in py_files("compare", "xval")}


@pytest.mark.parametrize("mod", sorted(m for m in COMPARE if layer(m) is not None))
def test_each_room_imports_only_its_layer_and_below(mod):
    mine = layer(mod)
    bad = [m for m in imports(COMPARE[mod]) if (layer(m) or 0) > mine]
    assert not bad, f"{mod} ({LAYERS[mine][0]}) imports {bad} from a higher layer"


def test_every_compare_module_is_in_a_layer():
    assert [m for m in COMPARE if layer(m) is None and m != "compare"] == []


def test_xval_is_covered():
    assert "xval" in COMPARE and layer("xval") == len(LAYERS) - 1


# what a scene's kind and a parameter's kind can be (Scene.kind, Param.kind): outside
# compare/scenes/ code asks the scene what it needs (`sc.command`, `sc.has_output_grid`,
# `sc.either(time=…, modes=…)`, `p.is_numeric`, ...), never which kind it is
PARAM_KINDS = {"float", "int", "vector", "choice"}
SCENE_KIND_TESTS = {"is_time", "is_modes"}


def _literals(node):
    """The string constants of a comparison operand, or None where it is anything else."""
    items = node.elts if isinstance(node, (ast.Tuple, ast.List, ast.Set)) else [node]
    if all(isinstance(e, ast.Constant) and isinstance(e.value, str) for e in items):
        return {e.value for e in items}
    return None


def kind_checks(path):
    """`x.kind ==/!=/in ...` comparisons in a file that test a scene or parameter kind: against
    one of their kinds, or against anything not a string literal (a constant in disguise);
    and every use of `x.is_time` / `x.is_modes`."""
    from compare.scenes import SCENES
    kinds = {sc.kind for sc in SCENES.values()} | {"time", "modes"} | PARAM_KINDS
    hits = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Attribute) and node.attr in SCENE_KIND_TESTS:
            hits.append(f"{path.relative_to(ROOT)}:{node.lineno}: {ast.unparse(node)}")
        if not isinstance(node, ast.Compare):
            continue
        sides = [node.left, *node.comparators]
        if not any(isinstance(e, ast.Attribute) and e.attr == "kind" for e in sides):
            continue
        others = [e for e in sides if not (isinstance(e, ast.Attribute) and e.attr == "kind")]
        lits = [_literals(e) for e in others]
        if any(v is None or v & kinds for v in lits):
            hits.append(f"{path.relative_to(ROOT)}:{node.lineno}: {ast.unparse(node)}")
    return hits


@pytest.mark.parametrize("path", [p for p in py_files("compare", "xval")
                                  if "scenes" not in p.relative_to(ROOT).parts],
                         ids=lambda p: str(p.relative_to(ROOT)))
def test_no_kind_checks_outside_scenes(path):
    hits = kind_checks(path)
    assert not hits, "\n".join(hits)


# what a leaf module carries (compare/contract.py, ARCHITECTURE.md): read through LeafInfo
LEAF_ATTRS = {"DEFAULT_SETTINGS", "INTEGRATORS", "ADAPTIVE", "AUTO_DT", "MODES_SETTINGS",
              "ORDERS", "check_settings", "regimes", "simulate", "modes"}
LEAF_READERS = {"compare/leafinfo.py", "compare/solvers.py"}


def leaf_reads(path):
    """Reads of a leaf module's attributes: getattr/hasattr naming one, `x.DEFAULT_SETTINGS`
    and the like, and `solver.leaf(scene)` (the module itself)."""
    hits = []
    for node in ast.walk(ast.parse(path.read_text())):
        bad = (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
               and node.func.id in ("getattr", "hasattr") and len(node.args) > 1
               and isinstance(node.args[1], ast.Constant) and node.args[1].value in LEAF_ATTRS)
        bad |= (isinstance(node, ast.Attribute) and node.attr in LEAF_ATTRS
                and node.attr.isupper())
        bad |= (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
                and node.func.attr == "leaf")
        if bad:
            hits.append(f"{path.relative_to(ROOT)}:{node.lineno}: {ast.unparse(node)}")
    return hits


@pytest.mark.parametrize("path", [p for p in py_files("compare", "xval")
                                  if str(p.relative_to(ROOT)) not in LEAF_READERS],
                         ids=lambda p: str(p.relative_to(ROOT)))
def test_leaf_attributes_read_only_by_leafinfo_and_solvers(path):
    hits = leaf_reads(path)
    assert not hits, "\n".join(hits)


@pytest.mark.parametrize("code, check", [
    ("def f(sc):\n    return sc.kind == 'modes'\n", kind_checks),
    ("def f(p):\n    return p.kind not in ('float', 'int')\n", kind_checks),
    ("from compare.scenes.base import MODES\ndef f(sc):\n    return sc.kind != MODES\n",
     kind_checks),
    ("def f(sc):\n    return 1 if sc.is_time else 0\n", kind_checks),
    ("def f(sc):\n    if not sc.is_modes:\n        return 1\n", kind_checks),
    ("def f(leaf):\n    return getattr(leaf, 'ADAPTIVE', ())\n", leaf_reads),
    ("def f(leaf):\n    return leaf.DEFAULT_SETTINGS\n", leaf_reads),
    ("def f(s, sc):\n    return s.leaf(sc)\n", leaf_reads),
])
def test_the_rules_catch_a_seeded_violation(code, check, tmp_path, monkeypatch):
    probe = scratch_root(tmp_path, monkeypatch) / "compare" / "workflows" / "_layer_probe.py"
    probe.write_text(code)
    assert check(probe)


def test_a_campbell_event_kind_is_no_scene_kind(tmp_path, monkeypatch):
    probe = scratch_root(tmp_path, monkeypatch) / "compare" / "workflows" / "_layer_probe.py"
    probe.write_text("def f(e):\n    return e.kind != 'crossing'\n")
    assert kind_checks(probe) == []


def _graph():
    """Module → the project modules it imports (a package import counts as its __init__; a
    module's own parent packages are loaded before it, so `from . import x` is no edge back)."""
    return {mod: {m for m in imports(path) if m in COMPARE and m != mod
                  and not mod.startswith(m + ".")}
            for mod, path in COMPARE.items()}


def _cycle(graph):
    """One import cycle as a list of modules, or None (depth-first search)."""
    state, stack = {}, []

    def visit(m):
        state[m] = 1
        stack.append(m)
        for n in sorted(graph[m]):
            if state.get(n) == 1:
                return stack[stack.index(n):] + [n]
            if n not in state and (found := visit(n)):
                return found
        stack.pop()
        state[m] = 2
        return None

    for m in sorted(graph):
        if m not in state and (found := visit(m)):
            return found
    return None


def test_no_import_cycle_in_compare():
    assert _cycle(_graph()) is None, " → ".join(_cycle(_graph()))


def test_the_cycle_check_finds_one():
    assert _cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]


# file writes: the atomic helpers, plain writes, numpy/json/matplotlib/rerun savers, a
# Trajectory's or result's `.save`, folder copies, os.open for writing
WRITE_CALLS = {"write_text", "write_bytes", "write_json", "publish", "atomic_path", "savez",
               "savez_compressed", "save", "savefig", "dump", "copytree", "copyfile", "copy",
               "mkdir", "makedirs", "subplots"}
# Markdown a workflow would compose: a heading, a table row or rule, an image link
MARKDOWN = re.compile(r"^(#{1,6} |\|[ -]|!\[)")


def writes(path, delegating=False):
    """Calls in a file that write a file (`delegating`: a Result's `.save`, which hands its
    writing to compare/output/, allowed)."""
    hits = []
    for node in ast.walk(ast.parse(path.read_text())):
        if not isinstance(node, ast.Call):
            continue
        f = node.func
        name = f.attr if isinstance(f, ast.Attribute) else f.id if isinstance(f, ast.Name) else ""
        mode = (node.args[1] if len(node.args) > 1 else
                next((k.value for k in node.keywords if k.arg == "mode"), None))
        bad = name in WRITE_CALLS and not (name == "dump" and isinstance(f, ast.Attribute)
                                           and getattr(f.value, "id", "") == "pickle") \
            and not (delegating and name == "save") \
            and not (name == "copy" and len(node.args) < 2)      # an array's or a dict's copy
        bad |= (name in ("open", "fdopen") and isinstance(mode, ast.Constant)
                and isinstance(mode.value, str) and bool(set(mode.value) & set("wax+")))
        bad |= name == "open" and any(isinstance(a, ast.Attribute) and a.attr in ("O_WRONLY",
                                      "O_CREAT", "O_RDWR") for a in ast.walk(node)) \
            and not any(isinstance(a, ast.Attribute) and a.attr == "devnull"
                        for a in ast.walk(node))
        if bad:
            hits.append(f"{path.relative_to(ROOT)}:{node.lineno}: {ast.unparse(node)[:80]}")
    return hits


# the rooms that may hand a Result to its `.save` (the front door and the results)
DELEGATING = ("compare/commands", "compare/results", "compare/api.py", "compare/cli.py", "xval")


def test_workflows_write_no_files():
    found = [h for p in py_files("compare/workflows") for h in writes(p)]
    assert not found, "workflows/ writes files (move the writer into compare/output/):\n" \
        + "\n".join(found)


def test_only_output_writes_files():
    """compare/output/ (and the atomic helpers it writes with) is the one room that writes."""
    found = []
    for p in py_files("compare", "xval"):
        rel = p.relative_to(ROOT).as_posix()
        if rel.startswith("compare/output/") or rel == "compare/atomic.py":
            continue
        found += writes(p, delegating=rel.startswith(DELEGATING))
    assert not found, "files written outside compare/output/:\n" + "\n".join(found)


def markdown_lines(path):
    """String literals outside docstrings (f-strings by their first literal part) that start
    like Markdown."""
    docs, hits = docstring_lines(path), []
    for node in ast.walk(ast.parse(path.read_text())):
        text = (node.values[0].value if isinstance(node, ast.JoinedStr) and node.values
                and isinstance(node.values[0], ast.Constant) else
                node.value if isinstance(node, ast.Constant) else None)
        if isinstance(text, str) and node.lineno not in docs and MARKDOWN.match(text):
            hits.append(f"{path.relative_to(ROOT)}:{node.lineno}: {text[:60]!r}")
    return hits


def test_workflows_compose_no_markdown():
    found = [h for p in py_files("compare/workflows") for h in markdown_lines(p)]
    assert not found, "workflows/ composes Markdown (compose it in compare/output/):\n" \
        + "\n".join(found)


@pytest.mark.parametrize("code", [
    "def f(rows):\n    return ['## Results', ''] + [f'| {r} |' for r in rows]\n",
    "def f(n):\n    return f'# Map: {n}'\n",
    "def f():\n    return '|---|---|'\n",
    "def f():\n    return '![figure](map.png)'\n"])
def test_the_markdown_rule_catches_a_seeded_report(code, tmp_path, monkeypatch):
    root = scratch_root(tmp_path, monkeypatch, "compare/workflows")
    (root / "compare" / "workflows" / "_layer_probe.py").write_text(code)
    with pytest.raises(AssertionError, match="_layer_probe"):
        test_workflows_compose_no_markdown()


def test_the_markdown_rule_lets_docstrings_and_plain_text_be(tmp_path, monkeypatch):
    probe = scratch_root(tmp_path, monkeypatch) / "compare" / "workflows" / "_layer_probe.py"
    probe.write_text('def f(n):\n    """# not a report: a docstring"""\n'
                     '    return f"{n} points | 3 solvers", "#1 of 3"\n')
    assert markdown_lines(probe) == []


@pytest.mark.parametrize("code", [
    "def f(p):\n    p.mkdir(parents=True)\n",
    "import matplotlib.pyplot as plt\ndef f():\n    return plt.subplots()\n",
    "from compare.atomic import write_text\ndef f(p):\n    write_text(p / 'report.md', '')\n",
    "def f(p):\n    p.write_text('x')\n",
    "def f(p):\n    with open(p, 'w') as fh:\n        fh.write('x')\n",
    "import json\ndef f(p, o):\n    with open(p, mode='a') as fh:\n        json.dump(o, fh)\n",
    "import numpy as np\ndef f(p, x):\n    np.savez(p, x=x)\n",
    "def f(tr, p):\n    tr.save(p / 'run.npz')\n",
])
def test_the_writer_rule_catches_a_seeded_writer(code, tmp_path, monkeypatch):
    # a copy of compare/workflows/ with the probe added: the rule over the whole room fails on it
    root = scratch_root(tmp_path, monkeypatch, "compare/workflows")
    probe = root / "compare" / "workflows" / "_layer_probe.py"
    probe.write_text(code)
    assert writes(probe)
    with pytest.raises(AssertionError, match="_layer_probe"):
        test_workflows_write_no_files()


def test_the_writer_rule_lets_reads_be(tmp_path, monkeypatch):
    probe = scratch_root(tmp_path, monkeypatch) / "compare" / "workflows" / "_layer_probe.py"
    probe.write_text("import json\ndef f(p):\n    with open(p) as fh:\n        return json.load(fh)"
                     "\ndef g(p):\n    return open(p, 'rb').read()\n")
    assert writes(probe) == []


def test_the_output_rule_catches_a_writer_in_a_lower_room(tmp_path, monkeypatch):
    root = scratch_root(tmp_path, monkeypatch, "compare/analysis")
    (root / "compare" / "analysis" / "_layer_probe.py").write_text(
        "import numpy as np\ndef f(p, x):\n    np.save(p, x)\n")
    (root / "compare" / "results").mkdir()
    (root / "compare" / "results" / "_delegates.py").write_text(
        "def f(result, p):\n    return result.save(p)\n")
    with pytest.raises(AssertionError, match="analysis/_layer_probe.py") as e:
        test_only_output_writes_files()
    assert "_delegates" not in str(e.value)
