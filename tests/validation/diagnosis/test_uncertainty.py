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


# --- the statistics layer alone: many cheap least-squares problems of known truth --------------------------------

#: the regression problems: slope and offset of 10 runs whose rows carry AR(1) noise (rho = 0.9), as the integral
#: form's overlapping windows and the coloured Savitzky-Golay accelerations do, at unequal lengths and amplitudes
REGRESSION_TRUTH = np.array([1.0, -0.5])
REGRESSION_PROBLEMS = 400
#: the shared systematic slope error of the third study: about 4 times the slope's statistical error (3.9 %, median)
SYSTEMATIC = 0.15


def _regression_runs(rng, n_runs=10, rho=0.9, systematic=0.0):
    """Runs of ``y = a x + b`` with AR(1) noise; ``systematic``: every run's slope off by that fraction (a model
    error shared by all runs, which the scatter over runs cannot see)."""
    from scipy.signal import lfilter

    xs, ys = [], []
    for _ in range(n_runs):
        n = int(rng.integers(80, 240))
        t = np.arange(n) * 0.01
        x = np.column_stack([rng.uniform(0.3, 2.0) * np.sin(2 * np.pi * rng.uniform(1, 3) * t + rng.uniform(0, 6.3)),
                             np.ones(n)])
        noise = lfilter([np.sqrt(1 - rho**2)], [1, -rho], rng.normal(size=n))
        xs.append(x)
        ys.append(x @ (REGRESSION_TRUTH * [1 + systematic, 1]) + 0.5 * noise)
    return xs, ys


def _least_squares(xs, ys):
    a, y = np.vstack(xs), np.concatenate(ys)
    return np.linalg.lstsq(a, y, rcond=None)[0], a, y


@pytest.fixture(scope="module")
def regression_study():
    """Per problem (seeded): the slope's jackknife interval and whether the rows' least-squares covariance
    ``s^2 (A^T A)^-1`` (rows taken as independent) gives an interval holding the truth; exact and with a shared
    systematic slope error (:data:`SYSTEMATIC`)."""
    from scipy import stats

    from validation.diagnosis.summarise.uncertainty import jackknife_interval

    out = {}
    for systematic in (0.0, SYSTEMATIC):
        rng = np.random.default_rng(62)
        rows = []
        for _ in range(REGRESSION_PROBLEMS):
            xs, ys = _regression_runs(rng, systematic=systematic)
            coef, a, y = _least_squares(xs, ys)
            r = len(xs)
            loo = np.array([_least_squares(xs[:i] + xs[i + 1:], ys[:i] + ys[i + 1:])[0][0] for i in range(r)])
            resid = y - a @ coef
            naive_se = np.sqrt(resid @ resid / (len(y) - 2) * np.linalg.inv(a.T @ a)[0, 0])
            rows.append((jackknife_interval(coef[0], loo),
                         abs(coef[0] - REGRESSION_TRUTH[0]) <= stats.norm.ppf(0.975) * naive_se))
        out[systematic] = rows
    return out


def test_jackknife_intervals_cover_95_percent_with_correlated_rows(regression_study):
    """400 problems: at a true coverage of 95 % the count of intervals holding the truth lies within 369-390 with
    probability 0.99 (binomial 0.5 % and 99.5 % quantiles: 368 and 390); at 90 % it reaches 369 with probability
    0.07.  Measured: 388 (0.97; the jackknife of a least-squares slope is slightly conservative)."""
    rows = regression_study[0.0]
    covered = sum(iv.covers(REGRESSION_TRUTH[0]) for iv, _ in rows)
    assert all(iv.determined and iv.dof == 9 for iv, _ in rows)
    assert 369 <= covered <= 390, covered


def test_row_covariance_undercovers_correlated_rows(regression_study):
    """The same problems with the rows' least-squares covariance: correlated rows make it far too narrow
    (measured 208 of 400, 52 %), the reason the diagnosis takes the scatter over runs instead."""
    covered = sum(naive for _, naive in regression_study[0.0])
    assert covered < 0.7 * REGRESSION_PROBLEMS, covered


