"""The project's one seam for parallel work (runs, sweeps, blind cases).

``map_ordered(fn, items)`` runs ``fn`` on every item and returns the results in input order, with a
progress bar.  Where the work runs is chosen by :class:`ExecutorConfig`:

* ``workers=1``: in this process, nested ``map_ordered`` calls included (no pickling; easiest to debug);
* ``workers=N`` (default: the number of cores): a local ``ProcessPoolExecutor``;
* ``scheduler="tcp://host:8786"`` (or ``$CUBEDIMER_SCHEDULER``): a ``dask.distributed`` client
  connected to an existing cluster; install with ``pip install 'cubedimer[dask]'``.

``fn`` and the items must be picklable (module-level functions, plain data).

No nested pools: work that runs inside a task - a call of ``fn`` by :func:`map_ordered` on any
executor, a daemonic process (which may not start children) or a dask worker - calls
``map_ordered`` serially, in its own process.  A blind study therefore parallelises over its cases
and each case simulates its runs one after another, on local processes and on a cluster alike;
callers need not know where they run (:func:`in_task` tells them).

Every task runs with one BLAS thread (:func:`single_blas_thread`), wherever it runs: a dask worker
process starts with one (its nanny sets ``OMP_NUM_THREADS=1``), and a multi-threaded BLAS rounds its
reductions differently, so that without this the same study differed in the last digits between a
serial run and a cluster.  The parallelism is across tasks.
"""
from __future__ import annotations

import logging
import multiprocessing
import os
import sys
import threading

from .config_checks import check_choice, check_that, check_whole
from contextlib import contextmanager
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from typing import Any, Callable, Iterable, Iterator, Sequence

__all__ = ["ExecutorConfig", "ExecutorError", "map_ordered", "in_task", "loopback_cluster", "single_blas_thread"]

logger = logging.getLogger(__name__)

_task_state = threading.local()  # .depth: how many map_ordered tasks enclose the current call


class ExecutorError(RuntimeError):
    """The requested executor cannot be used (dask not installed, scheduler unreachable); one line."""


@dataclass(frozen=True)
class ExecutorConfig:
    """Where parallel work runs.

    Parameters
    ----------
    workers : int, optional
        Local worker processes; None means ``os.cpu_count()``; 1 runs in-process.
    scheduler : str, optional
        Address of a dask.distributed scheduler; overrides ``workers``.  Defaults to the
        environment variable ``CUBEDIMER_SCHEDULER`` when set.
    start_method : {None, "fork", "spawn", "forkserver"}
        How local worker processes start (None: the platform's default, ``fork`` on Linux).  Work whose libraries
        start OpenMP threads in the calling process (bempp-cl's numba-parallel assembly) needs ``spawn``: a process
        that has used GNU OpenMP is terminated by ``fork``.
    """

    workers: int | None = None
    scheduler: str | None = None
    start_method: str | None = None

    def __post_init__(self) -> None:
        check_whole(self, "workers", optional=True)
        check_that(self, self.scheduler is None or isinstance(self.scheduler, str),
                   f"scheduler must be an address string, got {self.scheduler!r}")
        check_choice(self, "start_method", (None, "fork", "spawn", "forkserver"), what="start_method")

    def resolved_scheduler(self) -> str | None:
        return self.scheduler or os.environ.get("CUBEDIMER_SCHEDULER") or None

    def resolved_workers(self) -> int:
        w = self.workers if self.workers is not None else (os.cpu_count() or 1)
        if w < 1:
            raise ValueError(f"workers must be >= 1, got {w}")
        return int(w)


def in_task() -> bool:
    """True when the caller runs inside a parallel task, where :func:`map_ordered` runs serially.

    That is: inside a call of ``fn`` made by :func:`map_ordered` (in this thread), in a daemonic
    process, or on a dask worker.
    """
    if getattr(_task_state, "depth", 0) > 0 or multiprocessing.current_process().daemon:
        return True
    if "distributed" in sys.modules:  # only ask dask when it is loaded (a worker has loaded it)
        try:
            from distributed import get_worker

            get_worker()
            return True
        except (ImportError, ValueError):
            pass
    return False


def single_blas_thread():
    """Context manager: one BLAS/OpenMP thread inside it (threadpoolctl), the same result wherever a
    task runs; many small factorisations are also faster so on a shared machine."""
    from threadpoolctl import threadpool_limits

    return threadpool_limits(1)


class _Task:
    """``fn`` run with one BLAS thread; with ``mark``, also marked as a task while it runs, so that a
    :func:`map_ordered` inside it runs serially."""

    def __init__(self, fn: Callable[[Any], Any], mark: bool = True):
        self.fn = fn
        self.mark = mark

    def __call__(self, item: Any) -> Any:
        with single_blas_thread():
            if not self.mark:
                return self.fn(item)
            _task_state.depth = getattr(_task_state, "depth", 0) + 1
            try:
                return self.fn(item)
            finally:
                _task_state.depth -= 1


