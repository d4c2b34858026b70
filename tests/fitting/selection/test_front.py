"""The front of a discovery (fitting.selection.front): model size against the held-out long-time error, recorded in
model.json and a figure, and ``--max-terms`` picking another point on it."""
from __future__ import annotations

import json

import numpy as np
import pytest

from fitting.cli import main
from fitting.model import PolynomialModel
from cubedimer.folds import run_folds
from cubedimer.terms import evaluate_library
from fitting.model import TERMS
from fitting.selection.front import (Front, FrontPoint, HeldOutRun, capped_support, forward_path, long_time_error,
                                     long_time_error_along, long_time_forward, long_time_front, refined_front)
from fitting.selection.support_search import reduced_design
from fitting.synthetic import SyntheticConfig, generate_runs, write_dataset

FAST = ["--max-evals", "20", "--workers", "1", "--quiet"]


@pytest.fixture(scope="module")
def front_dataset(tmp_path_factory, truth):
    d = tmp_path_factory.mktemp("front_ds")
    write_dataset(d, truth, SyntheticConfig(n_runs=5, duration=2.0, seed=21))
    return d


@pytest.fixture(scope="module")
def default_fit(front_dataset, tmp_path_factory):
    out = tmp_path_factory.mktemp("front_fit")
    assert main(["fit", str(front_dataset), "--out", str(out), *FAST]) == 0
    return out, json.loads((out / "model.json").read_text())


def test_model_json_records_the_front(default_fit, truth):
    out, doc = default_fit
    front = doc["discovery"]["front"]
    assert front["n_folds"] == 5 and front["max_terms"] is None
    points = front["points"]
    caps = [p["max_terms"] for p in points]
    assert caps == sorted(set(caps))  # smallest cap first, one model per cap
    assert all(max(p["n_terms"].values()) <= p["max_terms"] for p in points)
    # every cap evaluated maps to the point that is its model (a cap whose best model is a smaller one's: that one)
    assert {int(c): i for c, i in front["cap_points"].items()}[points[-1]["max_terms"]] == len(points) - 1
    selected = [p for p in points if p["selected"]]
    assert len(selected) == 1
    # the selected point is the model written (before the polish, which keeps the support)
    assert {eq: set(t) for eq, t in selected[0]["terms"].items()} == {eq: set(t) for eq, t in doc["equations"].items()}
    finite = [p for p in points if p["error"] is not None]
    assert all(p["error"] > 0 and len(p["fold_errors"]) == 5 for p in finite)
    assert all(p["error_se"] is None or p["error_se"] >= 0 for p in finite)
    # the error along the runs (restarted from the state estimates every 5 slow periods) on every finite point
    assert all(p["error_along"] is not None and p["error_along"] > 0 and len(p["fold_errors_along"]) == 5
               for p in finite)
    assert "measure_along" in front
    # on a sparse truth the selection (the true support here) predicts the held-out runs better than the
    # damped oscillators alone (2 terms per equation) by far: measured 4-6 % against > 100 %
    smallest = next(p for p in finite if sum(p["n_terms"].values()) <= 4)
    assert selected[0]["error"] < 0.2 < smallest["error"]
    knee = next(p for p in points if p["max_terms"] == front["knee_max_terms"])
    best = min(finite, key=lambda p: p["error"])
    assert knee["error"] <= best["error"] + (best["error_se"] or 0.0)  # the one-standard-error rule
    assert all(sum(p["n_terms"].values()) >= sum(knee["n_terms"].values())
               for p in finite if p["error"] <= best["error"] + (best["error_se"] or 0.0))
    assert (out / "front.png").stat().st_size > 1000


def test_max_terms_picks_the_point_at_that_size(front_dataset, default_fit, tmp_path):
    _, doc = default_fit
    # no figures: what is checked is model.json (test_model_json_records_the_front checks the front's figure)
    assert main(["fit", str(front_dataset), "--out", str(tmp_path), "--max-terms", "3", "--no-plots", *FAST]) == 0
    capped = json.loads((tmp_path / "model.json").read_text())
    assert capped["discovery"]["front"]["max_terms"] == 3
    front = doc["discovery"]["front"]
    point = front["points"][front["cap_points"]["3"]]  # below the selection's size the front orders the caps
    assert all(len(t) <= 3 for t in capped["equations"].values())
    assert {eq: set(t) for eq, t in capped["equations"].items()} == {eq: set(t) for eq, t in point["terms"].items()}
    assert capped["settings"]["discovery"]["selection"]["max_terms"] == 3


def test_max_terms_is_refused_by_the_paper_method(front_dataset, tmp_path, capsys):
    assert main(["fit", str(front_dataset), "--out", str(tmp_path), "--method", "paper", "--max-terms", "3"]) == 2
    assert "--max-terms applies to --method discovery" in capsys.readouterr().err
    assert not (tmp_path / "model.json").exists()


