"""Where jobs run, and the one executor under every study that runs many: `worker_pool` (a
local process pool — embedded, nothing to start — or Dask distributed: a LocalCluster or a
running scheduler's address) owns the workers' lives, and `execute_many` runs calls on it and
hands each outcome back as it finishes (what a store already holds under a call's digest is
the caller's to skip: a campaign's jobs, a map's points). Campaigns,
maps and `bench --points` all go through these two.

A local pool's workers are forked from a forkserver that imported their modules once (Linux;
elsewhere spawned), and die with the process that started the pool: each sets the kernel's
parent-death signal (Linux `prctl(PR_SET_PDEATHSIG, SIGKILL)`) and watches that process from a
thread (any POSIX system; a worker busy inside a compiled kernel sees it when the kernel
returns), so a `kill -9` of `xval campaign` / `xval map` leaves no worker behind, and the
forkserver and the resource tracker, whose pipes the workers held, end with them.
`terminated_as_interrupt()` turns SIGTERM into the Ctrl-C path (finished jobs kept, one line
saying how to resume, the lock released).
"""
import ast
import ctypes
import multiprocessing
import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterator
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from contextlib import contextmanager
from dataclasses import dataclass

from ..errors import BadInput
from ..output.guard import alive

PR_SET_PDEATHSIG = 1
WATCH_S = 1.0              # how often a worker looks for its parent


def connect(scheduler, timeout_s=10):
    """A Dask client of the scheduler at `scheduler`; BadInput (one line) when none answers."""
    try:
        from distributed import Client
    except ImportError:
        raise BadInput("--executor dask needs the optional extra: pip install "
                       "'xval[dask]'") from None
    try:
        return Client(scheduler, timeout=f"{timeout_s}s")
    except (OSError, TimeoutError, ValueError) as e:
        raise BadInput(f"--scheduler {scheduler}: no Dask scheduler answers there "
                       f"({type(e).__name__}: {str(e).splitlines()[0] if str(e) else ''})"
                       ) from None


