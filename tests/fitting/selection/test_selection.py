"""Unit tests of the joint-loss term selection (fitting.selection.backward_elimination) and its pipeline fallback."""
import numpy as np

from fitting.model import DAMPING_TERMS, TERMS, damping_mask
from fitting.config import FitConfig, PaperMethodConfig
from fitting.output.model_file import model_json
from fitting.selection.rules import SelectionConfig


def test_damping_mask_has_the_two_viscous_terms():
    m = damping_mask()
    assert m.sum() == 2
    assert m[0, TERMS.index(DAMPING_TERMS["yddot"])] and m[1, TERMS.index(DAMPING_TERMS["thetaddot"])]


def test_default_rule_is_significance_and_the_others_are_available():
    # the significance of the ensemble mean is the default; the paper's z-rule and backward elimination are options
    assert FitConfig.for_method("paper").method.selection.rule == "significance"
    assert SelectionConfig(rule="backward").rule == "backward"
    assert SelectionConfig(rule="zscore").rule == "zscore"


def test_too_few_runs_for_wilcoxon_fall_back_to_zscore_rule(small_dataset, tmp_path):
    """3 runs: the one-sided Wilcoxon test cannot reach p < 0.01 (min p = 1/8), so the paper's rule is used."""
    from fitting.fit import fit_dataset
    from fitting.refinement.long_time import RefineConfig

    cfg = FitConfig(method=PaperMethodConfig(
        refine=RefineConfig(max_evals=60), joint=RefineConfig(max_evals=40, rel_bound=0.3, abs_bound=0.005),
        selection=SelectionConfig(rule="backward")))
    res = fit_dataset(small_dataset, config=cfg, progress=False)
    assert res.extras.selection is None
    np.testing.assert_array_equal(res.mask, res.extras.mask_zscore)
    assert model_json(res)["selection"]["rule"] == "zscore"


def _stats_from(coefs):
    from fitting.selection.ensemble import term_statistics
    from fitting.model import PolynomialModel

    return term_statistics([PolynomialModel(c) for c in coefs])


def test_mean_pvalues_equal_the_one_sample_t_test(rng):
    from scipy.stats import ttest_1samp

    from fitting.selection.ensemble import mean_pvalues

    coefs = np.zeros((12, 2, len(TERMS)))
    coefs[:, 0, 1] = rng.normal(1.0, 2.0, 12)    # weak: mean 1, spread 2
    coefs[:, 1, 3] = rng.normal(-5.0, 1.0, 12)   # strong
    p = mean_pvalues(_stats_from(coefs))
    for q, j in ((0, 1), (1, 3)):
        np.testing.assert_allclose(p[q, j], ttest_1samp(coefs[:, q, j], 0.0).pvalue, rtol=1e-10)  # same statistic
    assert p[0, 0] == 1.0  # absent from every run: not tested


def test_significance_rule_keeps_a_weak_consistent_term_that_the_z_rule_drops(rng):
    """A term with per-run z = mean/std ~ 1.5 is significant as a mean over 30 runs (t ~ 8); a pure-noise term
    is not, and the Holm correction keeps the family-wise error at alpha."""
    from fitting.selection.ensemble import EnsembleConfig, select_significant_terms, select_terms

    coefs = np.zeros((30, 2, len(TERMS)))
    coefs[:, 1, 5] = rng.normal(1.5, 1.0, 30)   # weak but consistent
    coefs[:, 1, 7] = rng.normal(0.0, 1.0, 30)   # noise
    coefs[:, 0, 1] = rng.normal(10.0, 1.0, 30)  # strong
    stats = _stats_from(coefs)
    sig = select_significant_terms(stats, alpha=0.01)
    z = select_terms(stats, EnsembleConfig())
    assert sig[1, 5] and not z[1, 5]
    assert sig[0, 1] and z[0, 1]
    assert not sig[1, 7]
    assert sig.sum() == 2 + 2  # the two real terms and the two damping terms


def test_holm_family_wise_error_on_pure_noise():
    """300 data sets of 34 noise terms over 20 runs: the fraction with any term selected stays <= alpha (+ MC error)."""
    from fitting.selection.ensemble import select_significant_terms

    rng = np.random.default_rng(7)
    hits = 0
    for _ in range(300):
        coefs = rng.normal(0.0, 1.0, (20, 2, len(TERMS))) * (~damping_mask())
        hits += int((select_significant_terms(_stats_from(coefs), alpha=0.05) & ~damping_mask()).any())
    # Holm controls the family-wise error at 0.05; 3 binomial standard errors of 300 draws = 0.038
    assert hits / 300 <= 0.05 + 0.038