def test_capped_support_shrinks_along_the_path_and_enlarges_only_when_asked():
    path = [(0, 1, 2, 3, 4), (0, 1, 2, 3), (0, 1, 2), (0, 2, 5), (0, 1)]
    held = [1.0, 1.1, 1.3, 1.2, 2.0]
    sel = (0, 2, 5)
    assert capped_support(path, held, sel, 3) == (0, 2, 5)       # the selection fits under the cap
    assert capped_support(path, held, sel, 10) == (0, 2, 5)      # a cap never enlarges by default
    assert capped_support(path, held, sel, 2) == (0, 1)
    assert capped_support(path, held, sel, 1) == (0, 1)          # nothing fits: the smallest on the path
    assert capped_support(path, held, sel, 4, enlarge=True) == (0, 1, 2, 3)
    assert capped_support(path, held, (0, 1, 2, 3, 4), 5, enlarge=True) == (0, 1, 2, 3, 4)  # nothing larger


def test_knee_is_the_smallest_model_within_one_standard_error():
    def pt(n, err, se):
        return FrontPoint(n, {"yddot": tuple(str(i) for i in range(n)), "thetaddot": ()}, err, se, (err,))

    front = Front((pt(1, np.inf, np.nan), pt(2, 0.30, 0.02), pt(3, 0.11, 0.01), pt(4, 0.105, 0.01), pt(5, 0.10, 0.01)), 5)
    assert front.knee.max_terms == 3  # 0.11 <= 0.10 + 0.01, and 0.30 is not
    front = Front((pt(2, 0.30, 0.02), pt(3, 0.12, 0.01), pt(5, 0.10, 0.01)), 5)
    assert front.knee.max_terms == 5


def test_long_time_error_is_zero_for_the_truth_and_dimensionless(truth):
    r = generate_runs(truth, SyntheticConfig(n_runs=1, duration=1.0, noise_y=0.0, noise_theta=0.0, missing_frames=0,
                                             seed=2))[0]
    run = HeldOutRun(float(r["t"][1] - r["t"][0]), r["y"], r["theta"], r["x0"])
    # the generating model: only RK4's step differs (the data at h omega = 0.01, the error at 0.05: a phase error of
    # (h omega)^5 / 120 = 3e-9 per step, ~1e-5 over the run's 3 substeps x 1500 frames)
    assert long_time_error(truth, run) < 1e-4
    slower = PolynomialModel(truth.coef * np.where(truth.support, 0.98, 0.0))
    e = long_time_error(slower, run)
    assert 0.01 < e < 2.0
    scaled = HeldOutRun(run.dt, run.y * 1e3, run.theta, r["x0"] * np.array([1e3, 1e3, 1.0, 1.0]))
    coef = slower.coef.copy()
    from fitting.model import Scales
    assert long_time_error(PolynomialModel(Scales(1e-3, 1.0, 1.0).to_scaled(coef)), scaled) == pytest.approx(e, rel=1e-6)


def test_error_along_the_runs_restarts_from_the_states(truth):
    r = generate_runs(truth, SyntheticConfig(n_runs=1, duration=2.0, noise_y=0.0, noise_theta=0.0, missing_frames=0,
                                             seed=2))[0]
    dt = float(r["t"][1] - r["t"][0])
    horizon = r["t"].size // 6
    run = HeldOutRun(dt, r["y"], r["theta"], r["x0"], r["state"], horizon)
    # the generating model from exact states: only RK4's step differs (as in the test above)
    assert long_time_error_along(truth, run) < 1e-4
    # a 2 % slower model: its phase error grows along a trajectory, so restarting every sixth of the run bounds it
    # below the error from the first state alone (a phase error growing linearly in time: the RMS over a horizon
    # scales with its length, so about 6 times smaller while the error stays below the amplitude)
    slower = PolynomialModel(truth.coef * np.where(truth.support, 0.98, 0.0))
    along, first = long_time_error_along(slower, run), long_time_error(slower, run)
    assert 0.0 < along < first / 3
    # one horizon over the whole run is the error from the first state
    whole = HeldOutRun(dt, r["y"], r["theta"], r["x0"], r["state"], r["t"].size)
    assert long_time_error_along(slower, whole) == pytest.approx(first, rel=1e-12)
    # without states there is no error along the run
    assert np.isnan(long_time_error_along(slower, HeldOutRun(dt, r["y"], r["theta"], r["x0"])))


# two lightly damped, weakly coupled linear oscillators: the best one-term model of each equation is its restoring
# force (the damping alone does not oscillate), which a path that keeps the damping terms cannot reach
W_Y, W_T = 2 * np.pi * 22.0, 2 * np.pi * 9.0
LINEAR = {"yddot": {"y": -W_Y ** 2, "ydot": -0.3, "theta": 1e-5 * W_Y ** 2},
          "thetaddot": {"theta": -W_T ** 2, "thetadot": -0.8, "y": 20.0 * W_T ** 2}}


