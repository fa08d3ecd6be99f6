"""The baseline file `xval diff --save-baseline` writes: one compressed .npz holding the JSON
manifest and the kept samples (built by compare/workflows/sides.py), written atomically."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..analysis.trajectory import _py
from ..atomic import atomic_path


def write_baseline(out: Path, manifest: dict, arrays: dict) -> Path:
    with atomic_path(out) as tmp:
        with open(tmp, "wb") as f:
            np.savez_compressed(f, manifest=np.array(json.dumps(manifest, default=_py)),
                                **arrays)
    return Path(out)


def copy_baseline(src: Path, out: Path) -> Path:
    with atomic_path(out) as tmp:
        tmp.write_bytes(Path(src).read_bytes())
    return Path(out)
