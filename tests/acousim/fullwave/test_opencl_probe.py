"""The OpenCL verdict: a trial run in a child process, whose failures (an exception, an abort, a hang) mean "no
OpenCL" rather than a crash of the command, cached per environment and never fatal when the cache is bad."""
from __future__ import annotations

import json
import threading
import time

import pytest

from acousim.fullwave import opencl_probe


@pytest.mark.parametrize("code,works,reason", [
    ("print('opencl-probe-ok 264')", True, "264 DOFs ran on OpenCL"),
    ("raise RuntimeError('clCreateKernel failed: INVALID_KERNEL_NAME')", False,
     "exit status 1): RuntimeError: clCreateKernel failed: INVALID_KERNEL_NAME"),
    ("import os; os.abort()", False, "killed by signal 6"),
    ("print('half a line')", False, "exit status 0"),
])
def test_the_trial_run_survives_every_way_a_driver_fails(code, works, reason):
    trial = opencl_probe.run_probe(code, timeout_s=60)
    assert trial.works is works and reason in trial.reason and "\n" not in trial.reason and trial.conclusive


def test_a_trial_run_that_hangs_is_stopped():
    trial = opencl_probe.run_probe("import time; time.sleep(30)", timeout_s=1)
    assert not trial.works and "did not finish in 1 s" in trial.reason
    assert not trial.conclusive  # a slow machine says nothing about the driver


def _counted_probe(monkeypatch, tmp_path, trial, seconds=0.0):
    """The verdict with a device 'found' and a counted trial run giving ``trial``; the cache under tmp_path."""
    calls = []

    def probe():
        calls.append(1)
        time.sleep(seconds)
        return trial

    monkeypatch.setattr(opencl_probe, "_opencl_device_found", lambda: True)
    monkeypatch.setattr(opencl_probe, "suite_cache_root", lambda: tmp_path)
    monkeypatch.setattr(opencl_probe, "run_probe", probe)
    return calls


@pytest.fixture
def probes(monkeypatch, tmp_path):
    """A trial run that fails, counted."""
    return _counted_probe(monkeypatch, tmp_path, opencl_probe.TrialAssembly(False, "exit status 1: broken"))


def test_the_verdict_is_probed_once_per_environment(probes, tmp_path):
    first = opencl_probe.opencl_verdict()
    second = opencl_probe.opencl_verdict()
    assert not first.works and second == first and len(probes) == 1
    cached = json.loads((tmp_path / "opencl" / f"verdict-{first.key}.json").read_text())
    assert cached == {"works": False, "reason": "exit status 1: broken", "key": first.key}


@pytest.mark.parametrize("content", ["{not json", json.dumps({"works": True}), "[]", ""])
def test_a_cached_verdict_that_cannot_be_read_is_probed_again(probes, tmp_path, content):
    path = tmp_path / "opencl" / f"verdict-{opencl_probe.environment_key()}.json"
    path.parent.mkdir(parents=True)
    path.write_text(content)
    assert not opencl_probe.opencl_verdict().works and len(probes) == 1
    assert json.loads(path.read_text())["reason"] == "exit status 1: broken"  # rewritten


def test_another_environment_is_probed_again(probes, monkeypatch):
    opencl_probe.opencl_verdict()
    monkeypatch.setattr(opencl_probe, "_version", lambda package: "9.9" if package == "pyopencl" else "1.0")
    opencl_probe.opencl_verdict()
    assert len(probes) == 2


def test_no_device_means_no_probe(monkeypatch, probes):
    monkeypatch.setattr(opencl_probe, "_opencl_device_found", lambda: False)
    verdict = opencl_probe.opencl_verdict()
    assert not verdict.works and "no OpenCL CPU device" in verdict.reason and probes == []


def test_a_trial_run_out_of_time_is_kept_for_a_while_only(monkeypatch, tmp_path):
    """A timeout is the machine's load, not the driver's verdict: numba for this command and for the other workers
    that ask within RETRY_AFTER_S (they would each wait out the timeout again), a new probe after it."""
    calls = _counted_probe(monkeypatch, tmp_path, opencl_probe.TrialAssembly(False, "did not finish", conclusive=False))
    now = time.time()
    assert not opencl_probe.opencl_verdict().works
    assert not opencl_probe.opencl_verdict().works and len(calls) == 1
    monkeypatch.setattr(opencl_probe.time, "time", lambda: now + opencl_probe.RETRY_AFTER_S + 1)
    assert not opencl_probe.opencl_verdict().works and len(calls) == 2


def test_processes_that_need_the_verdict_at_once_probe_once(monkeypatch, tmp_path):
    """Four workers asking while the first probe runs (0.5 s) wait for it and read its verdict: one probe, not four
    (each thread opens the lock file itself, so that they contend as processes do)."""
    calls = _counted_probe(monkeypatch, tmp_path, opencl_probe.TrialAssembly(True, "ran on OpenCL"), seconds=0.5)
    verdicts = []
    workers = [threading.Thread(target=lambda: verdicts.append(opencl_probe.opencl_verdict())) for _ in range(4)]
    for w in workers:
        w.start()
    for w in workers:
        w.join(timeout=30)
    assert len(verdicts) == 4 and all(v.works for v in verdicts) and len(calls) == 1