@pytest.fixture(scope="module")
def linear_front_inputs():
    truth = PolynomialModel.from_equations(LINEAR)
    runs = generate_runs(truth, SyntheticConfig(n_runs=4, duration=1.5, noise_y=1e-7, noise_theta=2e-4,
                                                missing_frames=0, seed=5))
    dts = [float(r["t"][1] - r["t"][0]) for r in runs]
    lib = [evaluate_library(r["state"]) for r in runs]
    win = int(round(0.75 / 9.0 / dts[0]))  # 0.75 periods of the slower mode
    designs = [reduced_design([r[k] for r in runs], lib, dts, [win] * 4, [0] * 4) for k in ("y", "theta")]
    horizon = int(round(5.0 / 9.0 / dts[0]))  # ALONG_HORIZON_PERIODS of the slower mode
    held = [HeldOutRun(dt, r["y"], r["theta"], r["x0"], r["state"], horizon) for dt, r in zip(dts, runs)]
    idx = {t: TERMS.index(t) for t in ("y", "ydot", "theta", "thetadot")}
    sel = [tuple(sorted(TERMS.index(t) for t in LINEAR[eq])) for eq in ("yddot", "thetaddot")]
    # the selection's paths as the discovery makes them: elimination down to the forced damping term
    forced_paths = [[sel[0], tuple(sorted((idx["y"], idx["ydot"]))), (idx["ydot"],)],
                    [sel[1], tuple(sorted((idx["theta"], idx["thetadot"]))), (idx["thetadot"],)]]
    fronts = [(p, [np.nan] * len(p), list(s)) for p, s in zip(forced_paths, sel)]
    return truth, designs, fronts, held, idx


def test_the_front_orders_small_sizes_by_the_long_time_error(linear_front_inputs):
    truth, designs, fronts, held, idx = linear_front_inputs
    restoring = ((idx["y"],), (idx["theta"],))
    assert forward_path(designs[0], 4, 1) == [restoring[0]]  # the restoring force explains the most acceleration
    assert long_time_forward(designs, run_folds(4, 4), held, 4, 1) == [restoring]
    plain = long_time_front(designs, fronts, held, 4, ordered=False)
    ordered = long_time_front(designs, fronts, held, 4)
    one_plain, one = (next(p for p in f.points if p.max_terms == 1) for f in (plain, ordered))
    assert one_plain.terms == {"yddot": ("ydot",), "thetaddot": ("thetadot",)}  # the forced path's one term
    assert one.terms == {"yddot": ("y",), "thetaddot": ("theta",)}
    # the damping alone does not oscillate: its trajectory leaves the motion (measured: it blows up, inf); the
    # undamped oscillators follow the runs with a phase error from the missing damping and coupling (measured 0.42)
    assert one.error < 0.8 < one_plain.error
    assert ordered.supports_at(1) == restoring
    assert ordered.supports_at(2) == tuple(tuple(sorted(TERMS.index(t) for t in p)) for p in
                                           next(p for p in ordered.points if p.max_terms == 2).terms.values())
    assert ordered.supports_at(3) is None  # at the selection's size the selection itself (capped_support)
    assert ordered.selected is not None and ordered.selected.max_terms == 3


def test_refined_front_keeps_a_refinement_only_where_it_predicts_better(linear_front_inputs):
    truth, designs, fronts, held, _ = linear_front_inputs
    front = long_time_front(designs, fronts, held, 4, caps=[3])
    (point,) = front.points
    exact = refined_front(front, lambda c: truth.coef, held).points[0]
    assert exact.refined and np.array_equal(exact.coef, truth.coef)  # the truth predicts the runs better
    worse = refined_front(front, lambda c: 1.05 * c, held).points[0]  # 5 % off every coefficient: worse
    assert not worse.refined and np.array_equal(worse.coef, point.coef)
    assert exact.to_json()["refined"] is True and worse.to_json()["refined"] is False


def test_refined_front_keeps_the_estimate_that_predicts_the_runs_best(linear_front_inputs):
    truth, designs, fronts, held, _ = linear_front_inputs
    front = long_time_front(designs, fronts, held, 4, caps=[3])
    (point,) = front.points
    off = lambda c: 1.05 * c  # noqa: E731  5 % off every coefficient: a 2.5 % frequency error, worse than the fit's

    # an estimate beside the output error (e.g. the accelerations' least squares) that is the truth is kept, and named
    acc = refined_front(front, off, held, {"accelerations": lambda c: truth.coef}).points[0]
    assert acc.estimate == "accelerations" and not acc.refined and np.array_equal(acc.coef, truth.coef)
    assert acc.to_json()["estimate"] == "accelerations"
    # where the output error's is the truth it is kept over a worse estimate; where both are worse the least squares
    oe = refined_front(front, lambda c: truth.coef, held, {"accelerations": off}).points[0]
    assert oe.estimate == "output error" and oe.refined
    plain = refined_front(front, off, held, {"accelerations": off}).points[0]
    assert plain.estimate == "integral form" and np.array_equal(plain.coef, point.coef)

    # an estimate that fails (a singular fit) is no candidate, not the front's error
    def singular(c):
        raise np.linalg.LinAlgError("singular")
    assert refined_front(front, off, held, {"accelerations": singular}).points[0].estimate == "integral form"
    # an estimate's coefficients outside the point's supports are dropped: the support is the front's
    wide = refined_front(front, off, held, {"accelerations": lambda c: truth.coef + 1e-9}).points[0]
    assert np.array_equal(wide.coef != 0, point.coef != 0)
