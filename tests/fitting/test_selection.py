"""Unit tests of the joint-loss term selection (fitting.selection) and its pipeline fallback."""
import numpy as np

from fitting.model import DAMPING_TERMS, TERMS
from fitting.pipeline import FitConfig, model_json
from fitting.selection import SelectionConfig, damping_mask


def test_damping_mask_has_the_two_viscous_terms():
    m = damping_mask()
    assert m.sum() == 2
    assert m[0, TERMS.index(DAMPING_TERMS["yddot"])] and m[1, TERMS.index(DAMPING_TERMS["thetaddot"])]


def test_default_rule_is_the_papers_and_backward_is_available():
    # the paper's z > 3 rule is the default; backward elimination is opt-in until its wall time is measured
    assert FitConfig().selection.rule == "zscore"
    assert SelectionConfig(rule="backward").rule == "backward"


def test_too_few_runs_for_wilcoxon_fall_back_to_zscore_rule(small_dataset, tmp_path):
    """3 runs: the one-sided Wilcoxon test cannot reach p < 0.01 (min p = 1/8), so the paper's rule is used."""
    from fitting.pipeline import fit_dataset
    from fitting.refine import RefineConfig

    cfg = FitConfig(refine=RefineConfig(max_evals=60), joint=RefineConfig(max_evals=40, rel_bound=0.3, abs_bound=0.005),
                    selection=SelectionConfig(rule="backward"))
    res = fit_dataset(small_dataset, tmp_path, config=cfg, plots=False, progress=False)
    assert res.selection is None
    np.testing.assert_array_equal(res.mask, res.mask_zscore)
    assert model_json(res)["selection"]["rule"] == "zscore"
