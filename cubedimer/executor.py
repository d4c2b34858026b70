"""The project's one seam for parallel work (runs, sweeps, blind cases).

``map_ordered(fn, items)`` runs ``fn`` on every item and returns the results in input order, with a
progress bar.  Where the work runs is chosen by :class:`ExecutorConfig`:

* ``workers=1``: in this process (no pickling; easiest to debug);
* ``workers=N`` (default: the number of cores): a local ``ProcessPoolExecutor``;
* ``scheduler="tcp://host:8786"`` (or ``$CUBEDIMER_SCHEDULER``): a ``dask.distributed`` client
  connected to an existing cluster; install with ``pip install 'cubedimer[dask]'``.

``fn`` and the items must be picklable (module-level functions, plain data).
"""
from __future__ import annotations

import os
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from typing import Any, Callable, Iterable, Sequence

__all__ = ["ExecutorConfig", "map_ordered"]


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
    """

    workers: int | None = None
    scheduler: str | None = None

    def resolved_scheduler(self) -> str | None:
        return self.scheduler or os.environ.get("CUBEDIMER_SCHEDULER") or None

    def resolved_workers(self) -> int:
        w = self.workers if self.workers is not None else (os.cpu_count() or 1)
        if w < 1:
            raise ValueError(f"workers must be >= 1, got {w}")
        return int(w)


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

    Exceptions raised by ``fn`` propagate (the first one, after cancelling what has not started).
    """
    config = config or ExecutorConfig()
    items: Sequence[Any] = list(items)
    results: list[Any] = [None] * len(items)
    bar = _progress(len(items), desc, progress)
    try:
        address = config.resolved_scheduler()
        if address:
            try:
                from dask.distributed import Client, as_completed as dask_as_completed
            except ImportError as exc:  # pragma: no cover - depends on the optional extra
                raise RuntimeError(
                    "a dask scheduler was requested but dask.distributed is not installed: "
                    "pip install 'cubedimer[dask]'"
                ) from exc
            with Client(address) as client:
                futures = {client.submit(fn, it, pure=False): i for i, it in enumerate(items)}
                for fut in dask_as_completed(list(futures)):
                    i = futures[fut]
                    results[i] = fut.result()
                    if on_result:
                        on_result(i, results[i])
                    bar.update()
            return results
        workers = min(config.resolved_workers(), max(len(items), 1))
        if workers == 1:
            for i, it in enumerate(items):
                results[i] = fn(it)
                if on_result:
                    on_result(i, results[i])
                bar.update()
            return results
        with ProcessPoolExecutor(max_workers=workers) as pool:
            futures = {pool.submit(fn, it): i for i, it in enumerate(items)}
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
