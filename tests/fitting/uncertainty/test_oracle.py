"""The oracle (integral-form standard errors at a model's own noise-free trajectories) and the run planner."""
import json
from dataclasses import replace

import numpy as np
import pytest

from cubedimer.dataset import load_dataset
from cubedimer.spectra import dominant_frequency
from cubedimer.terms import EQUATION_NAMES, evaluate_library
from fitting.cli import main
from fitting.derivatives.integral_form import (detrend_windows, fit_integral_form, integral_columns, integral_window,
                                               window_starts)
from fitting.model import TERMS
from fitting.uncertainty.oracle import (NoiseLevels, OracleRun, canonical_term, estimate_tracking_noise,
                                        oracle_standard_errors)
from fitting.uncertainty.run_planning import PlanConfig, plan_runs
from fitting.fit import prepare_runs
from fitting.synthetic import SyntheticConfig, generate_runs, paper_reduced_model, write_dataset

NOISE = NoiseLevels(1.5e-6, 0.003)  # the paper-like tracking noise of the table [m], [-]
FPS = 1500.0


@pytest.fixture(scope="module")
def model():
    return paper_reduced_model()


@pytest.fixture(scope="module")
def clean(model):
    """Six noise-free 2-s runs of the paper's reduced model (exact states from fitting.synthetic)."""
    return generate_runs(model, SyntheticConfig(n_runs=6, duration=2.0, fps=FPS, noise_y=0.0, noise_theta=0.0,
                                                missing_frames=0, seed=5))


def _design(columns, windows):
    """The integral form's detrended design, stacked over the runs."""
    return np.concatenate([integral_columns(f, 1.0 / FPS, window_starts(len(f), w), w)
                           for f, w in zip(columns, windows)])


def _targets(positions, windows):
    """The integral form's detrended targets, stacked over the runs ((rows, draws) for positions (n, draws))."""
    return np.concatenate([detrend_windows(x, window_starts(len(x), w), w) for x, w in zip(positions, windows)])


def _stacked(positions, columns, windows):
    """The integral form's detrended design and targets."""
    return _design(columns, windows), _targets(positions, windows)


def _lstsq(X, b):
    scale = np.sqrt(np.sum(X * X, axis=0))
    return np.linalg.lstsq(X / scale, b, rcond=None)[0] / scale[:, None]


