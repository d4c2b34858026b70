"""The held-out selection under model error (fitting.selection.support_search.select_heldout) on designs built directly as R
factors: its one-standard-error rule, and the tolerance below which a gain in held-out error counts as none."""
import numpy as np
import pytest

from fitting.model import TERMS
from fitting.selection.support_search import ReducedDesign, select_heldout

N_LIB = len(TERMS)
ROWS, RUNS = 2000, 10
STRONG, WEAK, SPARE = 3, 5, 7  # column 1 is forced; 3 and 5 carry signal, the rest is noise


def _design(weak: float, seed: int) -> ReducedDesign:
    """b = X_1 + 0.5 X_3 + weak X_5 + unit white noise over RUNS runs of ROWS rows of standard-normal columns."""
    rng = np.random.default_rng(seed)
    per_run = []
    for _ in range(RUNS):
        X = rng.standard_normal((ROWS, N_LIB))
        b = X[:, 1] + 0.5 * X[:, STRONG] + weak * X[:, WEAK] + rng.standard_normal(ROWS)
        per_run.append(np.linalg.qr(np.column_stack([X, b]), mode="r"))
    total = np.linalg.qr(np.vstack(per_run), mode="r")
    return ReducedDesign(per_run, np.full(RUNS, ROWS), np.zeros(RUNS, dtype=np.int64), total)


FORCED = np.zeros(N_LIB, bool)
FORCED[1] = True


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_consistent_gain_of_one_per_cent_is_kept_only_below_the_tolerance(seed):
    # the weak term lowers every run's held-out sum of squares by 0.1^2 = 1 % (+- 0.45 % per run, a paired standard
    # error over 10 runs of ~0.2 %); each noise column changes it by ~0.01-0.05 %, with standard errors as small
    d = _design(0.1, seed)
    rules = {tol: select_heldout(d, FORCED, velocity_first=False, tolerance=tol) for tol in (0.0, 0.003, 0.03)}
    # the one-standard-error rule alone keeps the weak term and, on some draws, noise columns whose tiny gains
    # exceed their tinier standard errors
    assert {1, STRONG, WEAK} <= set(rules[0.0][0])
    # a tolerance of 0.3 % drops the noise and keeps the 1 % term; one of 3 % drops it too
    assert sorted(rules[0.003][0]) == [1, STRONG, WEAK]
    assert sorted(rules[0.03][0]) == [1, STRONG]
    # the path runs from the full library to the forced term, and the full library's held-out error exceeds the
    # true support's (the 32 noise columns only add variance)
    sel, path, held = rules[0.003]
    assert len(path[0]) == N_LIB and path[-1] == [1] and np.all(np.isfinite(held))
    assert held[0] > held[path.index(sel)]


@pytest.mark.parametrize("seed", [1, 2])
def test_the_tolerance_never_drops_a_term_that_matters_more(seed):
    # a term worth 9 % of the held-out sum of squares (0.3^2) stays under the 3 % tolerance
    sel, _, _ = select_heldout(_design(0.3, seed), FORCED, velocity_first=False, tolerance=0.03)
    assert sorted(sel) == [1, STRONG, WEAK]


@pytest.mark.parametrize("seed", [1, 2])
@pytest.mark.parametrize("noise, keeps_weak", [(1.0, True), (0.1, False)])
def test_the_tolerance_is_a_share_of_the_misfit_above_the_noise(seed, noise, keeps_weak):
    # the design's misfit is unit white noise: told so (noise 1), nothing of it is model error and the tolerance
    # shrinks to ~0.2 % of itself, below the weak term's 1 %; told the noise is 0.1, 99 % of the misfit counts as
    # model error and the 3 % tolerance applies almost whole
    sel, _, _ = select_heldout(_design(0.1, seed), FORCED, velocity_first=False, tolerance=0.03, noise=noise)
    assert (WEAK in sel) is keeps_weak and {1, STRONG} <= set(sel)


@pytest.mark.parametrize("seed", [1, 2])
@pytest.mark.parametrize("rms_tolerance, keeps_weak", [(0.0, True), (0.002, True), (0.01, False)])
def test_the_users_practical_threshold_applies_under_model_error_too(seed, rms_tolerance, keeps_weak):
    # told the misfit is all noise, the model-error tolerance is ~0 and the rule keeps the weak term, whose 1 % of
    # the held-out sum of squares is 0.5 % of its RMS: a practical threshold of 0.2 % of the RMS keeps it, one of 1 %
    # drops it; the strong term (12 % of the RMS) stays under either
    sel, _, _ = select_heldout(_design(0.1, seed), FORCED, velocity_first=False, tolerance=0.03, noise=1.0,
                               rms_tolerance=rms_tolerance)
    assert (WEAK in sel) is keeps_weak and {1, STRONG} <= set(sel)