def _progress(total: int, desc: str | None, enabled: bool):
    from tqdm.auto import tqdm

    return tqdm(total=total, desc=desc, disable=not enabled or total <= 1, leave=False)


def map_ordered(
    fn: Callable[[Any], Any],
    items: Iterable[Any],
    config: ExecutorConfig | None = None,
    desc: str | None = None,
    progress: bool = True,
    on_result: Callable[[int, Any], None] | None = None,
) -> list[Any]:
    """Apply ``fn`` to every item, in parallel per ``config``; results in input order.

    Parameters
    ----------
    fn : callable
        Picklable function of one argument.
    items : iterable
        Inputs.
    config : ExecutorConfig, optional
        Where to run (default: local processes, one per core).
    desc : str, optional
        Progress-bar label.
    progress : bool
        Show a progress bar (stderr).
    on_result : callable, optional
        Called as ``on_result(index, result)`` in the parent process as each item finishes, e.g.
        to save it to disk so that an interrupted study can resume.

    Called inside a task (see :func:`in_task`), it runs serially in the calling process whatever
    ``config`` says, so that no process pool is ever started inside another one.

    Exceptions raised by ``fn`` propagate (the first one, after cancelling what has not started).
    """
    config = config or ExecutorConfig()
    items: Sequence[Any] = list(items)
    results: list[Any] = [None] * len(items)
    nested = in_task()
    if nested:
        logger.debug("map_ordered inside a task: %d item(s) run serially in process %d", len(items), os.getpid())
    task = _Task(fn)
    bar = _progress(len(items), desc, progress and not nested)
    try:
        address = None if nested else config.resolved_scheduler()
        if address:
            try:
                from dask.distributed import Client, as_completed as dask_as_completed
            except ImportError:  # pragma: no cover - depends on the optional extra
                raise ExecutorError(f"a dask scheduler ({address}) was requested but dask.distributed is not "
                                    f"installed: pip install 'cubedimer[dask]'") from None
            try:
                client = Client(address)
            except (OSError, TimeoutError, ValueError) as exc:
                raise ExecutorError(f"cannot reach the dask scheduler at {address} ({type(exc).__name__}: "
                                    f"{str(exc)[:200]})") from None
            with client:
                futures = {client.submit(task, it, pure=False): i for i, it in enumerate(items)}
                for fut in dask_as_completed(list(futures)):
                    i = futures[fut]
                    results[i] = fut.result()
                    if on_result:
                        on_result(i, results[i])
                    bar.update()
            return results
        requested = 1 if nested else config.resolved_workers()
        if min(requested, len(items)) <= 1:
            # workers=1 means one process for everything, nested work included; a single item with
            # more workers allowed runs here unmarked, so that work inside it may still use them
            call = task if requested == 1 else _Task(fn, mark=False)
            for i, it in enumerate(items):
                results[i] = call(it)
                if on_result:
                    on_result(i, results[i])
                bar.update()
            return results
        context = multiprocessing.get_context(config.start_method) if config.start_method else None
        with ProcessPoolExecutor(max_workers=min(requested, len(items)), mp_context=context) as pool:
            futures = {pool.submit(task, it): i for i, it in enumerate(items)}
            try:
                for fut in as_completed(futures):
                    i = futures[fut]
                    results[i] = fut.result()
                    if on_result:
                        on_result(i, results[i])
                    bar.update()
            except BaseException:
                for f in futures:
                    f.cancel()
                raise
        return results
    finally:
        bar.close()


@contextmanager
def loopback_cluster(n_workers: int = 2, timeout: float = 60.0) -> Iterator[str]:
    """A dask cluster on 127.0.0.1 for trying the cluster path on one machine; yields its address.

    A scheduler and ``n_workers`` daemonic worker processes of one thread each (what
    ``dask scheduler`` plus ``dask worker --nworkers N --nthreads 1`` start), shut down on exit.

    Parameters
    ----------
    n_workers : int
        Worker processes.
    timeout : float
        Longest wait [s] of a worker for the scheduler, and for the cluster to close.
    """
    try:
        from dask.distributed import LocalCluster
    except ImportError:  # pragma: no cover - depends on the optional extra
        raise ExecutorError("dask.distributed is not installed: pip install 'cubedimer[dask]'") from None
    cluster = LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True, host="127.0.0.1",
                           dashboard_address=":0", silence_logs=logging.ERROR, death_timeout=timeout)
    try:
        yield cluster.scheduler_address
    finally:
        cluster.close(timeout=timeout)
