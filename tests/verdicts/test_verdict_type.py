"""`Verdict` (compare/analysis/verdict.py): the rank the studies decide the worst verdict by,
what `--strict` and `assert_agree` refuse, the JSON strings unchanged, and `Result.problems()`
on synthetic results of several studies."""
import json
from types import SimpleNamespace

import numpy as np
import pytest

import xval
from compare.analysis.metrics import Comparison
from compare.analysis.verdict import Verdict, agree_text
from compare.results import CampaignResult, ExtremesResult, MapResult, TimeResult
from compare.results.base import comparisons_from_json
from compare.workflows.maps import compare_boundaries, verdict_status
from compare.workflows.modes import modes_status

A, D, I, S = Verdict.AGREE, Verdict.DISAGREE, Verdict.INCONCLUSIVE, Verdict.SKIPPED


def cmp(verdict, a="a", b="b", channel="x", dev=1.0, bound=2.0):
    return Comparison(a, b, channel, dev, dev, dev, 1.0, bound, verdict, "why", dev, None, bound)


def test_every_value_in_use_and_its_json_string():
    assert [str(v) for v in Verdict] == ["agree", "disagree", "inconclusive", "incomplete",
                                         "unconfirmed", "skipped", "no data"]
    assert json.dumps([Verdict.NO_DATA, A]) == '["no data", "agree"]'
    assert A == "agree" and f"{D}" == "disagree" and Verdict("inconclusive") is I


def test_rank_worst_first_as_the_studies_decide_it():
    assert Verdict.by_rank() == [D, Verdict.INCOMPLETE, Verdict.UNCONFIRMED, S, I,
                                 Verdict.NO_DATA, A]
    assert Verdict.worst(["agree", "inconclusive"]) is I
    assert Verdict.worst([A, S, I]) is S
    assert Verdict.worst([], default=Verdict.NO_DATA) is Verdict.NO_DATA


def test_a_map_pair_is_disagree_over_incomplete_over_unconfirmed_over_agree():
    def crossing(x, regimes="pq", **kw):
        return {"x": x, "y": None, "bracket": [x - 1e-3, x + 1e-3], "from": regimes[0],
                "to": regimes[1], "error": 0.0, **kw}
    # both find p→q at 1 (a's unconfirmed); b finds q→r at 3, where a's run failed
    seen = {"a": {None: [(0.0, "p", "ok", None), (2.9, "q", "error", "boom"),
                         (3.1, "q", "ok", None)]},
            "b": {None: [(0.0, "p", "ok", None), (3.1, "q", "ok", None)]}}
    a = [crossing(1.0, unconfirmed=True)]
    b = [crossing(1.0), crossing(3.0, "qr")]
    v = compare_boundaries({"a": a, "b": b}, 1e-3, seen)[0]
    assert v["verdict"] is Verdict.INCOMPLETE, v
    # and a finds r→s at 2, where b's own runs read no crossing: disagree outranks the rest
    missed = compare_boundaries({"a": a + [crossing(2.0, "rs")], "b": b}, 1e-3, seen)[0]
    assert missed["verdict"] is D, missed
    assert [u["outcome"] for u in missed["unmatched"]] == ["disagree", "incomplete"]
    only = compare_boundaries({"a": a, "b": [crossing(1.0)]}, 1e-3, seen)[0]
    assert only["verdict"] is Verdict.UNCONFIRMED, only
    st = verdict_status([{"verdict": "agree"}, {"verdict": "no data"},
                         {"verdict": "unconfirmed"}])
    assert st["status"] == "unconfirmed" and list(st)[2:] == ["disagree", "incomplete",
                                                             "unconfirmed", "no data", "agree"]
    assert verdict_status([])["status"] == "no comparison"


