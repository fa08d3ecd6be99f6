import importlib
import json
import os
import sys
import tempfile
import time
from pathlib import Path

import pytest

import compare  # noqa: F401  before numpy: one BLAS thread, as `xval` runs (compare/__init__.py)

LOGS = Path(__file__).resolve().parents[1] / "logs"
os.environ.setdefault("MPLCONFIGDIR", str(LOGS / ".mplconfig"))


def xval(*args, cwd=None):
    """The command line as a user runs it — `compare.cli.main`: its parser, its exit status, its
    stdout and stderr caught at the file descriptors, where the engines and the campaign's pool
    workers write too — in this process: (exit status, stdout, stderr). A `python -m compare`
    per call spent ~2.3 s importing and loading kernels this worker holds already (profiled
    default run: 231 + 44 of those 125 processes' 450 CPU-s). What needs its own process (Ctrl-C,
    kill, a plug-in's path, the entry point) starts one: test_faults, test_kill,
    test_campaign_scale, test_plugin, test_maps."""
    from compare import cli
    old_cwd, streams = os.getcwd(), (sys.stdout, sys.stderr)
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        for s in streams:
            s.flush()
        saved = os.dup(1), os.dup(2)
        os.dup2(out.fileno(), 1)
        os.dup2(err.fileno(), 2)
        sys.stdout, sys.stderr = (open(fd, "w", encoding="utf-8", closefd=False) for fd in (1, 2))
        try:
            if cwd is not None:
                os.chdir(cwd)
            try:
                rc = cli.main([str(a) for a in args])
            except SystemExit as e:          # argparse's usage errors
                rc = e.code if isinstance(e.code, int) else int(e.code is not None)
        finally:
            sys.stdout.flush()
            sys.stderr.flush()
            sys.stdout, sys.stderr = streams
            os.chdir(old_cwd)
            for fd, s in zip((1, 2), saved):
                os.dup2(s, fd)
                os.close(s)
        texts = []
        for f in (out, err):
            f.seek(0)
            texts.append(f.read().decode("utf-8", "replace"))
    return rc, *texts


def wait_for(cond, timeout=120.0, poll=0.1, what="timed out waiting"):
    """Poll `cond()` until it is true; fail the test with `what` after `timeout` seconds."""
    t0 = time.monotonic()
    while not cond():
        assert time.monotonic() - t0 < timeout, what
        time.sleep(poll)


# pytest-xdist (addopts `-n 2`): each module runs whole on one worker, so that its module-scoped
# fixtures (a campaign, an engine run) run once. No test writes into the source tree (test_layers
# seeds its probes in a scratch copy), so the docs build and a campaign's copy of the packages
# need no worker of their own.
@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config, log):
    from xdist.scheduler import LoadScopeScheduling

    class ByModule(LoadScopeScheduling):
        def _split_scope(self, nodeid):
            return nodeid.split("::", 1)[0]
    return ByModule(config, log)


# the longest modules first (seconds per module, default run on 2 busy cores: test_golden 68,
# test_plugin 60, test_helicopter_engines 56, test_sail 50, test_diff 38, test_campaign_scale
# 37, test_faults 33, test_cross_solvers 31; the rest ≤ 30): a worker takes the next module when
# it has two tests left, so a long module taken last kept one worker busy alone at the end
LONGEST = ("tests/verdicts/test_golden.py", "tests/front/test_plugin.py",
           "tests/engines/test_helicopter_engines.py", "tests/physics/test_sail.py",
           "tests/studies/test_diff.py", "tests/studies/test_campaign_scale.py",
           "tests/front/test_faults.py", "tests/verdicts/test_cross_solvers.py")


def pytest_collection_modifyitems(config, items):
    rank = {m: i for i, m in enumerate(LONGEST)}
    items.sort(key=lambda it: rank.get(it.nodeid.split("::", 1)[0], len(LONGEST)))


@pytest.fixture(scope="session")
def rotor_default_run(tmp_path_factory):
    """`xval run rotor-spinup --json` with every solver, once per xdist worker."""
    out = tmp_path_factory.mktemp("run")
    rc, so, se = xval("run", "rotor-spinup", "--json", "--out", str(out))
    assert rc == 0, se
    return json.loads(so), out


# The modules whose import compiles kernels typed ahead (explicit signatures), each after the
# ones it imports. On an empty numba cache both xdist workers collected every test module at once
# and compiled these side by side, each of them twice: ~48 CPU-s in both workers, the first 55 s
# of a cold run (numba's compile events, every process). Each worker imports them first, one at
# a time under a file lock, in its own order: the other worker loads what one compiled.
EAGER_KERNELS = {
    "gw0": ("custom_models.integrators.dense", "custom_models.rotor.batch",
            "custom_models.integrators.linear_acceleration", "custom_models.integrators.events",
            "custom_models.mstmm.elements", "custom_models.press.kinematics"),
    "gw1": ("custom_models.integrators.linear_acceleration", "custom_models.mstmm.elements",
            "custom_models.press.kinematics", "custom_models.integrators.dense",
            "custom_models.integrators.events", "custom_models.rotor.batch")}


