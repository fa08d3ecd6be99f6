"""`Verdict`: what a comparison of two solvers says, as one type for every study.

A `StrEnum`, so a verdict is its own JSON string ("agree", ...) and compares equal to it; each
member knows its rank (for the worst verdict of a set) and whether `--strict` refuses it.
`xval.assert_agree` refuses every verdict but `agree`.
"""
from __future__ import annotations

from collections import Counter
from enum import StrEnum

MARGINAL = 0.5     # an agreement using more than half its bound is reported as marginal


class Verdict(StrEnum):
    AGREE = "agree"
    DISAGREE = "disagree"
    # within the bound, but one solver's own error bar is too wide to tell (never agreement)
    INCONCLUSIVE = "inconclusive"
    # a map pair where a run failed or a solver ran no points: no answer to compare
    INCOMPLETE = "incomplete"
    # a map crossing that agrees but vanishes at its solver's tighter setting
    UNCONFIRMED = "unconfirmed"
    # a comparison not made because a solver did not finish (the failed run is the problem)
    SKIPPED = "skipped"
    # a map pair with nothing comparable (crossings only outside the other's region)
    NO_DATA = "no data"

    @property
    def rank(self) -> int:
        """Higher is worse: the worst of a set is the one `Verdict.worst` returns."""
        return _RANK[self]

    @property
    def refused(self) -> bool:
        """Whether `--strict` fails on it (`skipped`: the failed run is what it names)."""
        return self in _REFUSED

    @property
    def agrees(self) -> bool:
        """Whether `xval.assert_agree` accepts it: `agree` only."""
        return self is Verdict.AGREE

    def marginal(self, ratio: float) -> bool:
        """An agreement that uses more than MARGINAL of its bound."""
        return self is Verdict.AGREE and ratio > MARGINAL

    def shown(self, ratio: float) -> str:
        """As tables print it: `agree (marginal)` above MARGINAL of the bound (a presentation
        of `agree` and its ratio, not a verdict of its own)."""
        return "agree (marginal)" if self.marginal(ratio) else self

    @staticmethod
    def worst(verdicts, default=None):
        """The worst verdict of `verdicts` (strings accepted), `default` where there is none."""
        return max(map(Verdict, verdicts), key=_RANK.__getitem__, default=default)

    @staticmethod
    def by_rank() -> list[Verdict]:
        """Every verdict, worst first."""
        return sorted(Verdict, key=_RANK.__getitem__, reverse=True)

    @staticmethod
    def tally(verdicts) -> Counter:
        """How many of each verdict (strings accepted); a missing one counts 0."""
        return Counter(map(Verdict, verdicts))


# Worst first, as the studies decide today: a map pair is disagree over incomplete over
# unconfirmed over no data over agree (workflows/map_verdicts.py); a modes run counts any
# verdict but agree and inconclusive as disagree, above inconclusive (workflows/modes.py:
# modes_status).
_RANK = {v: r for r, v in enumerate(reversed((
    Verdict.DISAGREE, Verdict.INCOMPLETE, Verdict.UNCONFIRMED, Verdict.SKIPPED,
    Verdict.INCONCLUSIVE, Verdict.NO_DATA, Verdict.AGREE)))}
_REFUSED = frozenset({Verdict.DISAGREE, Verdict.INCOMPLETE, Verdict.UNCONFIRMED,
                      Verdict.INCONCLUSIVE})


def agree_text(verdicts) -> str:
    """"N of M comparisons agree", with the inconclusive ones counted apart (never as
    agreement), as every summary line writes it."""
    v = list(verdicts)
    n = Verdict.tally(v)
    return (f"{n[Verdict.AGREE]} of {len(v)} comparisons agree"
            + (f", {n[Verdict.INCONCLUSIVE]} inconclusive" if n[Verdict.INCONCLUSIVE] else ""))
