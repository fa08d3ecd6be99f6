"""Why the engines and the paper's model of the helicopter disagree where they do (issue 23).

mstmm and fem write the whole aircraft in the rotor frame, as the paper does; the engines
spin the rotor on a fuselage that stays put (reference_models/helicopter_common.py). The two
can only differ through the rotor's speed: with the rotor at rest both are the same structure.
So each disagreeing pair is run again at rest, mode by mode: a mode that agrees at rest and
not at speed is moved by how the support turning under the rotor is written (the frame
assumption), by the measured amount; a mode that disagrees at rest too is a model difference
this does not explain, and the report says so.
"""
from __future__ import annotations

import numpy as np

from ..analysis.metrics import frequency_allowance

ENGINES = ("exudyn", "mujoco")


def explain(params, comparisons, modes_at, tolerances):
    """`modes_at(solver name, params)` runs one solver's modes; `tolerances` the scene's."""
    bad = [c for c in comparisons if c.verdict == "disagree"
           and (c.a in ENGINES) != (c.b in ENGINES)]
    if not bad or params["speed"] == 0:
        return [], []
    rest = {n: modes_at(n, {**params, "speed": 0.0})
            for n in sorted({c.a for c in bad} | {c.b for c in bad})}

    def at_rest(a, b):
        """Largest relative difference of the two at rest, mode by mode in frequency
        order (at rest the cyclic pairs are degenerate: names would be arbitrary)."""
        fa, fb = rest[a].frequencies_hz, rest[b].frequencies_hz
        k = min(len(fa), len(fb))
        return float(np.max(np.abs(fa[:k] / fb[:k] - 1))) if k else np.inf
    rows, md = [], ["## Why the engines and the paper's model differ", "",
                    f"At Ω = {params['speed']:g} rad/s, each pair that disagrees, against "
                    "the same pair with the rotor at rest (no frame question; at rest "
                    "compared mode by mode in frequency order):", ""]
    for c in bad:
        r = at_rest(c.a, c.b)
        tol = frequency_allowance(tolerances, c.a, c.b)
        frame = r <= tol
        if not frame:
            why = f"not the frame alone: the pair differs at rest too ({r:.2e})"
        else:
            why = f"the frame assumption: the rotor-frame support moves it by {c.max_rel:.2e}"
            if c.max_rel > 0.2:     # paired by name: say the shapes may not be alike
                why += " (paired by name; spinning, the shapes may couple differently)"
        rows.append({"a": c.a, "b": c.b, "mode": c.channel, "rel": c.max_rel,
                     "rel_at_rest": r, "frame": frame, "why": why})
        md.append(f"- {c.a}–{c.b} {c.channel}: {c.decided_by}; at rest ≤ {r:.2e} → {why}")
    return rows, md