def test_a_shared_systematic_error_needs_its_own_term(regression_study):
    """A slope 15 % off in every run: the jackknife's intervals (the scatter over runs) do not see it and miss the
    truth in most problems (measured: 67 of 400 hold it); with the systematic error added in quadrature at its size
    (15 % of the estimate, as EFFECT_MODEL_ERROR adds a tuned one) they hold it in all 400 (half-widths of at least
    t(0.975, 9) * 15 % = 34 % against the offset of 15 %)."""
    from validation.diagnosis.summarise.uncertainty import with_model_error

    rows = regression_study[SYSTEMATIC]
    assert sum(iv.covers(REGRESSION_TRUTH[0]) for iv, _ in rows) < 0.5 * REGRESSION_PROBLEMS
    widened = [with_model_error(iv, SYSTEMATIC * abs(iv.value)) for iv, _ in rows]
    assert sum(iv.covers(REGRESSION_TRUTH[0]) for iv in widened) >= 0.95 * REGRESSION_PROBLEMS
    iv = widened[0]
    assert iv.statistical_std_error == rows[0][0].std_error and iv.model_std_error == pytest.approx(SYSTEMATIC * abs(iv.value))
    assert iv.std_error == pytest.approx(np.hypot(iv.statistical_std_error, iv.model_std_error))


def test_effect_model_errors_are_added_per_parameter_and_kept_apart():
    """Each parameter gets its own relative systematic error; a parameter without one keeps the jackknife's
    interval, a not-determined one stays not determined, and both parts survive diagnosis.json's round trip."""
    from validation.diagnosis.summarise.uncertainty import EFFECT_MODEL_ERROR, with_effect_model_errors

    stat = interval_from_error(2.0, 0.01, 9)
    none = ParameterInterval(5.0, None, None, 9, "no spread over the runs")
    got = with_effect_model_errors({"linear_damping": {"gamma_theta": stat, "gamma_y": none},
                                    "velocity_coupling": {"c6": stat}})
    gt = got["linear_damping"]["gamma_theta"]
    rel = EFFECT_MODEL_ERROR["linear_damping"]["gamma_theta"]
    assert gt.std_error == pytest.approx(np.hypot(0.01, rel * 2.0)) and gt.model_std_error == pytest.approx(rel * 2.0)
    assert got["linear_damping"]["gamma_y"] is none and got["velocity_coupling"]["c6"] is stat
    assert ParameterInterval.from_dict(gt.to_dict()) == gt
    assert set(stat.to_dict()) == {"value", "std_error", "interval_95", "dof", "determined", "reason"}


def test_beside_a_cavity_gamma_y_and_the_pressure_take_their_own_systematic_parts():
    """With a cavity in the model, gamma_y's systematic part is the absolute BESIDE_CAVITY_GAMMA_Y_ERROR (1/s: an
    estimate near zero, as beside a cavity's lag it often is, still gets it) and the pressure's the relative
    BESIDE_CAVITY_PRESSURE_ERROR; without a cavity both keep their usual parts."""
    from validation.diagnosis.summarise.uncertainty import (BESIDE_CAVITY_GAMMA_Y_ERROR, BESIDE_CAVITY_PRESSURE_ERROR,
                                                             EFFECT_MODEL_ERROR, PRESSURE_MODEL_ERROR,
                                                             pressure_model_error, with_effect_model_errors)

    gamma_y = interval_from_error(-0.40, 0.32, 9)  # the air damps y at 0.57 1/s: outside the jackknife's interval
    cavity = {"static_gain": interval_from_error(-1e-3, 1e-5, 9)}
    beside = with_effect_model_errors({"linear_damping": {"gamma_y": gamma_y}, "cavity_lag": cavity})
    got = beside["linear_damping"]["gamma_y"]
    assert got.model_std_error == BESIDE_CAVITY_GAMMA_Y_ERROR
    assert got.std_error == pytest.approx(np.hypot(0.32, BESIDE_CAVITY_GAMMA_Y_ERROR))
    assert not gamma_y.covers(0.57) and got.covers(0.57)
    alone = with_effect_model_errors({"linear_damping": {"gamma_y": gamma_y}})["linear_damping"]["gamma_y"]
    assert alone.model_std_error == pytest.approx(EFFECT_MODEL_ERROR["linear_damping"]["gamma_y"] * 0.40)
    assert pressure_model_error(["linear_damping", "cavity_lag"]) == BESIDE_CAVITY_PRESSURE_ERROR
    assert pressure_model_error({"linear_damping": {}}) == PRESSURE_MODEL_ERROR


