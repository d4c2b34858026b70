import numpy as np
import pytest

from fitting.compare import cross_coupling_mask, drop_terms, paired_wilcoxon
from fitting.selection.ensemble import Z_CAP, select_terms, term_statistics
from fitting.model import TERMS, PolynomialModel


def _models(values_per_run):
    return [PolynomialModel.from_equations({"yddot": v, "thetaddot": {}}) for v in values_per_run]


def test_zscores_include_zeros():
    runs = [{"y": -1.0, "y^2": 1.0}, {"y": -1.2, "y^2": -1.0}, {"y": -0.8}, {"y": -1.0, "y^2": 0.5}]
    st = term_statistics(_models(runs))
    j = TERMS.index("y")
    c = np.array([-1.0, -1.2, -0.8, -1.0])
    np.testing.assert_allclose(st.zscore[0, j], abs(c.mean()) / c.std(ddof=1), rtol=1e-12)
    k = TERMS.index("y^2")
    c2 = np.array([1.0, -1.0, 0.0, 0.5])  # the missing run counts as 0
    np.testing.assert_allclose(st.zscore[0, k], abs(c2.mean()) / c2.std(ddof=1), rtol=1e-12)
    np.testing.assert_allclose(st.inclusion[0, k], 0.75)


def test_selection_keeps_damping_and_caps_constant_terms():
    st = term_statistics(_models([{"y": -1.0}, {"y": -1.0}, {"y": -1.0}]))
    assert st.zscore[0, TERMS.index("y")] == Z_CAP
    mask = select_terms(st)
    assert mask[0, TERMS.index("y")] and mask[0, TERMS.index("ydot")] and mask[1, TERMS.index("thetadot")]
    assert mask.sum() == 3


def test_wilcoxon_detects_systematic_difference():
    rng = np.random.default_rng(0)
    ref = rng.uniform(0.01, 0.02, 12)
    r = paired_wilcoxon(ref * 1.5, ref)
    assert r.p_greater < 0.001 and r.n == 12  # all 12 differences positive: exact p = 2^-12
    assert paired_wilcoxon(ref, ref).p_greater == 1.0


def test_drop_terms_and_cross_coupling(truth):
    cc = cross_coupling_mask(truth)
    names = {(q, TERMS[j]) for q, j in zip(*np.nonzero(cc))}
    assert names == {(1, "y"), (1, "y^2*theta"), (1, "y*ydot*thetadot"), (1, "y*thetadot^2")}
    v = drop_terms(truth, ["thetaddot:y^2*theta", "1"])
    assert not v.support[1, TERMS.index("y^2*theta")] and not v.support[:, 0].any()
    with pytest.raises(ValueError):
        drop_terms(truth, ["thetaddot:q"])
