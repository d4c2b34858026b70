"""Runs whose hinge ended folded are left out of the diagnosis, named with their angle (validation.diagnosis.identify.folded)."""
import numpy as np
import pytest

from cubedimer.dataset import load_dataset
from cubedimer.errors import DatasetError
from validation.diagnosis.identify.folded import FOLDED_THETA, folded_angle, leave_out_folded_runs


def _levitated(t, rng, theta):
    """y: a 22-Hz oscillation of 100 um with 1 um of tracking noise; theta as given plus 0.005 of noise."""
    return (1e-4 * np.cos(2 * np.pi * 22 * t) + rng.normal(0, 1e-6, t.size),
            theta + rng.normal(0, 0.005, t.size))


@pytest.fixture
def mixed_set(tmp_path, write_csv):
    """Four runs: a hinge swinging +-0.95 about 0, one that closes to -0.98 after 1 s and stays there (the squeeze
    film's creep), one resting at +0.88, just inside the bound, and one that plunges to the fold in its last 0.15 s
    (the inviscid twin stops a run there)."""
    rng = np.random.default_rng(3)
    t = np.arange(3000) / 1000.0
    angles = {"run01.csv": 0.95 * np.sin(2 * np.pi * 1.7 * t),
              "run02.csv": np.where(t < 1.0, -0.3 + 0.2 * np.sin(2 * np.pi * 1.7 * t), -0.98),
              "run03.csv": np.full(t.size, 0.88),
              "run04.csv": np.where(t < 2.85, 0.3, 0.3 + 0.685 * ((t - 2.85) / 0.149) ** 2)}
    for name, theta in angles.items():
        write_csv(tmp_path / name, t, *_levitated(t, rng, theta))
    return tmp_path


def test_only_the_run_that_ended_folded_is_left_out_with_its_angle(mixed_set):
    dataset = load_dataset(mixed_set)
    angles = {r.name: folded_angle(r) for r in dataset.runs}
    assert angles["run01.csv"] is None  # a wide swing through 0 is not a fold: the median is near 0
    assert angles["run03.csv"] is None  # inside the bound
    np.testing.assert_allclose(angles["run02.csv"], -0.98, atol=0.003)  # the median of 100 frames with 0.005 noise
    assert angles["run04.csv"] > 0.95  # the last 0.1 s has a median of about 0.6: only its last frames tell
    kept = leave_out_folded_runs(dataset)
    assert [r.name for r in kept.runs] == ["run01.csv", "run03.csv"]
    skipped = kept.skipped_files()
    assert [s["file"] for s in skipped] == ["run02.csv", "run04.csv"]
    assert "-0.98" in skipped[0]["reason"] and f"{FOLDED_THETA:g}" in skipped[0]["reason"]
    assert leave_out_folded_runs(kept) is kept  # nothing left to leave out: the same object


def test_a_set_whose_every_hinge_folded_is_refused_in_one_line(tmp_path, write_csv):
    """A strong mirror asymmetry (beta0 beyond the hinge's largest restoring acceleration) folds every run: the
    diagnosis refuses the set, counting the skipped files, instead of diagnosing noise about theta = -0.96."""
    from validation.diagnosis import diagnose
    from validation.diagnosis.steps import load_for_diagnosis

    rng = np.random.default_rng(4)
    t = np.arange(3000) / 1000.0
    for i in range(4):
        write_csv(tmp_path / f"run{i + 1:02d}.csv", t, *_levitated(t, rng, np.full(t.size, -0.96)))
    dataset = load_for_diagnosis(tmp_path, progress=False)
    assert not dataset.runs and len(dataset.skipped) == 4
    with pytest.raises(DatasetError, match=r"0 usable runs \(4 file\(s\) skipped, each with its reason above\)"):
        diagnose(dataset, progress=False)
