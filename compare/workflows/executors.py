"""Where jobs run: a local process pool (embedded, nothing to start) or Dask distributed (a
LocalCluster, or a running scheduler's address); campaigns and maps use the same two."""
import multiprocessing
import signal
from concurrent.futures import ProcessPoolExecutor

from ..errors import BadInput


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


def make_executor(kind, scheduler, workers, ignore_sigint=False):
    if kind == "dask":
        try:
            from distributed import Client, LocalCluster
        except ImportError:
            raise BadInput("--executor dask needs the optional extra: pip install "
                           "'xval[dask]'") from None
        if scheduler:
            client = connect(scheduler)
        else:
            client = Client(LocalCluster(n_workers=workers or 2, threads_per_worker=1,
                                         dashboard_address=None, silence_logs=50))
        return client.get_executor(), client
    # spawn: engines start threads; a forked child would inherit a half-initialised state.
    # The children inherit one BLAS thread each (compare/__init__.py)
    # a campaign's workers ignore SIGINT: Ctrl-C reaches the whole process group, and only the
    # main process decides what happens (stop the workers, keep what is stored, say how to
    # resume); other callers keep the default (a worker's KeyboardInterrupt ends its job)
    quiet = dict(initializer=signal.signal, initargs=(signal.SIGINT, signal.SIG_IGN)) \
        if ignore_sigint else {}
    return ProcessPoolExecutor(max_workers=workers or 2,
                               mp_context=multiprocessing.get_context("spawn"), **quiet), None
