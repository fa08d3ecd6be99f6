"""The local worker pool kept warm between the studies of one process
(compare/workflows/executors.py): the next study takes the same workers, never a dead or a
stale one, and a study that failed leaves none behind."""
import os
import signal
import sys
import time

import pytest

from compare.workflows import executors
from compare.workflows.executors import execute_many, worker_pool


def _worker_pids(n=3):
    """The pids of the worker(s) that answered n calls of a one-worker study."""
    with worker_pool("local", None, 1) as ex:
        outs = list(execute_many({i: (os.getpid, ()) for i in range(n)}, ex))
    assert all(o.error is None for o in outs), [o.error for o in outs]
    return {o.value for o in outs}


def test_next_study_takes_the_warm_worker_a_dead_one_is_replaced(tmp_path, monkeypatch):
    first = _worker_pids()
    assert len(first) == 1 and os.getpid() not in first
    assert _worker_pids() == first                # the same process: nothing spawned again
    (pid,) = first
    parked = executors._warm[executors._pool_key(1)]
    os.kill(pid, signal.SIGKILL)                  # dies while it waits for work
    t0 = time.monotonic()
    while parked._processes[pid].is_alive() and time.monotonic() - t0 < 10:
        time.sleep(0.05)
    fresh = _worker_pids()                        # every call answered, by a new worker
    assert fresh and fresh != first
    monkeypatch.chdir(tmp_path)                   # what a spawned worker starts from changed
    assert _worker_pids().isdisjoint(fresh)


def test_a_study_that_raised_keeps_no_pool():
    with pytest.raises(RuntimeError, match="the caller failed"):
        with worker_pool("local", None, 1) as ex:
            list(execute_many({0: (os.getpid, ())}, ex))
            raise RuntimeError("the caller failed")
    assert executors._pool_key(1) not in executors._warm


def _worker_view():
    """What a worker starts its first call with (module-level: a worker imports it by name):
    the job runners imported, numba already compiled for (its target context set up)."""
    preload = sys.modules.get("compare.workflows.pool_preload")
    ready = preload is not None and bool(preload.numba_ready.signatures)
    return ("compare.workflows.campaign" in sys.modules and ready,
            os.environ.get("XVAL_TEST_MARK"), os.getcwd(), os.getppid())


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="forkserver: Linux only")
def test_a_forked_worker_starts_with_the_modules_and_this_processs_environment(tmp_path,
                                                                             monkeypatch):
    """Workers fork from a forkserver that imported their modules once and set numba up (0.01 s
    of CPU a worker against 1.6–1.9 s spawned, and ~0.5 s more for numba's set-up). What the
    forkserver cannot know — an environment variable and a working directory set after it
    started — reaches them all the same; and the worker is the forkserver's child, not this
    process's, so it must watch both to die with us."""
    with worker_pool("local", None, 1) as ex:      # the forkserver is running after this
        list(execute_many({0: (os.getpid, ())}, ex))
    monkeypatch.setenv("XVAL_TEST_MARK", "set after the forkserver started")
    monkeypatch.chdir(tmp_path)
    with worker_pool("local", None, 1) as ex:
        (out,) = list(execute_many({0: (_worker_view, ())}, ex))
    assert out.error is None, out.error
    preloaded, mark, cwd, ppid = out.value
    assert preloaded, "the worker imported its modules or set numba up itself"
    assert mark == "set after the forkserver started"
    assert os.path.samefile(cwd, tmp_path)
    assert ppid != os.getpid()                     # forked by the forkserver