def _worker_init(parent, env):
    """In each pool worker: ignore SIGINT (Ctrl-C reaches the whole process group; the main
    process stops the workers and keeps what is stored), take the environment `parent` has now
    (a forked worker starts from the forkserver's), and die with `parent`: the kernel's signal
    where there is one, armed against the process that started this one (`parent` itself, or
    the forkserver, which lives while its workers do), and a thread that watches both."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    os.environ.clear()
    os.environ.update(env)
    host = os.getppid()
    if sys.platform.startswith("linux"):
        try:
            ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
        except (OSError, AttributeError):
            pass

    def parent_alive():                # a forked worker, not its child, gets no signal from it
        return os.getppid() == host and alive(parent)

    if not parent_alive():             # the parent died before the signal was armed
        os._exit(1)

    def watch():
        while parent_alive():
            time.sleep(WATCH_S)
        os._exit(1)
    threading.Thread(target=watch, daemon=True, name="xval-parent-watch").start()


def _context():
    """How a local pool starts its workers. Linux: forked from a forkserver that imported the
    workers' modules once (`pool_preload`): a worker is ready after 0.01 s of CPU, where a
    spawned one started a fresh interpreter and imported them again, 1.6–1.9 s (35 spawned
    workers were ~15 % of a default test run's CPU). The forkserver is a clean,
    single-threaded process: nothing of this one (engine threads, rerun's) is forked.
    Elsewhere: spawn."""
    if not sys.platform.startswith("linux"):
        return multiprocessing.get_context("spawn")
    ctx = multiprocessing.get_context("forkserver")
    ctx.set_forkserver_preload(["compare.workflows.pool_preload"])
    return ctx


def make_executor(kind, scheduler, workers):
    """(executor, what to close after it): a Dask client's executor with the client and the
    LocalCluster it started (a Client closes only a cluster it made itself: one passed in kept
    its scheduler, workers and their monitors running in this process — measured, ~9 % of the
    CPU of a test session after two Dask tests), or a local process pool and nothing."""
    if kind == "dask":
        try:
            from distributed import Client, LocalCluster
        except ImportError:
            raise BadInput("--executor dask needs the optional extra: pip install "
                           "'xval[dask]'") from None
        if scheduler:
            client = connect(scheduler)
            return client.get_executor(), (client,)
        # no dashboard; the scheduler's HTTP routes on a free port, not 8787 (taken by
        # another cluster, it was a UserWarning on the campaign's stderr)
        cluster = LocalCluster(n_workers=workers or 2, threads_per_worker=1,
                               dashboard_address=None, silence_logs=50,
                               scheduler_kwargs={"dashboard_address": ":0"})
        client = Client(cluster)
        return client.get_executor(), (client, cluster)
    # never a fork of this process: engines start threads, and a forked child would inherit a
    # half-initialised state. The children run one BLAS thread each (compare/__init__.py)
    return _take_warm(workers) or ProcessPoolExecutor(
        max_workers=workers or 2, mp_context=_context(), initializer=_worker_init,
        initargs=(os.getpid(), dict(os.environ))), ()


# The local pool a study ended with, kept for the next study of this process (a campaign's
# maps, the next call of a notebook or a test session): a new worker's kernel loads (and,
# spawned, its imports: ~3 s of CPU) were paid again by every study. Kept only while what a
# worker starts from — worker count, working directory, sys.path, the environment — is the
# same; the workers end with this process (atexit, as any pool) or when that changes.
_warm: dict = {}


def _pool_key(workers):
    # PYTEST_CURRENT_TEST: pytest rewrites it for every test; no worker reads it
    env = sorted((k, v) for k, v in os.environ.items() if k != "PYTEST_CURRENT_TEST")
    return workers or 2, os.getcwd(), tuple(sys.path), tuple(env)


def _take_warm(workers):
    """The pool parked for this worker count, working directory, path and environment, if it
    still takes work (a worker may have died while it waited); else None."""
    warm = _warm.pop(_pool_key(workers), None)
    if warm is not None and not _usable(warm):
        warm.shutdown(wait=False, cancel_futures=True)
        warm = None
    return warm


def _keep_warm(ex, workers):
    """Park a pool whose every call has returned; a broken or shut-down one, and the pools
    parked under another working directory, path or environment, are ended instead."""
    key = _pool_key(workers)
    for k in [k for k in _warm if k[1:] != key[1:]]:
        _warm.pop(k).shutdown(wait=False, cancel_futures=True)
    if _usable(ex) and not ex._pending_work_items and key not in _warm:
        _warm[key] = ex
    else:
        ex.shutdown(wait=True)


def _usable(ex) -> bool:
    """A process pool that takes work: not broken, not shut down, every worker alive (one
    killed a moment ago is not yet marked broken)."""
    return (isinstance(ex, ProcessPoolExecutor) and not ex._broken and not ex._shutdown_thread
            and all(p.is_alive() for p in (ex._processes or {}).values()))


def _is_main_test(node):
    """`__name__ == "__main__"` (either way round)."""
    if not (isinstance(node, ast.Compare) and len(node.ops) == 1
            and isinstance(node.ops[0], ast.Eq)):
        return False
    sides = [node.left, node.comparators[0]]
    return (any(isinstance(x, ast.Name) and x.id == "__name__" for x in sides)
            and any(isinstance(x, ast.Constant) and x.value == "__main__" for x in sides))


def unguarded_script():
    """The script whose top level called us outside `if __name__ == "__main__":`, or None.
    A spawned pool worker imports the main script again: from that line it would call us
    again and die (BrokenProcessPool). None where there is no script file (a notebook,
    `python -c`) or its source cannot be read."""
    main = sys.modules.get("__main__")
    path = getattr(main, "__file__", None)
    f = sys._getframe(1)
    while f is not None and not (f.f_globals is vars(main) and f.f_code.co_name == "<module>"):
        f = f.f_back
    if f is None or not path:
        return None
    try:
        tree = ast.parse(open(path, encoding="utf-8").read())
    except (OSError, SyntaxError, ValueError):
        return None
    guarded = any(isinstance(n, ast.If) and _is_main_test(n.test)
                  and n.body[0].lineno <= f.f_lineno <= n.body[-1].end_lineno for n in tree.body)
    return None if guarded else path


class Interrupted(Exception):
    """Ctrl-C or SIGTERM in a campaign or map: the workers were stopped; the message says what
    is kept."""


def stop(ex):
    """Cancel what is queued and end the running jobs now (Ctrl-C, SIGTERM)."""
    procs = list((getattr(ex, "_processes", None) or {}).values())   # shutdown forgets them
    if isinstance(ex, ProcessPoolExecutor):
        ex.shutdown(wait=False, cancel_futures=True)
    else:                              # Dask's executor: wait=False cancels its futures
        ex.shutdown(wait=False)
    for p in procs:
        p.terminate()
    for p in procs:
        p.join(10)


@contextmanager
def terminated_as_interrupt():
    """SIGTERM raises KeyboardInterrupt in the main thread while the block runs, so that a
    `kill` takes the Ctrl-C path (workers stopped, finished jobs kept, lock released)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def on_term(signum, frame):
        raise KeyboardInterrupt()
    old = signal.signal(signal.SIGTERM, on_term)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, old)


@contextmanager
def _sigint_ignored():
    """Workers spawned in this block start with SIGINT ignored (a Python started so keeps it):
    Ctrl-C reaches the whole process group, and only the main process decides what happens."""
    if threading.current_thread() is not threading.main_thread():
        yield                              # only the main thread may set handlers
        return
    old = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old)