def test_a_parameter_one_run_carries_is_not_determined():
    """A leave-one-run-out refit without a finite value (the cavity's mode when the only run with a large enough
    amplitude is left out) gives "not determined" with that reason, never a number without an error."""
    from validation.diagnosis.summarise.uncertainty import jackknife_interval

    iv = jackknife_interval(250.0, np.array([240.0, 255.0, np.nan, 251.0, 248.0]))
    assert not iv.determined and "that run alone carries the parameter" in iv.reason
    assert "not determined" in iv.format()


def test_beta0_takes_the_energy_balance_pull_as_an_absolute_systematic_part():
    """Paper-like seed 810's beta0 (truth 0): -2.588 with a jackknife error of 0.83 1/s^2 on 11 degrees of freedom
    misses zero by 0.8 1/s^2; the energy balance's pull there, 1.66 1/s^2 (the fit without its rows gave -0.925),
    is added to its relative part in quadrature, and the interval holds zero.  Without a pull (the blind study's
    cases, where the pull is 0.03 at most) the relative part alone is left: EFFECT_MODEL_ERROR's 1.4e-3."""
    from validation.diagnosis.summarise.uncertainty import EFFECT_MODEL_ERROR, with_effect_model_errors

    beta0 = interval_from_error(-2.588, 0.83, 11)
    rel = EFFECT_MODEL_ERROR["mirror_asymmetry"]["beta0"]
    assert rel == 1.4e-3 and EFFECT_MODEL_ERROR["mirror_asymmetry"]["beta1"] == 0.09
    alone = with_effect_model_errors({"mirror_asymmetry": {"beta0": beta0}})["mirror_asymmetry"]["beta0"]
    assert alone.model_std_error == pytest.approx(rel * 2.588) and not alone.covers(0.0)
    got = with_effect_model_errors({"mirror_asymmetry": {"beta0": beta0}},
                                   absolute={"mirror_asymmetry": {"beta0": 1.66}})["mirror_asymmetry"]["beta0"]
    assert got.model_std_error == pytest.approx(np.hypot(rel * 2.588, 1.66))
    assert got.statistical_std_error == 0.83 and got.covers(0.0)
    # half-width t(0.975, 11) sqrt(0.83^2 + 1.66^2) = 2.201 * 1.856 = 4.08 1/s^2
    assert got.interval_95[1] - got.value == pytest.approx(4.08, abs=0.01)


@pytest.fixture(scope="module")
def mirror_runs(fast_model):
    """8 synthetic runs of 1.6 s with mirror asymmetry (beta0 = 2 1/s^2, beta1 = 5e4 1/(m s^2)) and linear damping
    at nominal pressure."""
    from .conftest import _synthetic_runs

    truth = Calibration.at(fast_model, 1.0, fast_model.equilibrium_height)
    effects = {"mirror_asymmetry": {"beta0": 2.0, "beta1": 5.0e4},
               "linear_damping": {"gamma_y": 0.5, "gamma_theta": 0.5}}
    return _synthetic_runs(fast_model, truth, effects, n_runs=8, duration=1.6, seed=7, known_noise=True), list(effects)