def test_oracle_standard_errors_match_a_monte_carlo_of_the_estimator(model, clean):
    """300 noise draws on fixed noise-free trajectories, each fitted by fitting.derivatives.integral_form.fit_integral_form
    on the true support with its columns at the exact states: the spread of the estimates is the oracle SE.

    The oracle integrates the model itself from the initial states (fitting.integrate), so this also checks
    that its trajectories, windows and columns are those of the estimator."""
    runs = [OracleRun(r["x0"], r["t"].size, 1.0 / FPS) for r in clean]
    oracle = oracle_standard_errors(model, runs, NOISE)
    rng = np.random.default_rng(2024)
    n_draws = 300  # the sample std of 300 draws scatters by 1/sqrt(2 * 299) = 4 %: 20 % is ~5 of those
    for q, (eq, coord) in enumerate(zip(EQUATION_NAMES, (0, 2))):
        names = list(oracle.terms[eq])
        assert names == [t for t, c in zip(TERMS, model.coef[q]) if c != 0]
        cols = [TERMS.index(t) for t in names]
        columns = [evaluate_library(r["state"])[:, cols] for r in clean]
        windows = [integral_window(1.0 / FPS, dominant_frequency(r["state"][:, coord], 1.0 / FPS)) for r in clean]
        dts = [1.0 / FPS] * len(clean)
        est, reported = [], []
        for _ in range(20):  # the estimator itself, a few draws ...
            pos = [r["state"][:, coord] + NOISE.of(eq) * rng.standard_normal(r["t"].size) for r in clean]
            fit = fit_integral_form(pos, columns, dts, windows)
            est.append(fit.coefficients)
            reported.append(fit.std_errors)
            # ... equals the same least squares done for many draws at once (below) to round-off
            X, b = _stacked(pos, columns, windows)
            np.testing.assert_allclose(_lstsq(X, b[:, None])[:, 0], fit.coefficients, rtol=1e-7)
        pos = [r["state"][:, coord][:, None] + NOISE.of(eq) * rng.standard_normal((r["t"].size, n_draws - 20))
               for r in clean]
        X, b = _stacked(pos, columns, windows)
        est = np.vstack([np.array(est), _lstsq(X, b).T])
        mc = np.std(est, axis=0, ddof=1)
        se = np.array([oracle.terms[eq][t].std_error for t in names])
        ratio = mc / se
        assert np.all(np.abs(ratio - 1.0) < 0.2), dict(zip(names, ratio))
        # the estimator's own (residual-based) standard errors agree too
        np.testing.assert_allclose(np.mean(reported, axis=0), se, rtol=0.2)
        # and the z reported is |coefficient| / SE
        for t, o in oracle.terms[eq].items():
            assert o.coefficient == model.coef[q, TERMS.index(t)] and o.z == pytest.approx(abs(o.coefficient) / o.std_error)
    # linear in the noise: twice the noise, twice the standard errors
    twice = oracle_standard_errors(model, runs, NoiseLevels(2 * NOISE.sigma_y, 2 * NOISE.sigma_theta))
    for eq in EQUATION_NAMES:
        for t, o in oracle.terms[eq].items():
            assert twice.terms[eq][t].std_error == pytest.approx(2 * o.std_error, rel=1e-9)
    js = oracle.to_json()
    assert set(js["thetaddot"]["y^2*theta"]) == {"coefficient", "std_error", "z", "alias", "alias_z"}
    assert js["n_runs"] == 6
    # dropping a term is a special case of replacing it: the alias z never exceeds the oracle z
    for eq in EQUATION_NAMES:
        for t, o in oracle.terms[eq].items():
            assert o.alias in TERMS and o.alias not in oracle.terms[eq] and 0.0 < o.alias_z <= o.z * (1 + 1e-9)


