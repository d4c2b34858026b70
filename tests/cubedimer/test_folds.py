"""The K-fold split over runs (cubedimer.folds): interleaved folds, every run held out once."""
from cubedimer.folds import run_folds


def test_interleaved_folds_exact():
    assert run_folds(7, 3) == [([1, 2, 4, 5], [0, 3, 6]), ([0, 2, 3, 5, 6], [1, 4]), ([0, 1, 3, 4, 6], [2, 5])]


def test_more_folds_than_runs_is_leave_one_run_out():
    assert run_folds(3, 5) == [([1, 2], [0]), ([0, 2], [1]), ([0, 1], [2])]


def test_every_run_held_out_exactly_once_and_never_trained_on_in_its_fold():
    for n in range(1, 12):
        for k in range(1, 8):
            folds = run_folds(n, k)
            assert len(folds) == min(k, n)
            held = sorted(i for _, test in folds for i in test)
            assert held == list(range(n))
            for train, test in folds:
                assert sorted(train + test) == list(range(n))


def test_no_runs_no_folds():
    assert run_folds(0, 5) == []