@contextmanager
def worker_pool(kind="local", scheduler=None, workers=None, on_stop: Callable = stop,
                in_process_if_unguarded=False):
    """The workers of one study, and everything about their lives: they die with this process
    (see `_worker_init`), SIGTERM is handled as Ctrl-C, and on either `on_stop(executor)` ends
    them (default `stop`; a campaign also removes its half-written files) before the
    KeyboardInterrupt goes on to the caller; on any other exception they finish and are shut
    down; on a normal exit, every call returned, a local pool is kept warm for the next study
    of this process (`_warm`).
    `in_process_if_unguarded`: a script that called us outside its `__main__` guard gets None
    (run here, one call at a time) and one line saying what to add — its spawned workers would
    import it again and die."""
    script = kind == "local" and in_process_if_unguarded and unguarded_script()
    if script:
        print(f"xval: {script}: running in this process, one point at a time; put the call "
              f'under `if __name__ == "__main__":` for {workers or 2} workers', file=sys.stderr)
        yield None
        return
    ex, owned = make_executor(kind, scheduler, workers)
    try:
        with terminated_as_interrupt():
            yield ex
    except KeyboardInterrupt:
        on_stop(ex)
        raise
    except BaseException:
        ex.shutdown(wait=True)
        raise
    else:
        if not owned:
            _keep_warm(ex, workers)
        else:
            ex.shutdown(wait=True)
    finally:
        for x in owned:
            x.close()


@dataclass
class Outcome:
    """One call's end: its key, and its value or the exception it raised."""
    key: object
    value: object = None
    error: BaseException | None = None


def execute_many(calls: dict, executor=None, waiting: Callable | None = None,
                 poll_s: float = 0.5) -> Iterator[Outcome]:
    """Run `calls` ({key: (fn, args)}, fn importable by the workers) and yield an `Outcome` as
    each finishes (`executor` None: here, one after another). A call that raises is an outcome
    like any other: a dead worker never hides the other calls. `waiting(keys)`: told every
    `poll_s` which keys are still out (a progress view)."""
    todo = calls
    if executor is None:
        for key, (fn, args) in todo.items():
            try:
                yield Outcome(key, fn(*args))
            except Exception as e:
                yield Outcome(key, error=e)
        return
    with _sigint_ignored():                # a worker spawns at its first submit
        futures = {executor.submit(fn, *args): key for key, (fn, args) in todo.items()}
    left = set(futures)
    while left:
        done, left = wait(left, timeout=poll_s, return_when=FIRST_COMPLETED)
        if waiting:
            waiting([futures[f] for f in left])
        for f in done:
            try:
                yield Outcome(futures[f], f.result())
            except Exception as e:
                yield Outcome(futures[f], error=e)