def test_alias_z_predicts_how_often_least_squares_prefers_the_alias():
    """A weak hinge term near its alias: y*thetadot^2 on a nearly harmonic 9-Hz hinge, whose closest rival is
    ydot*theta*thetadot.  Over noise draws on fixed noise-free trajectories, least squares at the exact columns
    compares the true support with the one where the term is replaced by its alias: the mean difference of the
    residual sums of squares is alias_z^2 noise variances, and the alias wins in Phi(-alias_z / 2) of the draws."""
    from scipy.special import ndtr

    from fitting.model import PolynomialModel

    w_y, w_t = 2 * np.pi * 22.0, 2 * np.pi * 9.0
    weak = PolynomialModel.from_equations({
        "yddot": {"y": -w_y ** 2, "y^2": 1.0e6, "ydot": -0.3},
        "thetaddot": {"theta": -w_t ** 2, "y": 1.5e6, "y^2*theta": 4.0e9, "thetadot": -0.8, "y*thetadot^2": 400.0,
                      "y*ydot*thetadot": 2.0e6}})
    noise = NoiseLevels(2.0e-6, 0.004)
    gen = generate_runs(weak, SyntheticConfig(n_runs=8, duration=3.0, fps=FPS, noise_y=0.0, noise_theta=0.0,
                                              missing_frames=0, seed=11))
    runs = [OracleRun(r["x0"], r["t"].size, 1.0 / FPS) for r in gen]
    term = oracle_standard_errors(weak, runs, noise).terms["thetaddot"]["y*thetadot^2"]
    assert term.alias == "ydot*theta*thetadot"
    assert 1.5 < term.alias_z < 5.0 < term.z  # a term well above zero (z ~ 10) but only a few sigma from its alias
    support = [t for t, c in zip(TERMS, weak.coef[1]) if c != 0]
    rival = [term.alias if t == "y*thetadot^2" else t for t in support]
    windows = [integral_window(1.0 / FPS, dominant_frequency(r["state"][:, 2], 1.0 / FPS)) for r in gen]
    # the least-squares residual is the targets b minus their projection on the columns' span (Q of a thin QR of the
    # design X): rss = |b|^2 - |Q^T b|^2, and b (the positions' alone) is the same for both supports, so the rival's
    # excess is |Q_true^T b|^2 - |Q_rival^T b|^2.  Q^T b is a sum over the runs' rows, accumulated run by run and
    # a few hundred draws at a time (the draws' 8 x 4500 x 4000 positions at once took gigabytes)
    qs = []
    for names in (support, rival):
        columns = [evaluate_library(r["state"])[:, [TERMS.index(t) for t in names]] for r in gen]
        design = [_design([c], [w]) for c, w in zip(columns, windows)]
        q = np.linalg.qr(np.concatenate(design), mode="reduced")[0]
        qs.append(np.split(q, np.cumsum([len(d) for d in design])[:-1]))
    rng = np.random.default_rng(7)
    n_draws, chunk = 4000, 500
    projected = [np.zeros((q[0].shape[1], n_draws)) for q in qs]
    for k, r in enumerate(gen):
        draws = rng.standard_normal((r["t"].size, n_draws))  # the same draws, in the same order, as all at once
        for c in range(0, n_draws, chunk):
            pos = r["state"][:, 2][:, None] + noise.sigma_theta * draws[:, c:c + chunk]
            b = _targets([pos], [windows[k]])
            for q, acc in zip(qs, projected):
                acc[:, c:c + chunk] += q[k].T @ b
    gain = (np.sum(projected[0] ** 2, axis=0) - np.sum(projected[1] ** 2, axis=0)) / noise.sigma_theta ** 2
    # the mean of 4000 draws scatters by 2 alias_z / sqrt(4000) = 0.03 alias_z; allow 10 % of alias_z^2 + 0.3
    assert abs(np.mean(gain) - term.alias_z ** 2) < 0.1 * term.alias_z ** 2 + 0.3
    # a proportion near 0.1 from 4000 draws scatters by 0.005; the normal approximation of the difference of
    # the two sums of squares (its quadratic part neglected) is good to about 0.02 here
    assert abs(np.mean(gain < 0) - float(ndtr(-0.5 * term.alias_z))) < 0.03
    assert term.alias_probability == pytest.approx(float(ndtr(-0.5 * term.alias_z)))


