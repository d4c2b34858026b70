"""The cubic library's names: monomials, their parsing and the coefficients' ``equation:term`` labels."""
import numpy as np
import pytest

from cubedimer.terms import (EQUATION_NAMES, coefficient_label, coefficient_labels, evaluate_library,
                             library_exponents, library_terms, parse_term)


def test_library_has_every_monomial_of_degree_three_once():
    # C(4 + 3, 3) = 35 monomials of degree <= 3 in four variables, all distinct
    exps = library_exponents(3)
    assert exps.shape == (35, 4)
    assert len({tuple(e) for e in exps}) == 35
    assert exps.sum(axis=1).max() == 3


@pytest.mark.parametrize("name", library_terms(3))
def test_parse_inverts_the_name(name):
    e = parse_term(name)
    np.testing.assert_array_equal(library_exponents(3)[library_terms(3).index(name)], e)


def test_library_columns_are_the_named_monomials():
    state = np.array([[2.0, 3.0, 5.0, 7.0]])
    cols = evaluate_library(state)[0]
    # y*theta^2 = 2 * 25, ydot^2*thetadot = 9 * 7, the constant 1
    for name, value in (("y*theta^2", 50.0), ("ydot^2*thetadot", 63.0), ("1", 1.0)):
        assert cols[library_terms(3).index(name)] == value


def test_coefficient_labels_match_the_coefficient_array():
    labels = coefficient_labels()
    assert labels.shape == (len(EQUATION_NAMES), 35)
    j = library_terms(3).index("y^2*theta")
    assert coefficient_label(1, j) == "thetaddot:y^2*theta" == labels[1, j]
    assert all(labels[q, k] == coefficient_label(q, k) for q in range(2) for k in range(35))
