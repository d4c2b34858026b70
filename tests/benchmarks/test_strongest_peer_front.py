"""The strongest-peer benchmark's second target (every size on our front against pysindy's best at that size or
smaller) and its table from an unfinished grid's cache (``--cached-only``)."""
from __future__ import annotations

import json

import numpy as np

import benchmarks.bench_strongest_peer as bench


def _point(size, ours, best, cv):
    return {"size": size, "n_terms": [size, size], "selected": False, "ours": ours, "best": best, "best_cfg": "a",
            "cv": cv, "cv_cfg": "b"}


def test_second_target_needs_every_front_point_at_most_pysindys_best_at_that_size():
    rows = [{"method": "ours", "truth": "t", "level": 0.12, "seed": 1, "fit_runs": 8,
             "front": [_point(1, np.inf, None, None),  # no pysindy model this small: nothing to beat, not counted
                       _point(3, np.inf, np.inf, np.inf),  # both blew up: a tie
                       _point(8, 0.02, 0.03, 0.05), _point(11, 0.03, 0.02, 0.04)]},
            {"method": "ours", "truth": "t", "level": 0.12, "seed": 2, "fit_runs": 8,
             "front": [_point(8, 0.02, 0.03, 0.03)]}]
    text = "\n".join(bench.targets_front(rows))
    # seed 1: 4 points, 3 with a pysindy model; at most the CV pick at each (the tie at size 3 is the worst, 1.00),
    # but 1.50 times the held-out best at size 11
    assert "| 4 (3) | yes (3 of 3) | 1.00 (3) | no (2 of 3; lost at 11) | 1.50 (11) |" in text
    assert "picks at that size or smaller: 2 of 2 cases (100 %" in text
    assert "held-out runs at that size or smaller: 1 of 2 cases (50 %" in text
    assert bench._ratio(np.inf, 0.1) == np.inf and np.isnan(bench._ratio(0.1, None))


def test_cached_only_tabulates_the_finished_cases_and_names_the_others(tmp_path, monkeypatch):
    seen = []
    monkeypatch.setattr(bench, "run_case", lambda *case: seen.append(case[:4]) or [])
    key = bench._case_key("duffing_vdp", 0.05, 7, 4)
    for part in ("peer", f"ours_v{bench.OURS_VERSION}"):
        (tmp_path / f"{key}_{part}.json").write_text(json.dumps({}))
    (tmp_path / f"{bench._case_key('duffing_vdp', 0.12, 7, 4)}_peer.json").write_text("{}")  # ours not finished
    text = bench.main(["--truths", "duffing_vdp", "--levels", "0.05", "0.12", "--seeds", "7", "--runs", "4",
                       "--cache-dir", str(tmp_path), "--cached-only"])
    assert seen == [("duffing_vdp", 0.05, 7, 4)]
    assert "Not measured (not in the cache): duffing_vdp 12 % seed 7 4 runs." in text and "--cached-only" in text