def test_planner_scaling_is_measured_and_consistent(model):
    """The planner's rows at n runs: the median oracle SE over random draws falls like 1/sqrt(n) (measured on the
    draws), and its row at n = n_reference is the oracle of the reference runs themselves."""
    cfg = PlanConfig(duration=2.0, fps=FPS, term="thetaddot:theta*y^2", n_reference=32, run_counts=(8, 16, 32),
                     n_draws=100, seed=3)
    plan = plan_runs(model, NOISE, cfg)
    assert (plan.equation, plan.term) == ("thetaddot", "y^2*theta")
    se = {n: s for n, s, _, _ in plan.table}
    # pooling runs of different amplitudes also breaks near-collinearities, so few runs gain slightly more than
    # 1/sqrt(n) (measured on a pool of 96 runs: 5-7 % for 6-24 runs); 12 % leaves room for the draws' scatter
    assert se[16] / se[32] == pytest.approx(np.sqrt(2), rel=0.12)
    assert se[8] / se[16] == pytest.approx(np.sqrt(2), rel=0.12)
    assert -0.65 < plan.scaling_exponent < -0.42
    gen = generate_runs(model, SyntheticConfig(n_runs=32, duration=2.0, fps=FPS, noise_y=0.0, noise_theta=0.0,
                                               missing_frames=0, seed=3))
    direct = oracle_standard_errors(model, [OracleRun(g["x0"], g["t"].size, 1.0 / FPS) for g in gen], NOISE)
    assert se[32] == pytest.approx(direct.terms["thetaddot"]["y^2*theta"].std_error, rel=1e-9)
    # the closest alias is the reference runs' own, and the runs to tell it apart scale like alias_z^2
    d = direct.terms["thetaddot"]["y^2*theta"]
    assert plan.alias == d.alias and plan.alias_z_reference == pytest.approx(d.alias_z, rel=1e-9)
    assert plan.runs_needed_alias == int(np.ceil(32 * (4.0 / d.alias_z) ** 2))
    # a smaller term (the model changes with it, so does the table): the first row whose median z reaches 5
    small = plan_runs(model, NOISE, replace(cfg, size=5.0 * se[16]))
    assert small.table[0][2] < 5.0 <= small.table[-1][2]
    assert small.runs_needed == next(n for n, _, z, _ in small.table if z >= 5.0)
    # far beyond the table: extrapolated with 1/sqrt(n) from its largest row
    tiny = plan_runs(model, NOISE, replace(cfg, size=0.1 * se[32]))
    n_last, se_last = tiny.table[-1][:2]
    assert tiny.runs_needed == pytest.approx(n_last * (5.0 * se_last / abs(tiny.coefficient)) ** 2, rel=0.01)
    assert tiny.runs_needed_90 == 0


def test_canonical_term_and_noise_levels():
    assert canonical_term("thetaddot:theta*y^2") == ("thetaddot", "y^2*theta")
    assert canonical_term("yddot:1") == ("yddot", "1")
    for bad in ("y^2*theta", "zddot:y", "yddot:y^4"):
        with pytest.raises(ValueError):
            canonical_term(bad)
    with pytest.raises(ValueError):
        NoiseLevels(0.0, 0.003)


def test_tracking_noise_estimate_ignores_glitches(tmp_path, model):
    """Fourth differences, MAD-based: within 5 % of the true noise with 6 glitches of 100 sigma per run (the
    estimate's own scatter over ~12000 frames is ~1.2 %; the glitches touch 0.25 % of the differences)."""
    write_dataset(tmp_path, model, SyntheticConfig(n_runs=4, duration=2.0, fps=FPS, noise_y=NOISE.sigma_y,
                                                   noise_theta=NOISE.sigma_theta, missing_frames=0, seed=1))
    rng = np.random.default_rng(0)
    for f in sorted(tmp_path.glob("run*.csv")):
        lines = f.read_text().splitlines()
        for i in rng.choice(np.arange(30, len(lines) - 30), size=6, replace=False):
            t, y, th = lines[i].split(",")
            lines[i] = f"{t},{float(y) + rng.choice([-1, 1]) * 100 * NOISE.sigma_y:.6e},{th}"
        f.write_text("\n".join(lines) + "\n")
    prepared, _ = prepare_runs(load_dataset(tmp_path).runs)
    est = estimate_tracking_noise([p.run for p in prepared])
    assert est.sigma_y == pytest.approx(NOISE.sigma_y, rel=0.05)
    assert est.sigma_theta == pytest.approx(NOISE.sigma_theta, rel=0.05)


