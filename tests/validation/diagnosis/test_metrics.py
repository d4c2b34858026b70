"""The gap components: each computes what it describes, and gap_definition names the form each one uses."""
import numpy as np
import pytest

from validation.diagnosis import Calibration, DiagnosisProblem, GapFit
from validation.diagnosis.calibrate.gap_model import EnergyResidual, IntegralResidual, fit_gap_model
from validation.diagnosis.calibrate.metrics import (fit_components, fit_gaps, gap_components, gap_definition,
                                                    short_time_gaps)
from validation.diagnosis.prepare.runs import RunAccelerations


def _runs_and_residuals(seed=0, n_runs=3, n=200):
    rng = np.random.default_rng(seed)
    runs = [RunAccelerations(f"r{i}", np.arange(n) * 1e-3, rng.normal(size=(n, 4)), rng.normal(size=(n, 2)),
                             np.array([0.01, 0.02, 0.0, 0.0])) for i in range(n_runs)]
    residuals = [0.3 * rng.normal(size=(n, 2)) for _ in runs]
    energy = [EnergyResidual(rng.normal(size=10), 1 + rng.random(10), 0.05) for _ in runs]
    integral = [IntegralResidual(0.1 * rng.normal(size=150), 4.0, 0.2) for _ in runs]
    return runs, residuals, energy, integral


def test_definition_names_the_integral_form_where_it_is_used():
    integral = gap_definition(gap_components(integral_theta=True))
    assert "yddot (acceleration form)" in integral and "thetaddot (integral form)" in integral
    assert "energy (energy balance form)" in integral and "thetaddot (acceleration form)" not in integral
    accel = gap_definition(gap_components(integral_theta=False))
    assert "thetaddot (acceleration form)" in accel and "integral form" not in accel
    assert [c.name for c in gap_components(True)] == ["yddot", "thetaddot", "energy"]  # diagnosis.json gap_components


def test_components_compute_what_they_describe():
    runs, residuals, energy, integral = _runs_and_residuals()
    with_integral = short_time_gaps(runs, residuals, energy, integral=integral)
    without = short_time_gaps(runs, residuals, energy)
    for q, comp in enumerate(gap_components(True)):
        np.testing.assert_array_equal(with_integral[:, q], comp.per_run(runs, residuals, energy, integral, True))
    # theta: the integral form's formula, sum r^2 minus its floor over the detrended theta's sum of squares
    expected = [(np.sum(ir.residual**2) - ir.floor) / ir.norm for ir in integral]
    np.testing.assert_allclose(with_integral[:, 1], expected, rtol=1e-12)  # same arithmetic up to round-off
    # y and energy do not depend on the theta form; theta without integral data is the acceleration form
    np.testing.assert_array_equal(with_integral[:, [0, 2]], without[:, [0, 2]])
    r, e = runs[0], residuals[0]
    var = np.sum((r.accel[:, 1] - r.accel[:, 1].mean()) ** 2)
    assert without[0, 1] == pytest.approx((np.sum(e[:, 1] ** 2) - len(r.t) * r.noise[1]) / var, rel=1e-12)
    assert not np.allclose(with_integral[:, 1], without[:, 1])


def test_a_fit_reports_the_components_it_computed(fast_model, synthetic_runs):
    """A fit on runs without integral data uses (and names) the acceleration form for theta; with
    integral residuals the same fit's theta component is the integral one."""
    truth = Calibration.at(fast_model, 1.0, fast_model.equilibrium_height)
    runs = synthetic_runs(fast_model, truth, {}, n_runs=3, duration=0.6, seed=5)
    fit = fit_gap_model(DiagnosisProblem(fast_model, runs), [], fixed=truth)
    assert fit.integral is None and fit_components(fit)[1].form == "acceleration"
    _, _, _, integral = _runs_and_residuals(n_runs=3)
    with_integral = GapFit(fit.calibration, fit.effects, fit.residuals, fit.predicted, fit.energy, integral)
    assert fit_components(with_integral)[1].form == "integral"
    np.testing.assert_array_equal(fit_gaps(runs, with_integral)[:, 1],
                                  fit_components(with_integral)[1].per_run(runs, fit.residuals, fit.energy, integral, True))