def test_a_modes_run_with_a_failed_solver_is_incomplete_even_where_a_pair_disagrees():
    obj = {"incomplete": [{"solver": "c", "status": "error", "reason": "boom"}],
           "unpaired_modes": []}
    assert modes_status([cmp(D), cmp(A)], obj)[0] == "incomplete"
    obj["incomplete"] = []
    assert modes_status([cmp(D), cmp(I), cmp(A)], obj)[0] == "disagree"
    assert modes_status([cmp(S), cmp(I)], obj)[0] == "disagree"   # anything past inconclusive
    assert modes_status([cmp(I), cmp(A)], obj)[0] == "inconclusive"
    assert modes_status([cmp(A)], obj) == ("agree", "1 of 1 comparisons agree")
    assert modes_status([], obj)[0] == "incomplete"


def test_strict_refuses_what_it_refused_and_assert_agree_everything_but_agree():
    assert {v for v in Verdict if v.refused} == {D, I, Verdict.INCOMPLETE,
                                                 Verdict.UNCONFIRMED}
    assert [v for v in Verdict if v.agrees] == [A]
    assert agree_text([A, I, D, A]) == "2 of 4 comparisons agree, 1 inconclusive"


def test_json_round_trip_keeps_the_strings_and_the_shown_form():
    cs = [cmp(A, dev=0.5), cmp(A, dev=1.5), cmp(I), cmp(D, dev=3.0),
          Comparison("a", "b", "y", np.nan, np.nan, np.nan, np.nan, 1.0, S, "not compared")]
    rows = [c.as_dict() for c in cs]
    assert [r["shown"] for r in rows] == ["agree", "agree (marginal)", "inconclusive",
                                          "disagree", "skipped"]
    text = json.dumps(rows)
    back = comparisons_from_json(json.loads(text))
    assert [type(c.verdict) for c in back] == [Verdict] * 5
    assert json.dumps([c.as_dict() for c in back]) == text
    assert '"verdict": "agree"' in text and "Verdict" not in text


def _run(solvers, comparisons):
    return TimeResult("rotor-spinup", {}, [SimpleNamespace(solver=s, status=st, reason=None)
                                           for s, st in solvers], comparisons, [])


def test_problems_of_a_run():
    ok = _run([("a", "ok"), ("b", "ok")], [cmp(A, channel="x"), cmp(I, channel="y")])
    assert ok.problems() == ["a vs b y: inconclusive"]
    assert ok.problems(channels=["x"]) == []
    xval.assert_agree(ok, "x")
    with pytest.raises(AssertionError, match="1 of 1 comparisons of rotor-spinup do not agree"):
        xval.assert_agree(ok, "y")
    failed = _run([("a", "ok"), ("b", "error")], [cmp(S)])
    assert failed.problems() == ["b error (incomplete)"]      # the run, not its skipped pair
    with pytest.raises(AssertionError, match="incomplete: b error"):
        xval.assert_agree(failed)
    assert _run([("a", "ok")], []).problems() == ["nothing was compared (incomplete)"]


def test_problems_of_a_map_a_campaign_and_extremes():
    pair = lambda v: {"a": "a", "b": "b", "verdict": v}
    m = MapResult({"verdicts": [pair(v) for v in ("agree", "no data", "unconfirmed",
                                                   "incomplete", "disagree")]})
    assert m.problems() == ["a vs b: unconfirmed", "a vs b: incomplete", "a vs b: disagree"]
    case = {"case": "c1", "runs": [{"solver": "a", "status": "ok"},
                                   {"solver": "b", "status": "diverged"}],
            "comparisons": [{"a": "a", "b": "b", "channel": "x", "verdict": "skipped"}]}
    crashed = {"case": "c2", "error": "crashed"}
    camp = CampaignResult({"cases": [case, crashed], "maps": [{"map": "m1", **m.data}]})
    assert camp.problems() == ["c1: b diverged (incomplete)", "c2: crashed",
                               "map m1: a vs b: unconfirmed", "map m1: a vs b: incomplete",
                               "map m1: a vs b: disagree"]
    rows = [{"case": "k", "solver": "s", "outcome": o} for o in
            ("FAILED", "FAILED (known)", "error", "stale: within tolerance", "ok")]
    assert ExtremesResult({"results": rows}).problems() == [
        "k s: FAILED", "k s: error", "k s: stale: within tolerance"]