def test_plan_cli(tmp_path, model, capsys):
    path = tmp_path / "model.json"
    path.write_text(json.dumps(model.to_json()))
    args = ["plan", "--model", str(path), "--noise-y", "1.5e-6", "--noise-theta", "0.003", "--duration", "1",
            "--fps", "1500", "--runs", "4", "8", "--reference-runs", "6"]
    assert main(args + ["--term", "thetaddot:y^2*theta"]) == 0
    out = capsys.readouterr().out
    rows = [line.split() for line in out.splitlines() if line.split() and line.split()[0].isdigit()]
    assert [r[0] for r in rows] == ["4", "8"] and float(rows[1][2]) > float(rows[0][2]) > 0
    assert "runs needed for oracle z >= 5" in out and "closest alias: " in out
    # a term outside the model needs a size; an unknown term is one line, exit 2
    assert main(args + ["--term", "thetaddot:theta^3"]) == 2
    assert main(args + ["--term", "thetaddot:theta^5"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 2 and all(e.startswith("error:") for e in err)
    assert main(args + ["--term", "thetaddot:theta^3", "--size", "-300"]) == 0


def test_plan_reads_the_data_sets_recorded_tracking_noise(tmp_path, model, capsys, sine_run, write_csv):
    """--data: the noise the data set's meta.json records (the tracking's block); the oracle SE is linear in the
    noise, so twice the recorded levels give twice the SE of the same plan at the given ones (same reference runs)."""
    path = tmp_path / "model.json"
    path.write_text(json.dumps(model.to_json()))
    common = ["plan", "--model", str(path), "--term", "thetaddot:y^2*theta", "--duration", "1", "--fps", "1500",
              "--runs", "4", "--reference-runs", "6"]

    def first_se() -> float:
        out = capsys.readouterr()
        row = [ln.split() for ln in out.out.splitlines() if ln.split() and ln.split()[0] == "4"][0]
        return float(row[1]), out.err

    assert main(common + ["--noise-y", "1.5e-6", "--noise-theta", "0.003"]) == 0
    given, _ = first_se()
    data = tmp_path / "data"
    data.mkdir()
    write_csv(data / "run01.csv", *sine_run)
    (data / "meta.json").write_text(json.dumps({"tracking": {"noise_y_m": 3e-6, "noise_theta": 0.006}}))
    assert main(common + ["--data", str(data)]) == 0
    recorded, err = first_se()
    assert recorded == pytest.approx(2 * given, rel=1e-3)  # 4 significant digits printed
    assert "sigma_y = 3e-06 m, sigma_theta = 0.006 (recorded by the tracking in" in err
    # without a record: estimated from the runs (a clean sine run: the estimate is tiny but positive), and named so
    (data / "meta.json").write_text("{}")
    assert main(common + ["--data", str(data)]) == 0
    assert "estimated from the runs of" in first_se()[1]
    # neither levels nor a data set: one line, exit 2
    assert main(common) == 2
    assert "give --noise-y and --noise-theta, or --data DATA_DIR" in capsys.readouterr().err


def test_replacement_rss_is_the_least_squares_residual_of_the_replacement():
    """From the Gram matrix alone, the residual of a contribution projected on other columns equals the direct least
    squares residual (columns spanning six decades, as the SI columns do); with its own columns it is 0."""
    from fitting.uncertainty.oracle import replacement_rss

    rng = np.random.default_rng(4)
    X = rng.standard_normal((400, 5)) * np.array([1e-6, 1.0, 1e3, 1.0, 1e-3])
    X[:, 3] += 0.9 * X[:, 1]  # a correlated rival
    c = np.array([2.0, -1e-3])
    signal = X[:, [1, 2]] @ c
    basis = [0, 3, 4]
    direct = float(np.sum((signal - X[:, basis] @ np.linalg.lstsq(X[:, basis], signal, rcond=None)[0]) ** 2))
    gram = X.T @ X
    assert replacement_rss(gram, [1, 2], c, basis) == pytest.approx(direct, rel=1e-8)
    assert replacement_rss(gram, [1, 2], c, []) == pytest.approx(float(signal @ signal), rel=1e-12)
    # the Schur complement cancels to rounding: ~1e-16 of the signal's sum of squares times the conditioning
    assert replacement_rss(gram, [1, 2], c, [0, 1, 2]) < 1e-10 * float(signal @ signal)
