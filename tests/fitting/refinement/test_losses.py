import numpy as np
import pytest

from fitting.refinement.losses import LossWeights, loss_terms, make_reference, rest_model_terms


@pytest.fixture
def ref(clean_runs):
    r = clean_runs[0]
    return make_reference(r["t"], r["state"])


def test_perfect_model_scores_zero(ref):
    lt = loss_terms(ref.state.copy(), ref.n, ref)
    assert lt.shape == 0.0 and lt.poincare == 0.0 and lt.frequency == 0.0 and not lt.blown_up


def test_rest_model_normalisation(ref):
    lt = rest_model_terms(ref)
    assert lt.frequency == 1.0  # exact by construction
    np.testing.assert_allclose(lt.poincare, 1.0, rtol=1e-12)  # exact up to rounding
    r2 = np.sum((ref.state / ref.norm) ** 2, axis=1)
    # exact formula (the data-to-simulation half uses every ref.sub-th data point)
    np.testing.assert_allclose(lt.shape, 0.5 * (r2.min() + r2[:: ref.sub].mean()) / r2.mean(), rtol=1e-12)


def test_loss_grows_with_frequency_error(ref, truth):
    from fitting.model import TERMS, PolynomialModel
    vals = []
    for f in (1.0, 1.01, 1.05):
        c = truth.coef.copy()
        c[0, TERMS.index("y")] *= f**2
        s, n = PolynomialModel(c).simulate(ref.x0, ref.t)
        vals.append(loss_terms(s, n, ref))
    assert vals[0].total < vals[1].total < vals[2].total
    np.testing.assert_allclose(vals[2].frequency, 0.5 * 0.05**2, rtol=0.3)  # r_y ~ 5 %; spectral peak accuracy ~1 %


def test_blow_up_penalty_finite_and_ordered(ref):
    w = LossWeights()
    early = loss_terms(np.full_like(ref.state, np.nan), 10, ref, w)
    late = loss_terms(np.full_like(ref.state, np.nan), ref.n - 10, ref, w)
    assert early.blown_up and np.isfinite(early.total)
    assert early.total > late.total >= w.penalty
