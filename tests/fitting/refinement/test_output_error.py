"""Output-error refinement (:mod:`fitting.refinement.output_error`): recovery of an exact model from perturbed coefficients at
the tracking-noise floor, and on a non-polynomial truth the cubic that predicts it best."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from cubedimer.spectra import dominant_frequency
from fitting.model import EXPONENTS, TERMS, PolynomialModel
from fitting.refinement.model_states import segment_layout
from fitting.refinement.output_error import OutputErrorConfig, refine_output_error

W1, W2 = 2 * np.pi * 1.0, 2 * np.pi * 1.6
FPS = 200.0
CUBIC = PolynomialModel.from_equations({
    "yddot": {"y": -W1**2, "ydot": -0.2, "theta": 3.0, "y^3": 6.0},
    "thetaddot": {"y": 3.0, "theta": -W2**2, "thetadot": -0.15, "y^2*theta": -10.0}})


def _runs(rhs, amplitude, n_runs, seed, duration=12.0):
    """Exact trajectories (DOP853, rtol 1e-10) from random states of the given angle amplitude.  ``rhs`` maps states
    (4, runs) to their derivatives: the runs are integrated as one system (one call of the Python right-hand side per
    stage for all of them)."""
    rng = np.random.default_rng(seed)
    t = np.arange(0, duration, 1 / FPS)
    x0 = []
    for _ in range(n_runs):
        a, ph = rng.uniform(0.5, 1.0, 2) * amplitude, rng.uniform(0, 2 * np.pi, 2)
        x0.append([a[0] * np.cos(ph[0]), -a[0] * W1 * np.sin(ph[0]), a[1] * np.cos(ph[1]), -a[1] * W2 * np.sin(ph[1])])
    sol = solve_ivp(lambda _, s: rhs(s.reshape(n_runs, 4).T).T.ravel(), (0, t[-1]), np.ravel(x0), t_eval=t,
                    method="DOP853", rtol=1e-10, atol=1e-12).y
    return [(t, sol[4 * k:4 * k + 4].T) for k in range(n_runs)]


def _refine(model, exact, sigma, seed, config=OutputErrorConfig()):
    """Refine ``model`` on noisy copies of ``exact``, starting the segments from the exact states."""
    rng = np.random.default_rng(seed)
    ys = [s[:, 0] + sigma * rng.standard_normal(len(t)) for t, s in exact]
    ths = [s[:, 2] + sigma * rng.standard_normal(len(t)) for t, s in exact]
    freqs = [min(dominant_frequency(y, 1 / FPS), dominant_frequency(th, 1 / FPS)) for y, th in zip(ys, ths)]
    return refine_output_error(model, [1 / FPS] * len(exact), ys, ths, [s for _, s in exact], freqs, (sigma, sigma),
                               config)


def _long_time(model, exact, periods=5.0):
    """RMS position error over ``periods`` of the 1-Hz mode from the exact initial state, over the RMS position
    (mean of y and theta, median over the runs)."""
    n = int(periods * FPS)
    errs = []
    for t, s in exact:
        sim, nv = model.simulate(s[0], t[:n], substeps=8)
        assert nv == n
        errs.append(np.mean([np.sqrt(np.mean((sim[:, k] - s[:n, k]) ** 2) / np.mean(s[:n, k] ** 2)) for k in (0, 2)]))
    return float(np.median(errs))


@pytest.fixture(scope="module")
def cubic_runs():
    """Four exact 12-s runs of :data:`CUBIC` (computed once for the module's tests)."""
    def rhs(s):
        acc = CUBIC.predict(s.T).T  # both accelerations of every run from one evaluation of the library
        return np.array([s[1], acc[0], s[3], acc[1]])

    return _runs(rhs, 0.5, 4, seed=1)


def test_an_exact_model_is_recovered_at_the_noise_floor(cubic_runs):
    exact = cubic_runs
    start = PolynomialModel(CUBIC.coef * np.where(CUBIC.support, 1.02, 0.0))  # every coefficient 2 % off
    fit = _refine(start, exact, 1e-3, seed=2)
    # the 2 % error is visible in the misfit (a 1 % frequency error over 5 periods is a 0.3-rad phase), and the
    # refined trajectories follow the data to the white noise: sqrt(chi^2 / N) of ~10^4 samples is 1 +- 0.01
    assert fit.misfit_start > 10.0
    assert 0.98 < fit.misfit < 1.02
    # every run in segments of 5 periods of its slower mode (1 Hz), overlapping by half: 4 per 12-s run
    assert fit.segments == 4 * segment_layout(len(exact[0][0]), int(5.0 * FPS))[0].size == 16 and fit.dropped == 0
    # the support is kept, and the stiffnesses come back from 2e-2 to 1e-4 (1e-5 and 5e-5 at this noise draw)
    assert ((fit.coef != 0) == CUBIC.support).all()
    for q, term in ((0, "y"), (1, "theta")):
        j = ["1", "y", "ydot", "theta"].index(term)
        np.testing.assert_allclose(fit.coef[q, j], CUBIC.coef[q, j], rtol=1e-4)
    # one optimum: started from the truth itself, the refinement ends at the same coefficients (the noise moves
    # the optimum from the truth by up to 1.6 % on the weak y^2*theta term, the start by much less)
    from_truth = _refine(CUBIC, exact, 1e-3, seed=2)
    np.testing.assert_allclose(fit.coef, from_truth.coef, rtol=1e-3)


def test_noiseless_data_give_the_exact_model(cubic_runs):
    """Without noise (a tracking noise of 0) the misfit is weighted by a floor of 1e-6 of the coordinates' RMS, and
    the refinement ends at the truth to the integrators' agreement."""
    exact = cubic_runs
    fit = _refine(PolynomialModel(CUBIC.coef * np.where(CUBIC.support, 1.02, 0.0)), exact, 0.0, seed=2)
    # RK4 at h omega <= 0.1 against DOP853 at rtol 1e-10: the coefficients agree to 3e-7 here
    np.testing.assert_allclose(fit.coef[CUBIC.support], CUBIC.coef[CUBIC.support], rtol=1e-5)


def _pendulums(s):
    """Two pendulums (sin forces) with a weak linear coupling and damping: not polynomial."""
    return np.array([s[1], -W1**2 * np.sin(s[0]) - 0.1 * s[1] + 2.0 * (s[2] - s[0]),
                     s[3], -W2**2 * np.sin(s[2]) - 0.1 * s[3] - 2.0 * (s[2] - s[0])])


def test_on_a_non_polynomial_truth_the_refined_cubic_predicts_better_than_the_taylor_series(pendulum_runs):
    """At swings of up to 1.2 rad the pendulums' frequencies drop by up to 9 %; the cubic Taylor series gets
    the drop wrong by a fifth-order amount, the output-error cubic fits the amplitude range of the data."""
    taylor = PolynomialModel.from_equations({
        "yddot": {"y": -W1**2 - 2.0, "ydot": -0.1, "theta": 2.0, "y^3": W1**2 / 6},
        "thetaddot": {"y": 2.0, "theta": -W2**2 - 2.0, "thetadot": -0.1, "theta^3": W2**2 / 6}})
    exact = pendulum_runs
    fit = _refine(taylor, exact[:6], 1e-3, seed=6)
    assert fit.misfit < 0.5 * fit.misfit_start
    before, after = _long_time(taylor, exact[6:]), _long_time(PolynomialModel(fit.coef), exact[6:])
    assert after < 0.5 * before, (before, after)


#: the pendulums' Taylor cubic: its support and start coefficients
PENDULUM_TAYLOR = {"yddot": {"y": -W1**2 - 2.0, "ydot": -0.1, "theta": 2.0, "y^3": W1**2 / 6},
                   "thetaddot": {"y": 2.0, "theta": -W2**2 - 2.0, "thetadot": -0.1, "theta^3": W2**2 / 6}}
#: terms even in the coordinates: the pendulums' forces are odd, so these are zero at every order of the series
EVEN_TERMS = {"yddot": {"y^2": 0.5}, "thetaddot": {"y*theta": 0.5}}


def _with_even_terms():
    return PolynomialModel.from_equations({eq: {**PENDULUM_TAYLOR[eq], **EVEN_TERMS[eq]} for eq in PENDULUM_TAYLOR})


@pytest.fixture(scope="module")
def pendulum_runs():
    return _runs(_pendulums, 1.2, 8, seed=5)


@pytest.fixture(scope="module")
def even_terms_fit(pendulum_runs):
    """The default refinement of the Taylor support plus the two even terms on the first six pendulum runs (shared
    by the tests that read it; the refinement is deterministic, so sharing it changes no number)."""
    return _refine(_with_even_terms(), pendulum_runs[:6], 1e-3, seed=6)


def test_pruning_removes_the_terms_a_trajectory_does_not_need(pendulum_runs, even_terms_fit):
    """Under model error (swings of 1.2 rad) a support with two terms of the wrong symmetry: pruning removes both
    and keeps every term of the Taylor support, and the pruned cubic predicts held-out runs as well."""
    fit = even_terms_fit
    taylor = PolynomialModel.from_equations(PENDULUM_TAYLOR).support
    assert sorted(fit.pruned) == ["thetaddot:y*theta", "yddot:y^2"]
    assert (fit.coef[taylor] != 0).all()
    # what the additions bring is odd in the coordinates, like the forces: an even term cannot lower the misfit
    for name in fit.added:
        assert EXPONENTS[TERMS.index(name.split(":")[1])].sum() % 2 == 1, name
    assert ((fit.coef != 0) == (taylor | _mask(fit.added))).all()
    # the rule itself: the squared misfit within 3 % of the full support's model-error part (additions only lower
    # it)
    assert fit.misfit_support > 1.3  # a model-error part (misfit**2 - 1; 1.0 here) of the size of the noise
    assert fit.misfit**2 <= fit.misfit_support**2 + 0.03 * (fit.misfit_support**2 - 1)
    unpruned = _refine(_with_even_terms(), pendulum_runs[:6], 1e-3, seed=6,
                       config=OutputErrorConfig(support_tolerance=None))
    assert unpruned.pruned == unpruned.added == () and unpruned.misfit == fit.misfit_support
    # the held-out long-time error of the pruned cubic is that of the unpruned one within 10 % (both fit the same
    # amplitude range; the even terms' refined coefficients are near zero)
    before = _long_time(PolynomialModel(unpruned.coef), pendulum_runs[6:])
    after = _long_time(PolynomialModel(fit.coef), pendulum_runs[6:])
    assert after < 1.1 * before, (before, after)


def test_a_practical_threshold_makes_no_addition_worth_less_than_it(pendulum_runs, even_terms_fit):
    """``misfit_tolerance`` (the discovery's ``--heldout-tolerance``): by default the two additions after the pruning
    lower the misfit from 1.427 to 1.344 noise units (6 %); a threshold of 10 % of the RMS misfit makes neither, and
    the pruning stays within it of the full support's misfit."""
    default = even_terms_fit
    wide = _refine(_with_even_terms(), pendulum_runs[:6], 1e-3, seed=6, config=OutputErrorConfig(misfit_tolerance=0.1))
    assert len(default.added) == 2 and default.misfit < 0.95 * default.misfit_support
    assert wide.added == () and sorted(wide.pruned) == ["thetaddot:y*theta", "yddot:y^2"]
    assert wide.misfit <= 1.1 * wide.misfit_support


def _mask(names):
    mask = np.zeros((2, len(TERMS)), bool)
    for name in names:
        eq, term = name.split(":")
        mask[["yddot", "thetaddot"].index(eq), TERMS.index(term)] = True
    return mask


def test_a_damping_the_trajectories_need_is_added(pendulum_runs):
    """The Taylor support without y's damping: its acceleration share is 0.3 %, but over 5 periods it decides the
    amplitude.  The score test finds it first among the 63 absent terms, and with it the held-out long-time error
    drops twenty-fold."""
    eqs = {eq: dict(terms) for eq, terms in PENDULUM_TAYLOR.items()}
    del eqs["yddot"]["ydot"]
    fit = _refine(PolynomialModel.from_equations(eqs), pendulum_runs[:6], 1e-3, seed=6)
    assert fit.added[0] == "yddot:ydot" and fit.pruned == ()
    # the truth's damping 0.1 1/s, to the bias model error leaves (0.1 % at this draw)
    np.testing.assert_allclose(fit.coef[0, TERMS.index("ydot")], -0.1, rtol=0.01)
    without = _refine(PolynomialModel.from_equations(eqs), pendulum_runs[:6], 1e-3, seed=6,
                      config=OutputErrorConfig(support_tolerance=None))
    assert fit.misfit < 0.1 * without.misfit  # 24.5 -> 1.34 noise units
    pruning_alone = _refine(PolynomialModel.from_equations(eqs), pendulum_runs[:6], 1e-3, seed=6,
                            config=OutputErrorConfig(additions=False))
    assert pruning_alone.added == () and pruning_alone.coef[0, TERMS.index("ydot")] == 0
    # a cap on the terms per equation (the discovery's --max-terms) holds through the additions: at the size yddot
    # has without its damping (3 terms; thetaddot has 4) neither equation may grow, so the damping is not added
    capped = _refine(PolynomialModel.from_equations(eqs), pendulum_runs[:6], 1e-3, seed=6,
                     config=OutputErrorConfig(max_terms=len(eqs["yddot"])))
    assert capped.added == () and capped.coef[0, TERMS.index("ydot")] == 0
    before = _long_time(PolynomialModel(without.coef), pendulum_runs[6:])
    after = _long_time(PolynomialModel(fit.coef), pendulum_runs[6:])
    assert after < 0.05 * before, (before, after)  # 15 % -> 0.7 %


def _taylor_refit(runs, y_unit=1.0):
    """The pendulums' Taylor cubic refined on noisy runs with y in units of ``y_unit`` m (internals of the support
    search: segments, refined fit, smoothed states' library)."""
    from cubedimer.terms import evaluate_library
    from fitting.refinement.output_error import _refine as refine
    from fitting.refinement.segment_problem import TrajectoryProblem, build_segments, fit_segment_states

    rng = np.random.default_rng(6)
    config, sigma = OutputErrorConfig(), np.array([1e-3 / y_unit, 1e-3])
    states = [s * np.array([1 / y_unit, 1 / y_unit, 1.0, 1.0]) for _, s in runs]
    ys = [s[:, 0] + sigma[0] * rng.standard_normal(len(s)) for s in states]
    ths = [s[:, 2] + sigma[1] * rng.standard_normal(len(s)) for s in states]
    segs = build_segments([1 / FPS] * len(runs), ys, ths, states, [1.0] * len(runs), config)
    # y in units of y_unit: a term's coefficient scales with y_unit to the power of its powers of y and ydot, less
    # 1 in yddot
    power = EXPONENTS[:, 0] + EXPONENTS[:, 1] - np.array([[1], [0]])
    coef = PolynomialModel.from_equations(PENDULUM_TAYLOR).coef * float(y_unit) ** power
    start = TrajectoryProblem(coef, segs, sigma, config.h_omega)
    fit = refine(coef, segs, sigma, fit_segment_states(start, start.parameters(coef), segs.x0.copy())[0], config)
    return fit, segs, sigma, config, evaluate_library(np.vstack(states)), power


@pytest.fixture(scope="module")
def taylor_refit(pendulum_runs):
    """:func:`_taylor_refit` of the first six pendulum runs in units of ``y_unit`` (each unit computed once)."""
    done = {}

    def refit(y_unit=1.0):
        if y_unit not in done:
            done[y_unit] = _taylor_refit(pendulum_runs[:6], y_unit)
        return done[y_unit]

    return refit


def test_the_score_test_predicts_the_refitted_drop_of_the_misfit(taylor_refit):
    """The additions' score test (one Jacobian of all 70 coefficients, segment states eliminated) against the refit
    with the term: the first-order drop of the squared misfit and the coefficient it predicts."""
    from fitting.refinement.output_error import _addition_gains, _refine as refine

    fit, segs, sigma, config, library, _ = taylor_refit()
    gain, delta = _addition_gains(fit.coef, fit.x0, segs, sigma, library, config)
    assert np.isneginf(gain[fit.coef != 0]).all()
    # even terms cannot help odd forces: the few that pass the noise's chi-square floor (the residual is partly
    # model error, not white) gain 0.1 % of the model-error part, 30 times less than an addition needs
    even = (EXPONENTS.sum(axis=1) % 2 == 0)[None] & (fit.coef == 0)
    need = config.support_tolerance * (fit.misfit**2 - 1)
    assert gain[even].max() < 0.1 * need
    q, j = 1, TERMS.index("theta^2*thetadot")  # the hinge's amplitude-dependent damping-like term, the best here
    assert np.unravel_index(np.argmax(gain), gain.shape) == (q, j)
    trial = fit.coef.copy()
    trial[q, j] = delta[q, j]
    with_term = refine(trial, segs, sigma, fit.x0, config)
    # first order in a term that lowers the squared misfit by 6 %: the prediction is within 0.3 % at this draw
    np.testing.assert_allclose(gain[q, j], fit.misfit**2 - with_term.misfit**2, rtol=0.03)
    np.testing.assert_allclose(delta[q, j], with_term.coef[q, j], rtol=0.05)


def test_scores_and_standard_errors_do_not_depend_on_the_units(taylor_refit):
    """y in micrometres instead of metres moves the coefficients over twelve decades (y^3 in yddot by 1e-12): the
    score test's gains and the standard errors' z must not move (an unequilibrated pseudo-inverse cuts the
    large-variance directions as round-off)."""
    from fitting.refinement.output_error import _addition_gains, _standard_errors

    out = []
    for unit in (1.0, 1e-6):
        fit, segs, sigma, config, library, power = taylor_refit(unit)
        gain, delta = _addition_gains(fit.coef, fit.x0, segs, sigma, library, config)
        se = _standard_errors(fit.coef, fit.x0, segs, sigma, config)
        on = fit.coef != 0
        out.append((fit.coef[on] / se[on], gain, delta / float(unit) ** power))
    # the same fit in other units: agreement to the forward differences' and the refinement's stopping (1e-3)
    np.testing.assert_allclose(out[1][0], out[0][0], rtol=1e-3)
    ok = np.isfinite(out[0][1])
    assert (np.isfinite(out[1][1]) == ok).all()
    np.testing.assert_allclose(out[1][1][ok], out[0][1][ok], rtol=1e-3)
    np.testing.assert_allclose(out[1][2][ok], out[0][2][ok], rtol=1e-3)
    # and the z of the linear stiffness is a few thousand (a coefficient known to 0.03 %), not round-off's 1e12
    assert 1e2 < abs(out[0][0][0]) < 1e6


def test_forced_terms_are_never_pruned(pendulum_runs):
    model = _with_even_terms()
    forced = np.zeros_like(model.support)
    forced[0, TERMS.index("y^2")] = True
    rng = np.random.default_rng(6)
    runs = pendulum_runs[:6]
    ys = [s[:, 0] + 1e-3 * rng.standard_normal(len(t)) for t, s in runs]
    ths = [s[:, 2] + 1e-3 * rng.standard_normal(len(t)) for t, s in runs]
    fit = refine_output_error(model, [1 / FPS] * 6, ys, ths, [s for _, s in runs], [1.0] * 6, (1e-3, 1e-3),
                              forced=forced)
    assert fit.pruned == ("thetaddot:y*theta",) and fit.coef[forced].all()


def test_config_validates_itself():
    for bad in ({"periods": 0.0}, {"max_segments": 0}, {"iterations": 1.5}, {"rtol": -1.0}, {"support_tolerance": -0.1},
                {"support_rejections": 0}, {"addition_misfit": 0.0}, {"misfit_tolerance": -0.01},
                {"max_terms": 0}, {"max_terms": 2.5}):
        with pytest.raises(ValueError):
            OutputErrorConfig(**bad)


@pytest.mark.parametrize("mean_square, followed", [
    ([1.0, 1.0, 1.0, 24.0, 26.0, np.inf], [True, True, True, True, False, False]),  # 5x the median RMS: 25x its square
    ([np.inf, np.inf], [False, False]),
])
def test_segments_the_model_does_not_follow_are_left_out(mean_square, followed):
    from fitting.refinement.output_error import _followed

    assert _followed(np.array(mean_square), 5.0).tolist() == followed