def import_eager_kernels(worker):
    try:
        import fcntl
    except ImportError:                                  # not POSIX: imported as collected
        return
    locks = LOGS / ".compile-locks"
    locks.mkdir(parents=True, exist_ok=True)
    for name in EAGER_KERNELS.get(worker, ()):
        with open(locks / f"{name}.lock", "w") as f:
            fcntl.flock(f, fcntl.LOCK_EX)           # released when the file closes
            try:
                importlib.import_module(name)
            except Exception:                       # the collection reports it, per module
                return


def pytest_configure(config):
    # here, not in pyproject.toml: an ini filter naming numba's class imports numba, so numpy,
    # before this file sets one BLAS thread
    config.addinivalue_line("filterwarnings", "ignore::numba.NumbaPerformanceWarning")
    import_eager_kernels(os.environ.get("PYTEST_XDIST_WORKER"))


def pytest_addoption(parser):
    parser.addoption("--update-golden", action="store_true",
                     help="rewrite tests/golden/*.json from the current solvers (review the diff)")


def tension_torsion_exact_hz(speed, L, GJ, I_alpha, r_prop=1.0):
    """Exact first torsion frequency [Hz] of a uniform blade from the axis (r_H = 0) with the
    tension–torsion term: ((GJ + T k_A²)φ′)′ + I_α(ω² − r_prop Ω²)φ = 0, T = m̄Ω²(L² − x²)/2,
    I_α = m̄ k_A² (uniform density; r_prop = 1 the paper's eq. 30, (I_lag − I_flap)/I_α a rigid
    section's propeller term). Divided by I_α: ((a + Ω²(L² − x²)/2)φ′)′ + (ω² − rΩ²)φ = 0,
    a = GJ/I_α; x = √c·t, c = L² + 2a/Ω² gives Legendre's equation ((1 − t²)φ_t)_t +
    ν(ν+1)φ = 0 with ν(ν+1) = 2(ω² − rΩ²)/Ω². Clamped root: the odd solution t·₂F₁(A, B; 3/2;
    t²), A = (1 − ν)/2, B = (ν + 2)/2; free tip (p(L) = GJ > 0): its t-derivative
    F + 2z(AB/(3/2))·₂F₁(A+1, B+1; 5/2; z) vanishes at z = L²/c. The first root in ν."""
    import numpy as np
    from scipy.optimize import brentq
    from scipy.special import hyp2f1
    z = L**2 / (L**2 + 2 * GJ / I_alpha / speed**2)

    def g(nu):
        A, B = (1 - nu) / 2, (nu + 2) / 2
        return hyp2f1(A, B, 1.5, z) + 2 * z * (A * B / 1.5) * hyp2f1(A + 1, B + 1, 2.5, z)
    nus = np.linspace(0.5, 200.0, 40000)
    v = np.array([g(n) for n in nus])
    i = int(np.argmax(np.sign(v[:-1]) != np.sign(v[1:])))
    nu = brentq(g, nus[i], nus[i + 1], xtol=1e-14, rtol=1e-15)
    return float(np.sqrt(speed**2 * (r_prop + nu * (nu + 1) / 2)) / (2 * np.pi))


def one_to_one_count(paper, computed, tol):
    """The most table entries that can each have their own computed mode within relative tol,
    by Hopcroft–Karp (scipy's maximum_bipartite_matching) — an algorithm independent of the
    Hungarian assignment that compare.analysis.tables uses; both must give the same count."""
    import numpy as np
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import maximum_bipartite_matching
    rel = np.abs(np.asarray(computed)[None, :] / np.asarray(paper)[:, None] - 1)
    match = maximum_bipartite_matching(csr_matrix((rel <= tol).astype(int)), perm_type="column")
    return int(np.sum(match >= 0))


def table_counts(paper, computed):
    """(within 2 %, within 0.05 %) one to one, from compare.analysis.tables, checked against
    one_to_one_count and against the assignment itself (no computed mode used twice)."""
    from compare.analysis.tables import count_within, match_one_to_one
    out = []
    for tol in (0.02, 5e-4):
        used = [j for j, _ in match_one_to_one(paper, computed, tol) if j is not None]
        assert len(used) == len(set(used)), "a computed mode matched twice"
        n = count_within(paper, computed, tol)
        assert n == one_to_one_count(paper, computed, tol), tol
        out.append(n)
    return tuple(out)
