"""Known-truth recovery (issue #4): synthetic data from the paper's reduced model.

One module-scoped fit of 10 noisy runs (1 um / 0.005 tracking noise, 1500 fps, 3 s) with the
default settings.  The claims are asserted at the issue's thresholds; where the pipeline is known
to miss them the test is marked xfail with the measured numbers (see docs/fitting.md), so it
turns into an XPASS as soon as the pipeline improves.
"""
import numpy as np
import pytest

from fitting.compare import paired_wilcoxon
from fitting.executor import ExecutorConfig
from fitting.pipeline import fit_dataset
from fitting.synthetic import SyntheticConfig, write_dataset

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def recovery(tmp_path_factory, truth):
    data = tmp_path_factory.mktemp("recovery_data")
    write_dataset(data, truth, SyntheticConfig(n_runs=10, seed=11))
    out = tmp_path_factory.mktemp("recovery_out")
    return fit_dataset(data, out, executor=ExecutorConfig(workers=2), plots=False, progress=False)


def test_refined_beat_regression_only_on_shape(recovery):
    c0 = [f.loss_c0.shape for f in recovery.run_fits]
    ref = [f.loss_refined.shape for f in recovery.run_fits]
    assert paired_wilcoxon(c0, ref).p_greater < 0.01


@pytest.mark.parametrize("q,term", [
    (0, "y"), (0, "1"), (1, "theta"), (1, "y"),
    pytest.param(1, "1", marks=pytest.mark.xfail(reason="measured: 11 % off on these 10 runs (3 % on 30 runs)",
                                                 )),
])
def test_strong_terms_recovered(recovery, truth, q, term):
    from fitting.model import TERMS
    j = TERMS.index(term)
    assert recovery.model.support[q, j]
    np.testing.assert_allclose(recovery.model.coef[q, j], truth.coef[q, j], rtol=0.10)  # the 10 %


@pytest.mark.xfail(reason="z-score rule (30 runs): y^2*theta and y*thetadot^2 missing (z 1.4, 1.2), ydot^2 spurious; "
                          "backward elimination (opt-in --selection backward, 30 runs, before the final joint fit): true support, "
                          "0 missing / 0 spurious; not yet measured on these 10 runs")
def test_true_support(recovery, truth):
    missing = (truth.support & ~recovery.model.support).sum()
    spurious = (recovery.model.support & ~truth.support).sum()
    assert missing == 0 and spurious <= 1


@pytest.mark.xfail(reason="measured (30 runs, backward elimination): y*ydot*thetadot 17 % off (pooled regression "
                          "25 %), all other true terms < 7 %; z-score rule: y^2 24 %, y*ydot*thetadot 26 %")
def test_coefficients_within_10_percent(recovery, truth):
    s = truth.support
    np.testing.assert_allclose(recovery.model.coef[s], truth.coef[s], rtol=0.10)
