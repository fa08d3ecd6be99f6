"""The error estimate from coarser members (a leaf's `COARSER_DT`: sail-deploy's explicit
engines, whose step sits at its stability bound): the run is the finest member, so the estimate
costs the members' steps, 1/1.1 + 1/1.2 = 1.74 runs, where halving cost dt/2, 2·dt and dt/4:
6.5 runs; a member that does not complete (past the stability limit) hands the estimate back
to halving. That the bars still bound the error: tests/verdicts/test_coverage.py (sail-deploy,
Exudyn's unresolved thread mode) and `xval calibrate sail-deploy`."""
import numpy as np
import pytest

from compare import solvers
from compare.scenes import get_scene

SHORT = {"t_end": 0.05, "output_dt": 0.01}


def _counted(monkeypatch):
    """Every leaf run `simulate` makes, as the leaf itself reports it."""
    runs, inner = [], solvers._simulate

    def counting(*a, **k):
        tr = inner(*a, **k)
        runs.append(tr)
        return tr
    monkeypatch.setattr(solvers, "_simulate", counting)
    return runs


def _run(solver, settings=None):
    sc = get_scene("sail-deploy")
    s = solvers.get_solver(solver)
    params = sc.resolve(SHORT)
    st = solvers.settings_for(s, sc.name, extra=settings or {},
                              t_out=sc.output_grid(params))
    return solvers.simulate(sc, s, params, st, estimate_error=True)


@pytest.mark.parametrize("solver", ["exudyn", "mujoco"])
def test_the_coarser_members_cost_less_than_one_halving(monkeypatch, solver):
    runs = _counted(monkeypatch)
    tr = _run(solver)
    assert tr.status == "ok" and tr.errors, tr.stats
    assert "coarser" in tr.stats["error_estimate_by"]
    # the counts the leaf reports: the run, then its two members at 1.1 and 1.2 × the step
    assert len(runs) == 1 + tr.stats["error_estimate_runs"] == 3
    steps = [r.stats["steps"] for r in runs]
    assert sum(steps[1:]) == pytest.approx(steps[0] * (1 / 1.1 + 1 / 1.2), rel=0.01)
    assert sum(steps[1:]) < 2 * steps[0]          # halving's dt/2 run alone: 2 × the run
    for c in get_scene("sail-deploy").channels:
        assert np.all(np.isfinite(tr.errors[c])) and np.all(tr.errors[c] >= 0)


def test_a_member_past_the_stability_limit_hands_back_to_halving(monkeypatch):
    """Before the first release the thread's top mode is the tip's √(k/m_tip) ≈ 1.2e5 rad/s:
    Verlet is stable up to h = 2/ω ≈ 1.66e-5 s. At 1.5e-5 s the run holds; its member 1.2×
    (1.8e-5 s, ωh ≈ 2.2) grows by ~2× a step and diverges, so the estimate halves the step."""
    runs = _counted(monkeypatch)
    tr = _run("exudyn", {"dt": 1.5e-5})
    assert tr.status == "ok"
    assert runs[2].status != "ok", runs[2].reason            # the 1.2× member
    assert tr.stats["error_estimate_by"].startswith("dt 7.5e-06"), tr.stats
    assert tr.errors and "coarser" not in tr.stats["error_estimate_by"]


def test_the_bench_counts_what_an_error_bar_costs(monkeypatch):
    """`xval bench`'s cost of an error bar: every leaf run the verdicts' estimates made (counted
    here as the leaf returns them), their seconds, and per verdict."""
    from compare.workflows.bench import error_bar_cost
    from compare.workflows.plan import plan
    pl = plan("sail-deploy", SHORT, ["thread-spool", "thread-spool-conservative", "exudyn"])
    runs = _counted(monkeypatch)
    cost = error_bar_cost(pl, log=lambda _: None)
    assert cost["runs"] == len(runs)
    assert cost["by_solver"]["exudyn"]["runs"] == 3          # the run and its two members
    assert cost["seconds"] == pytest.approx(sum(r.wall_s for r in runs))
    assert cost["verdicts"] >= 3 * len(get_scene("sail-deploy").channels)   # 3 pairs, each channel
    assert cost["runs_per_verdict"] == pytest.approx(len(runs) / cost["verdicts"])
