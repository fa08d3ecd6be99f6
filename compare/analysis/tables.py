"""A published table of frequencies set against computed ones, one to one.

Every table entry gets at most one computed mode and every computed mode at most one entry
(scipy's Hungarian assignment, `linear_sum_assignment`), within a family where the table
names one: a computed mode near two table entries counts for one of them. With a tolerance
the assignment first maximises how many entries get their own mode within it, then minimises
the summed relative difference; without, it only minimises the sum — which can trade an entry
matched to 1e-5 for two matched to 1 % (measured on Table 3: 3 entries within 0.05 % instead
of 4), so a count "within tol" is always taken from the assignment made for that tol.
"""
from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment

_APART = 1e6      # pairing across families: never chosen


def match_one_to_one(paper, computed, tol=None, paper_families=None,
                     computed_families=None) -> list:
    """For each paper entry (index j of its computed mode, relative difference computed/paper
    − 1), or (None, None) when it gets none. Families (optional, both or neither): an entry
    only pairs with a mode of its own family."""
    p = np.asarray(paper, float)
    c = np.asarray(computed, float)
    rel = np.abs(c[None, :] / p[:, None] - 1.0)
    cost = rel.copy()
    if tol is not None:     # lexicographic: the count within tol, then the (capped) sum
        cost = (rel > tol) + np.minimum(rel, 1.0) / (len(p) + 1)
    if paper_families is not None:
        cost = cost + _APART * (np.asarray(paper_families)[:, None]
                                != np.asarray(computed_families)[None, :])
    rows, cols = linear_sum_assignment(cost)
    out = [(None, None)] * len(p)
    for i, j in zip(rows, cols):
        if cost[i, j] < _APART:
            out[i] = (int(j), float(c[j] / p[i] - 1.0))
    return out


def count_within(paper, computed, tol, paper_families=None, computed_families=None) -> int:
    """The most table entries that can each have their own computed mode within relative
    `tol` (one to one)."""
    m = match_one_to_one(paper, computed, tol, paper_families, computed_families)
    return sum(1 for j, r in m if j is not None and abs(r) <= tol)
