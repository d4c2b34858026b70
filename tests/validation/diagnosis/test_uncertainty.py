"""Standard errors and 95 % intervals of the diagnosis (the delete-one-run jackknife): their size against the
scatter of the estimates over seeds of synthetic data with known truth, their coverage on a small fixed study, and
"not determined" where the data give no finite interval."""

import numpy as np
import pytest

from validation.diagnosis import Calibration, DiagnosisProblem
from validation.diagnosis.calibrate.gap_model import fit_gap_model
from validation.diagnosis.summarise.uncertainty import (ParameterInterval, format_with_error, interval_from_error,
                                                        jackknife_errors)

#: the truth of the fixed study: pair scattering and a weak linear damping at a pressure 5 % above nominal
EFFECTS = {"pair_scattering": {"kappa": 1.2e4}, "linear_damping": {"gamma_y": 0.5, "gamma_theta": 0.5}}
SEEDS = range(100, 110)


@pytest.fixture(scope="module")
def fixed_study(fast_model):
    """10 seeds of 8 runs of 1.6 s: per seed, each parameter's interval (and the pressure's) and its truth."""
    from .conftest import _synthetic_runs

    truth = Calibration.at(fast_model, 1.05**2, fast_model.equilibrium_height)
    names = list(EFFECTS)
    out = {"kappa": [], "gamma_y": [], "gamma_theta": [], "pressure": []}
    for seed in SEEDS:
        runs = _synthetic_runs(fast_model, truth, EFFECTS, n_runs=8, duration=1.6, seed=seed, known_noise=True)
        problem = DiagnosisProblem(fast_model, runs)
        fit = fit_gap_model(problem, names)
        errors = jackknife_errors(problem, names, fit.effects, fit.calibration)
        for e, ps in EFFECTS.items():
            for p, v in ps.items():
                out[p].append((errors.effects[e][p], v))
        out["pressure"].append((errors.calibration["pressure_amplitude_pa"], truth.pressure_amplitude_pa))
    return out


@pytest.mark.parametrize("name", ["kappa", "gamma_y", pytest.param("gamma_theta", marks=pytest.mark.xfail(
    strict=True, reason="gamma_theta lies 1.2 SE (2-3 %) low on average: a bias the jackknife does not measure")),
    "pressure"])
def test_stated_errors_match_the_scatter_over_seeds(fixed_study, name):
    """The error of each estimate in units of its stated error, z = (estimate - truth) / SE, over the 10 seeds.  With
    a correct error z follows Student's t with 7 degrees of freedom, whose median |t| is 0.71; the median of 10
    draws of |t| lies within 0.35-1.35 with probability 0.99 (its order statistics).  Measured: kappa 0.36, gamma_y
    0.50, the pressure 0.39; gamma_theta 1.35, its estimates 1.2 SE low on average (a bias of 2-3 % that the
    jackknife does not measure: a known limitation, docs/diagnosis.md)."""
    z = np.array([(iv.value - truth) / iv.std_error for iv, truth in fixed_study[name]])
    assert 0.35 <= np.median(np.abs(z)) <= 1.35, (name, z)


def test_interval_coverage_on_a_fixed_study(fixed_study):
    """Coverage of the 95 % intervals: 40 intervals (4 numbers x 10 seeds).  Measured: 37 of 40 (kappa 10, gamma_y 9,
    gamma_theta 9, the pressure 9 of 10).  At a true coverage of 95 %, 35 or fewer of 40 has a probability of 5 %; at
    80 % (intervals too narrow by a factor of about 1.6), 36 or more has 8 %."""
    covered = [iv.covers(truth) for rows in fixed_study.values() for iv, truth in rows]
    assert all(iv.determined for rows in fixed_study.values() for iv, _ in rows)
    assert sum(covered) >= 36, sum(covered)
    for name, rows in fixed_study.items():  # no number's intervals miss more than 2 of 10
        assert sum(iv.covers(t) for iv, t in rows) >= 8, name


def test_interval_is_the_t_quantile_times_the_error():
    """95 % with 7 degrees of freedom: t = 2.3646 (tables)."""
    iv = interval_from_error(10.0, 1.0, 7)
    np.testing.assert_allclose(iv.interval_95, (10 - 2.3646, 10 + 2.3646), atol=1e-4)
    assert iv.covers(12.3) and not iv.covers(12.4)


@pytest.mark.parametrize("error, dof, reason", [
    (1.0, 0, "fewer than two runs"), (0.0, 7, "no spread"), (float("inf"), 7, "non-finite"),
    (float("nan"), 7, "non-finite")])
def test_no_finite_interval_is_not_determined(error, dof, reason):
    iv = interval_from_error(3.0, error, dof)
    assert not iv.determined and iv.interval_95 is None and reason in iv.reason
    assert not iv.covers(3.0)
    assert "not determined" in iv.format()


def test_too_few_runs_give_no_interval(fast_model, synthetic_runs):
    """Two runs: the jackknife has one refit per run and one degree of freedom left out of two, below the three runs
    an interval is made from; every number says so instead of giving an error."""
    truth = Calibration.at(fast_model, 1.0, fast_model.equilibrium_height)
    runs = synthetic_runs(fast_model, truth, EFFECTS, n_runs=2, duration=0.8, seed=7)
    problem = DiagnosisProblem(fast_model, runs)
    fit = fit_gap_model(problem, ["pair_scattering"])
    errors = jackknife_errors(problem, ["pair_scattering"], fit.effects, fit.calibration)
    for iv in [errors.effects["pair_scattering"]["kappa"], *errors.calibration.values()]:
        assert not iv.determined and "at least 3 runs" in iv.reason


@pytest.mark.parametrize("value, error, text", [
    (19512.3, 213.0, "1.951e4 +- 0.021e4"), (3000.79, 0.075, "3000.790 +- 0.075"), (0.0987, 0.0031, "0.0987 +- 0.0031"),
    (-1.92, 0.4, "-1.92 +- 0.40"), (1.2e-4, 3e-6, "1.200e-4 +- 0.030e-4")])
def test_value_with_error_text(value, error, text):
    assert format_with_error(value, error) == text


def test_interval_round_trips_through_json():
    iv = interval_from_error(2.0, 0.5, 9)
    assert ParameterInterval.from_dict(iv.to_dict()) == iv
