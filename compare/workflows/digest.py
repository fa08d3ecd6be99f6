"""What a stored result depends on: the digest of a job's inputs (scene, resolved parameters,
solver names, settings, package versions) and of the source code behind it (its models, what
of ours they import, the adapter, the scene) — `Plan.digest()`, the campaign store's key.
"""
import ast
import functools
import hashlib
import importlib.util
import json
import sys
from pathlib import Path

import numpy as np

from .. import solvers

STORE_VERSION = 2          # bump when the stored result format changes: everything reruns


def _canon(x):
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, np.generic):
        return x.item()
    return str(x)


PROJECT_PACKAGES = ("compare", "custom_models", "reference_models")


ROOT = Path(__file__).resolve().parents[2]          # the checkout: compare/ sits in it


def _source(module_name):
    """(file, is_package) of a project module, or (None, False)."""
    base = ROOT.joinpath(*module_name.split("."))
    if (base / "__init__.py").is_file():
        return base / "__init__.py", True
    if base.with_suffix(".py").is_file():
        return base.with_suffix(".py"), False
    if module_name.split(".")[0] not in PROJECT_PACKAGES:   # a plug-in package's module
        try:
            spec = importlib.util.find_spec(module_name)
        except (ImportError, ValueError):
            spec = None
        if spec is not None and spec.origin and spec.origin.endswith(".py"):
            return Path(spec.origin), spec.submodule_search_locations is not None
    return None, False


def _imports(module_name):
    """(source file, project modules it imports), read from the source (nothing imported)."""
    path, is_pkg = _source(module_name)
    if path is None:
        return None, ()
    return path, _imported(module_name, is_pkg, path.read_text())


@functools.lru_cache(maxsize=4096)
def _imported(module_name, is_pkg, text):
    """The project modules a module's source imports. Kept per source text: a campaign's jobs
    digest the same shared modules again and again (reading imports took 16 of the 17 CPU-s of
    code digests in a profiled test run), and an edited file is parsed anew."""
    tree = ast.parse(text)
    package = module_name if is_pkg else module_name.rpartition(".")[0]
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found += [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parts = package.split(".")
                parts = parts[:len(parts) - node.level + 1]
                base = ".".join(parts + ([base] if base else []))
            found.append(base)
            found += [f"{base}.{a.name}" for a in node.names]   # `from pkg import submodule`
    own = PROJECT_PACKAGES + (module_name.split(".")[0],)    # a plug-in follows its own too
    return tuple(m for m in found if m.split(".")[0] in own)


_CODE = {}


def code_digest(module_names):
    """sha256 over the source of the given modules and every project module they import,
    transitively: a fix in a model reruns its jobs, an edit of an unrelated model does not.
    Scene modules count only when named (the job's own scene), not through the registry the
    adapter imports, so adding a scene leaves other results valid."""
    key = tuple(sorted(module_names))
    if key not in _CODE:
        seen, todo, files = set(), list(key), {}
        while todo:
            name = todo.pop()
            if name in seen or (name.startswith("compare.scenes") and name not in key):
                continue
            seen.add(name)
            path, deps = _imports(name)
            if path is not None:
                files[name] = path.read_bytes()
                todo += deps
        h = hashlib.sha256()
        for name in sorted(files):
            h.update(name.encode() + b"\0" + files[name])
        _CODE[key] = h.hexdigest()
    return _CODE[key]


def _scene_module(scene):
    from ..scenes import ORIGIN
    if scene.name in ORIGIN:                   # a plug-in's scene: the module it came from
        return ORIGIN[scene.name][1]
    for name, mod in list(sys.modules.items()):
        if name.startswith("compare.scenes.") and any(v is scene for v in vars(mod).values()):
            return name
    return "compare.scenes"


def job_digest(scene, params, chosen, settings):
    """Digest of everything a result depends on: scene, resolved parameters, solver names,
    settings, package versions, and the source of the models, of everything of ours they
    import and of the adapter."""
    blob = json.dumps({"store": STORE_VERSION, "scene": scene.name, "params": params,
                       "solvers": [s.name for s in chosen], "settings": settings,
                       "versions": {s.name: solvers.versions(s) for s in chosen},
                       "code": job_code(scene, chosen)}, sort_keys=True, default=_canon)
    return hashlib.sha256(blob.encode()).hexdigest()


def job_code(scene, chosen):
    """Digest of the code behind a job (its models, the adapter, the scene); stored with the
    result so that `xval diff` can say the model code changed."""
    code = {"compare.solvers", "compare.analysis.trajectory", "compare.scenes.base",
            _scene_module(scene)}
    code |= {s.leaves[scene.name] for s in chosen}
    return code_digest(code)
