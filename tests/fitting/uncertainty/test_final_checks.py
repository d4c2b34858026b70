"""The fallback's chain of reduced models: which terms go first."""
import numpy as np
import pytest

from cubedimer.terms import coefficient_labels
from fitting.selection.ensemble import term_statistics
from fitting.uncertainty.final_checks import fallback_candidates
from fitting.model import PolynomialModel, damping_mask

#: a hinge-like model: both equations' stiffness and damping plus three couplings of the hinge
SUPPORT = {"yddot": {"y": -1.0e5, "ydot": -0.5, "y^3": 2.0e9},
           "thetaddot": {"theta": -6.0e4, "thetadot": -0.4, "y*theta": -8.0e6, "y^2*theta": 5.0e10,
                         "y*theta^2": 3.0e6}}


@pytest.fixture
def model() -> PolynomialModel:
    return PolynomialModel.from_equations(SUPPORT)


def _at(label: str) -> tuple[int, int]:
    """(equation, term) index of an ``equation:term`` label."""
    return tuple(np.argwhere(coefficient_labels() == label)[0])


def _per_run(model: PolynomialModel, spread: dict[str, float], n: int = 8, seed: int = 0) -> list[PolynomialModel]:
    """Per-run models scattered about ``model`` by a relative spread per ``equation:term`` (default 1 %)."""
    rng = np.random.default_rng(seed)
    rel = np.full(model.coef.shape, 0.01)
    for label, s in spread.items():
        rel[_at(label)] = s
    return [PolynomialModel(model.coef * (1 + rel * rng.standard_normal(model.coef.shape))) for _ in range(n)]


def _dropped(candidates) -> list[str]:
    """The terms each 'minimal model without ...' candidate removes, in the chain's order."""
    chain = [name for name, _ in candidates if name.startswith("minimal model without ")]
    return chain[-1].removeprefix("minimal model without ").split(", ")


def test_own_z_orders_the_chain_and_damping_stays(model):
    # per-run p-values call y*theta^2 the weakest (spread 300 % across runs: collinear with y^2*theta);
    # the pooled z calls it the strongest of the couplings
    stats = term_statistics(_per_run(model, {"thetaddot:y*theta^2": 3.0, "yddot:y^3": 0.5}))
    z = np.zeros(model.coef.shape)
    for label, value in {"yddot:y": 900, "yddot:ydot": 2.0, "yddot:y^3": 40, "thetaddot:theta": 800,
                         "thetaddot:thetadot": 1.5, "thetaddot:y*theta": 3.0, "thetaddot:y^2*theta": -6.0,
                         "thetaddot:y*theta^2": 25}.items():
        z[_at(label)] = value
    by_p = _dropped(fallback_candidates(model, model.support, stats, [], None))
    by_z = _dropped(fallback_candidates(model, model.support, stats, [], None, z=z))
    assert by_p[0] == "thetaddot:y*theta^2"
    # smallest |z| first; the damping terms (z 2.0 and 1.5, the smallest) are never dropped
    assert by_z == ["thetaddot:y*theta", "thetaddot:y^2*theta", "thetaddot:y*theta^2", "yddot:y^3", "thetaddot:theta"]
    assert not any(t in ("yddot:ydot", "thetaddot:thetadot") for t in by_z)


def test_candidates_zero_the_dropped_terms_and_keep_the_rest(model):
    stats = term_statistics(_per_run(model, {}))
    cands = [m for name, m in fallback_candidates(model, model.support, stats, [], None)
             if name.startswith("minimal model")]
    n_removable = int((model.support & ~damping_mask()).sum())
    # k = 1 .. n-1 terms dropped: at least one removable term always stays
    assert len(cands) == n_removable - 1
    for k, m in enumerate(cands, start=1):
        assert int(m.support.sum()) == int(model.support.sum()) - k
        np.testing.assert_array_equal(m.coef[m.support], model.coef[m.support])  # the kept values unchanged
        assert np.all(m.support[damping_mask()])


#: model.json of a discovery whose polished 5-term model blew up on 2 of 8 runs and whose fallback of 3 terms is written
FALLBACK_RECORD = {
    "equations": {"yddot": {"y": -1.9e4, "ydot": -0.6}, "thetaddot": {"theta": -110.0}},
    "fallback": {"reason": "the re-optimised minimal model (5 terms) blows up on 2 of 8 runs",
                 "used": "minimal model without thetaddot:y^2*theta, yddot:y^3", "order": "z",
                 "candidates": [{"name": "a", "loss": 190.0, "blown_up_runs": 2, "n_terms": 5},
                                {"name": "b", "loss": 0.3, "blown_up_runs": 0, "n_terms": 4},
                                {"name": "c", "loss": 0.2, "blown_up_runs": 0, "n_terms": 3}],
                 "blown_up_model": {"equations": {"yddot": {"y": -1.9e4, "ydot": -0.6, "y^3": 1e9},
                                                  "thetaddot": {"theta": -110.0, "y^2*theta": 2e8}},
                                    "loss": {"total": 500.0, "blown_up": True}}},
    "settings": {"discovery": {"keep_damping": True}},
}


def test_the_report_says_the_written_model_is_a_fallback():
    from fitting.methods.discovery import discovery_description

    text = discovery_description(FALLBACK_RECORD).text
    # the blown-up model's size, why it was not written, what was written instead and how many candidates held
    assert "gave a model of 5 terms. That model was not written: the re-optimised minimal model (5 terms) blows up " \
           "on 2 of 8 runs. The model written (3 terms) is its fallback" in text
    assert "(2 of 3; terms dropped with the smallest z of the fit first)" in text
    assert "minimal model without thetaddot:y^2*theta, yddot:y^3, re-optimised jointly" in text
    assert "gives a model of" not in text  # the discovery did not give the model written
    no_fallback = discovery_description({**FALLBACK_RECORD, "fallback": None}).text
    assert "gives a model of 3 terms" in no_fallback and "fallback" not in no_fallback