def test_no_energy_balance_pull_where_the_model_is_exact(fast_model, mirror_runs):
    """On runs of the exact model (the energy balance closes on their exact states), the joint fit and the fit
    without the energy rows agree on beta0: the pull :func:`energy_balance_pulls` reports, their difference, is
    below a hundredth of beta0's jackknife error (measured 1e-5 against 0.70 1/s^2), and beta0 is within 2.5 of
    that error of its truth (measured 2.042 against 2).  Without mirror asymmetry among the effects there is none."""
    from validation.diagnosis.summarise.uncertainty import energy_balance_pulls

    runs, names = mirror_runs
    problem = DiagnosisProblem(fast_model, runs)
    fit = fit_gap_model(problem, names)
    equations = fit_gap_model(problem, names, fixed=fit.calibration, energy_balance=False).effects
    pull = energy_balance_pulls(problem, names, fit.calibration)["mirror_asymmetry"]["beta0"]
    both = fit.effects["mirror_asymmetry"]["beta0"]
    assert pull == pytest.approx(abs(both - equations["mirror_asymmetry"]["beta0"]), rel=1e-9, abs=1e-12)
    se = jackknife_errors(problem, names, fit.effects, fit.calibration).effects["mirror_asymmetry"]["beta0"].std_error
    assert pull < 0.01 * se and abs(both - 2.0) < 2.5 * se
    # the energy rows matter to the fit: without them gamma_y, which they carry, moves (0.4995 -> 0.448 here)
    assert abs(equations["linear_damping"]["gamma_y"] - fit.effects["linear_damping"]["gamma_y"]) > 0.02
    assert energy_balance_pulls(problem, ["linear_damping"], fit.calibration) == {}


@pytest.mark.slow
def test_paper_like_beta0_interval_holds_its_true_zero(tmp_path):
    """The flagship preset, seed 810 (12 runs of 4 s; mirror asymmetry beta1 = 1e6, beta0 = 0): the final model's
    beta0 is -2.59 1/s^2 with a jackknife error of 0.83 (the jackknife's interval misses zero), the energy balance's
    pull is 1.66 (its states, whose 3 f_y velocity gain is 0.85, leave the balance 5 % short of closing; with the
    twin's exact states at the same frames the pull is 0.94) and the stated interval, with the pull as its
    systematic part, holds zero.  About 15 CPU-s (the twin's 12 runs, one calibration, 14 fits)."""
    from acousim.cli import main as acousim_main
    from validation.diagnosis.calibrate.calibration_step import calibration_step
    from validation.diagnosis.steps import DiagnoseConfig, load_for_diagnosis, start_diagnosis
    from validation.diagnosis.summarise.uncertainty import energy_balance_pulls, with_effect_model_errors

    out = tmp_path / "paper"
    assert acousim_main(["simulate", "--preset", "paper-like", "--runs", "12", "--seed", "810", "--workers", "1",
                         "--no-progress", "--out", str(out)]) == 0
    start = start_diagnosis(load_for_diagnosis(out, progress=False))
    config = DiagnoseConfig(drift=None, check_orientation=False, long_time=False)
    calibrated = calibration_step(start.prepared, start.conditions, start.model, start.spec, config, lambda *a: None)
    problem = calibrated.problem
    names = ["pair_scattering", "mirror_asymmetry", "linear_damping"]  # what the diagnosis names on it
    fit = fit_gap_model(problem, names)
    errors = jackknife_errors(problem, names, fit.effects, fit.calibration).effects
    pulls = energy_balance_pulls(problem, names, fit.calibration)
    beta0 = errors["mirror_asymmetry"]["beta0"]
    # the numbers of the diagnosis of this data set (docs/diagnosis.md), to the fit's reproducibility
    assert beta0.value == pytest.approx(-2.588, abs=0.01) and beta0.std_error == pytest.approx(0.83, abs=0.01)
    assert pulls["mirror_asymmetry"]["beta0"] == pytest.approx(1.66, abs=0.01)
    assert not beta0.covers(0.0)
    stated = with_effect_model_errors(errors, absolute=pulls)
    assert stated["mirror_asymmetry"]["beta0"].covers(0.0)
    assert all(stated[e][p].covers(v) for e, p, v in (("pair_scattering", "kappa", 19500.0),
                                                      ("mirror_asymmetry", "beta1", 1e6),
                                                      ("linear_damping", "gamma_y", 0.1),
                                                      ("linear_damping", "gamma_theta", 1.5)))
