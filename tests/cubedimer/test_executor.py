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
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=":0") as cluster:
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


def _inner_pid(_: int) -> int:
    return os.getpid()


def _outer(n: int) -> tuple[int, list[int], bool]:
    """A task that itself calls map_ordered with the default config (a pool, if it were allowed)."""
    from cubedimer.executor import in_task

    return os.getpid(), map_ordered(_inner_pid, range(n), ExecutorConfig(workers=2), progress=False), in_task()


def _assert_nested_serial(out, n=3):
    for pid, inner, marked in out:
        assert marked and inner == [pid] * n  # the inner work ran in the task's own process


@pytest.mark.parametrize("workers", [1, 2])
def test_map_ordered_inside_a_task_runs_serially(workers):
    out = map_ordered(_outer, [3, 3, 3], ExecutorConfig(workers=workers), progress=False)
    _assert_nested_serial(out)
    if workers == 1:
        assert {pid for pid, _, _ in out} == {os.getpid()}
    from cubedimer.executor import in_task

    assert not in_task()  # the marker does not leak out of the task


def test_single_item_with_workers_left_may_use_them():
    """One item on a multi-worker config runs here unmarked: its own parallel work may use the pool."""
    (pid, inner, marked), = map_ordered(_outer, [2], ExecutorConfig(workers=2), progress=False)
    assert pid == os.getpid() and not marked and os.getpid() not in inner


def _module_file(_: int) -> str:
    import cubedimer.executor

    return cubedimer.executor.__file__


def test_nested_map_ordered_on_a_process_cluster(process_cluster):
    """Daemonic dask worker processes may not start children: nested work must run in the task."""
    import cubedimer.executor

    # the workers run this checkout's code (what the cluster tests of the commands rely on)
    assert set(map_ordered(_module_file, range(2), ExecutorConfig(scheduler=process_cluster),
                           progress=False)) == {cubedimer.executor.__file__}
    out = map_ordered(_outer, [3, 3, 3, 3], ExecutorConfig(scheduler=process_cluster), progress=False)
    _assert_nested_serial(out)
    assert os.getpid() not in {pid for pid, _, _ in out}
    assert map_ordered(_work, range(4), ExecutorConfig(scheduler=process_cluster),
                       progress=False) == [_work(s) for s in range(4)]


def test_config_validates_itself():
    for bad in (0, -1, 1.5, True):
        with pytest.raises(ValueError):
            ExecutorConfig(workers=bad)


def test_unreachable_scheduler_is_one_executor_error():
    dask = pytest.importorskip("dask")
    from cubedimer.executor import ExecutorError

    with dask.config.set({"distributed.comm.timeouts.connect": "1s"}):
        with pytest.raises(ExecutorError, match="cannot reach the dask scheduler at tcp://127.0.0.1:9"):
            map_ordered(_work, range(2), ExecutorConfig(scheduler="tcp://127.0.0.1:9"), progress=False)


def _blas_threads(_: int) -> list[int]:
    from threadpoolctl import threadpool_info

    return [pool["num_threads"] for pool in threadpool_info() if pool["user_api"] == "blas"]


@pytest.mark.parametrize("workers", [1, 2])
def test_every_task_runs_with_one_blas_thread(workers):
    """A dask worker starts with one BLAS thread; every task gets one everywhere, so that reductions
    round the same way serially, on local processes and on a cluster (results byte-identical)."""
    from threadpoolctl import threadpool_limits

    with threadpool_limits(2):  # the caller's own setting must not leak into the tasks
        threads = map_ordered(_blas_threads, range(1 if workers == 2 else 3), ExecutorConfig(workers=workers),
                              progress=False)
    assert threads and all(t == [1] * len(t) and t for t in threads), threads


def test_blas_threads_restored_after_the_tasks():
    from threadpoolctl import threadpool_limits

    with threadpool_limits(2):
        map_ordered(_blas_threads, range(2), ExecutorConfig(workers=1), progress=False)
        assert all(n == 2 for n in _blas_threads(0)), _blas_threads(0)


def test_spawned_workers_give_the_same_results():
    """``start_method="spawn"`` (the family build's: a process running OpenMP threads cannot be forked)."""
    assert map_ordered(abs, [-3, -1, -2], ExecutorConfig(workers=2, start_method="spawn"), progress=False) == [3, 1, 2]


def test_an_unknown_start_method_is_refused():
    with pytest.raises(ValueError, match="start_method"):
        ExecutorConfig(start_method="thread")
