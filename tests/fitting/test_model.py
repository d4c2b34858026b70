import json

import numpy as np
import pytest

from cubedimer.terms import evaluate_library
from fitting.model import TERMS, PolynomialModel, Scales


def test_json_roundtrip(truth):
    d = json.loads(json.dumps(truth.to_json()))
    assert d["state"] == ["y", "ydot", "theta", "thetadot"] and d["units"] == "SI"
    back = PolynomialModel.from_json(d)
    np.testing.assert_array_equal(back.coef, truth.coef)  # exact: JSON floats round-trip


def test_from_equations_accepts_any_factor_order():
    m = PolynomialModel.from_equations({"thetaddot": {"theta*y^2": 2.0, "thetadot*ydot*y": 3.0}})
    assert m.equations()["thetaddot"] == {"y^2*theta": 2.0, "y*ydot*thetadot": 3.0}


@pytest.mark.parametrize("bad", [{"yddot": {"z": 1.0}}, {"yddot": {"y^4": 1.0}}, {"xddot": {"y": 1.0}}])
def test_bad_equations_raise(bad):
    with pytest.raises(ValueError):
        PolynomialModel.from_equations(bad)


def test_predict_matches_library(truth):
    x = np.random.default_rng(0).normal(size=(20, 4)) * [1e-4, 1e-2, 0.2, 10]
    np.testing.assert_allclose(truth.predict(x), evaluate_library(x) @ truth.coef.T, rtol=1e-12)


def test_scales_roundtrip_and_meaning(truth):
    s = Scales(1.2e-4, 0.25, 0.007)
    np.testing.assert_allclose(s.to_si(s.to_scaled(truth.coef)), truth.coef, rtol=1e-12)
    # scaled accelerations of scaled states equal SI accelerations divided by the scale
    x = np.array([[5e-5, 1e-2, 0.1, 3.0]])
    a_si = truth.predict(x)
    a_sc = evaluate_library(x / s.state) @ s.to_scaled(truth.coef).T
    np.testing.assert_allclose(a_sc, a_si / s.accel, rtol=1e-10)


def test_model_is_frozen(truth):
    with pytest.raises((AttributeError, ValueError)):
        truth.coef[0, 0] = 1.0
    assert len(TERMS) == 35
