"""The mesh-convergence judgement of the full-wave hinge (the study itself runs outside the test suite:
``python -m acousim convergence --study mesh``, results in docs/fullwave.md)."""
from __future__ import annotations

import numpy as np
import pytest

from acousim.fullwave.convergence import CONVERGED_WITHIN, judge_convergence, richardson_limit


def test_second_order_sequence_is_converged():
    """s(h) = s0 (1 + c h^2) on h = 1, 1/1.4, 1/1.4^2: monotone, order 2, finest levels 1.5 % apart."""
    h = 1.4 ** -np.arange(3)
    v = -1e-8 * (1 + 0.06 * h**2)
    verdict = judge_convergence(v, 1.4)
    assert verdict["monotone"] and np.isclose(verdict["order"], 2.0) and verdict["converged"]
    assert verdict["finest_difference"] < CONVERGED_WITHIN


def test_three_measured_levels_at_a_wide_gap_look_converged():
    """The measured momentum-flux stiffness at g = 0.04 s (mesh_family q = 0.7, 0.5, 0.35; docs/fullwave.md):
    corrections +6.2 % then +0.42 %, monotone, the finest two levels within 2 %: the judgement of these three levels
    (the next test shows why three levels are not the end of the story)."""
    verdict = judge_convergence([-3.0059e-10, -3.2050e-10, -3.2185e-10], 1.4)
    assert verdict["monotone"] and verdict["order"] > 1 and verdict["converged"]
    np.testing.assert_allclose(verdict["corrections"], [0.0621, 0.0042], atol=2e-4)


def test_more_measured_levels_at_g_0p05_are_not_converged():
    """The shipped family's row g/s = 0.05 (mesh_convergence.json, q = 1.4 ... 0.4): its first three levels look
    converged (+6.6 %, +0.24 %), the fourth adds +1.97 %, so the whole sequence is not monotone."""
    k = [-2.6425e-10, -2.8301e-10, -2.8368e-10, -2.8928e-10, -2.9041e-10]
    assert judge_convergence(k[:3], 1.4)["converged"]
    verdict = judge_convergence(k, 1.4)
    assert not verdict["monotone"] and not verdict["converged"]
    np.testing.assert_allclose(verdict["corrections"], [0.0663, 0.0024, 0.0194, 0.0039], atol=2e-4)


def test_measured_surface_traction_hinge_is_not_converged():
    """The surface-traction stiffness at g = 0.01 s (q = 0.7, 0.5, 0.35; docs/fullwave.md) is not: the corrections
    (-0.7 %, then -7.6 %) grow."""
    verdict = judge_convergence([-9.880e-09, -9.811e-09, -9.115e-09], 1.4)
    assert not verdict["monotone"] and verdict["order"] < 0 and not verdict["converged"]
    np.testing.assert_allclose(verdict["corrections"], [-0.0070, -0.0764], atol=1e-4)


def test_needs_three_levels():
    with pytest.raises(ValueError):
        judge_convergence([1.0, 1.1], 1.4)


@pytest.mark.parametrize("order", [0.7, 1.3, 2.0])
def test_richardson_limit_recovers_a_power_law_on_unequal_levels(order):
    """v(q) = v0 (1 + 0.05 q^p) on q = 1, 0.7, 0.5, 0.35: the limit and the order are recovered to rounding, and the
    finest level is predicted exactly from the three before it."""
    q = np.array([1.0, 0.7, 0.5, 0.35])
    v = -2.9e-10 * (1 + 0.05 * q**order)
    fit = richardson_limit(q, v)
    # three equations, three unknowns solved by a root finder to 1e-12 in p: rounding-level agreement
    np.testing.assert_allclose(fit["limit"], -2.9e-10, rtol=1e-9)
    np.testing.assert_allclose(fit["order"], order, rtol=1e-8)
    np.testing.assert_allclose(fit["finest_error"], 0.05 * 0.35**order, rtol=1e-6)
    assert fit["prediction_error"] < 1e-10


@pytest.mark.parametrize("values", [[1.0, 1.1, 1.3], [1.0, 1.1, 1.05], [1.0, 1.0, 1.1]])
def test_richardson_limit_refuses_corrections_that_do_not_shrink(values):
    """Growing, sign-changing or zero-then-nonzero corrections have no positive order: no limit is claimed."""
    with pytest.raises(ValueError, match="do not shrink"):
        richardson_limit([1.0, 0.7, 0.5], values)


def test_edge_graded_levels_at_g_0p05_converge_and_predict_their_finest_level():
    """The measured stiffness at g/s = 0.05 on meshes graded towards every edge (q = 1, 0.7, 0.5, 0.35;
    mesh_convergence.json): monotone corrections (+0.99, +0.72, +0.45 %), the fit through the three coarser levels
    predicts the finest within 0.2 % of the limit, and the family's node mesh (-2.830e-10 N m) lies more than 2 %
    from the limit, the finest level within 1 %."""
    q = [1.0, 0.7, 0.5, 0.35]
    k = [-2.8528e-10, -2.8813e-10, -2.9022e-10, -2.9154e-10]
    assert judge_convergence(k, 1.42)["monotone"]
    fit = richardson_limit(q, k)
    assert fit["prediction_error"] < 2e-3
    assert fit["finest_error"] < 0.01
    assert abs(-2.8301e-10 / fit["limit"] - 1) > CONVERGED_WITHIN


def test_richardson_limit_without_an_asymptotic_coarse_triple_makes_no_prediction():
    """The measured g/s = 0.01 edge-graded levels (q = 1.4, 1, 0.7, 0.5): q = 1.4 and 1 agree to 0.01 %, so the three
    coarser levels have no power law and nothing is predicted; the finest three do (+0.73 %, +0.26 %), order > 2."""
    fit = richardson_limit([1.4, 1.0, 0.7, 0.5], [-5.5098e-10, -5.5104e-10, -5.5504e-10, -5.5650e-10])
    assert fit["predicted_finest"] is None and fit["prediction_error"] is None
    assert fit["order"] > 2 and fit["finest_error"] < 0.005


@pytest.mark.parametrize("args,message", [
    (["--study", "gap", "--levels", "1"], "only a mesh study"),
    (["--study", "mesh", "--mesh-rule", "family", "--levels", "1,0.7,0.5"], "only a mesh study"),
    (["--study", "mesh", "--mesh-rule", "family-edges", "--levels", "1,0.7"], "at least three"),
    (["--study", "mesh", "--mesh-rule", "family-edges", "--levels", "1,0.7,0.5", "--family-level", "0.6"],
     "--family-level 0.6"),
])
def test_merge_into_refuses_what_it_cannot_merge_before_any_solve(tmp_path, capsys, args, message):
    from acousim.cli import main

    out, record = tmp_path / "study.jsonl", tmp_path / "mesh_convergence.json"
    code = main(["convergence", *args, "--out", str(out), "--merge-into", str(record)])
    err = capsys.readouterr().err
    assert code != 0 and message in err and len(err.strip().splitlines()) == 1
    assert not out.exists() and not record.exists()
