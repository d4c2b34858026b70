"""The executor seam: ordered results, progress callbacks, local processes and a dask cluster agree."""
import os

import numpy as np
import pytest

from cubedimer.executor import ExecutorConfig, map_ordered


def _work(seed: int) -> float:
    """A seeded computation: the same seed gives the same number wherever it runs."""
    return float(np.random.default_rng(seed).standard_normal(1000).sum())


def _fail_on_three(x: int) -> int:
    if x == 3:
        raise ValueError("bad item 3")
    return x


@pytest.mark.parametrize("workers", [1, 2])
def test_results_in_input_order_and_callback(workers):
    seen = []
    out = map_ordered(_work, range(6), ExecutorConfig(workers=workers), progress=False, on_result=lambda i, r: seen.append(i))
    assert out == [_work(s) for s in range(6)]
    assert sorted(seen) == list(range(6))


def test_errors_propagate():
    with pytest.raises(ValueError, match="bad item 3"):
        map_ordered(_fail_on_three, range(5), ExecutorConfig(workers=2), progress=False)


def test_dask_cluster_gives_same_results():
    distributed = pytest.importorskip("dask.distributed")
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None) as cluster:
        out = map_ordered(_work, range(4), ExecutorConfig(scheduler=cluster.scheduler_address), progress=False)
    assert out == [_work(s) for s in range(4)]


def test_environment_selects_scheduler(monkeypatch):
    monkeypatch.setenv("CUBEDIMER_SCHEDULER", "tcp://example:8786")
    assert ExecutorConfig().resolved_scheduler() == "tcp://example:8786"
    monkeypatch.delenv("CUBEDIMER_SCHEDULER")
    assert ExecutorConfig().resolved_scheduler() is None
    assert ExecutorConfig(workers=None).resolved_workers() == (os.cpu_count() or 1)
    with pytest.raises(ValueError):
        ExecutorConfig(workers=0).resolved_workers()
