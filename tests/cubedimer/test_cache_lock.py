"""The cache entry lock: a second process waits for the first's entry, a killed holder leaves no stale lock, and
a place where no lock can be taken runs the block unlocked rather than failing."""
from __future__ import annotations

import subprocess
import sys
import threading
import time

from cubedimer.cache_lock import cache_entry_lock


def test_a_second_holder_waits_until_the_first_has_made_the_entry(tmp_path):
    entry = tmp_path / "entry.json"
    held = threading.Event()

    def first():
        with cache_entry_lock(entry):
            held.set()
            time.sleep(0.4)
            entry.write_text("made")

    worker = threading.Thread(target=first)
    worker.start()
    assert held.wait(10)
    with cache_entry_lock(entry) as locked:
        seen = entry.read_text() if entry.exists() else None  # only after the first has let go
    worker.join()
    assert locked and seen == "made"


def test_a_holder_that_is_killed_leaves_no_stale_lock(tmp_path):
    entry = tmp_path / "entry.json"
    code = ("import sys, time; from cubedimer.cache_lock import cache_entry_lock\n"
            f"with cache_entry_lock({str(entry)!r}):\n    print('held', flush=True); time.sleep(120)")
    child = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    try:
        assert child.stdout.readline().strip() == "held"
    finally:
        child.kill()
        child.wait()
    taken = []
    taker = threading.Thread(target=lambda: taken.append(cache_entry_lock(entry).__enter__()), daemon=True)
    taker.start()
    taker.join(timeout=10)
    assert taken == [True]


def test_where_no_lock_can_be_taken_the_block_runs_unlocked(tmp_path):
    (tmp_path / "a file").write_text("")
    ran = []
    with cache_entry_lock(tmp_path / "a file" / "entry.json") as locked:  # its folder cannot be made
        ran.append(1)
    assert ran == [1] and locked is False
