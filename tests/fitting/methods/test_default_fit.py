"""The default ``fit`` (method "discovery") end to end: it is the default, records itself, meets the criterion of
test_discovery.py on a sparse truth, and survives tracking glitches; ``--method paper`` is the paper's pipeline."""
import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest

from cubedimer.dataset import write_run_csv
from fitting.cli import main
from fitting.model import TERMS, PolynomialModel
from fitting.config import DiscoveryMethodConfig, FitConfig, PaperMethodConfig
from fitting.fit import fit_dataset
from fitting.refinement.long_time import RefineConfig
from fitting.synthetic import SyntheticConfig, generate_runs

# the truths, the oracle and the criterion of test_discovery.py (pytest's importlib mode: load it by path)
_spec = importlib.util.spec_from_file_location(
    "_fitting_test_discovery", Path(__file__).parents[1] / "selection" / "test_discovery.py")
_disc = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_disc)
W_9, _check, _oracle_se, _truth = _disc.W_9, _disc._check, _disc._oracle_se, _disc._truth

# 4 runs of 2 s, the paper's form with every term at oracle z > 10 (test_discovery's small set)
TRUTH = _truth(W_9, {"1": 0.1, "y^2": 9.5e6},
               {"1": 60.0, "y": 1.5e6, "y^2*theta": 2e10, "y*thetadot^2": 5e3, "y*ydot*thetadot": 8e6})
CFG = SyntheticConfig(n_runs=4, duration=2.0, noise_y=1e-6, noise_theta=0.002, missing_frames=0, seed=21)


class _Fitted:
    """model.json's minimal model as (mask, coef) for test_discovery._check."""

    def __init__(self, model_json: dict):
        m = PolynomialModel.from_equations(model_json["equations"])
        self.mask, self.coef = m.support, m.coef


def _write(path, raw, glitches_per_run: int = 0, size: float = 0.0, seed: int = 0):
    """Write runs as CSV; ``glitches_per_run`` isolated frames of y displaced by +-``size`` [m]."""
    rng = np.random.default_rng(seed)
    path.mkdir()
    for i, r in enumerate(raw, 1):
        y = np.array(r["y"], float)
        if glitches_per_run:
            k = rng.choice(np.arange(50, y.size - 50), glitches_per_run, replace=False)
            y[k] += size * rng.choice([-1.0, 1.0], glitches_per_run)
        write_run_csv(path / f"run{i:02d}.csv", r["t"], y, r["theta"], ["test run"], t_decimals=7, y_digits=6,
                      theta_decimals=6, missing="")
    return path


@pytest.fixture(scope="module")
def sparse(tmp_path_factory):
    raw = generate_runs(TRUTH, CFG)
    return _write(tmp_path_factory.mktemp("sparse") / "data", raw), raw


def test_default_fit_is_discovery_records_it_and_meets_the_criterion(sparse, tmp_path, without_front):
    # the held-out front is left out (tests/fitting/conftest.py): test_front.py checks how model.json records it
    data, raw = sparse
    out = tmp_path / "out"
    # 40 evaluations of the polish (default 150) keep the test fast; the polish stays in its +-0.5 SE box anyway
    assert main(["fit", str(data), "--out", str(out), "--no-plots", "--quiet", "--workers", "1",
                 "--max-evals", "40"]) == 0
    d = json.loads((out / "model.json").read_text())
    assert d["method"] == "discovery" and d["settings"]["method"] == "discovery"
    assert d["settings"]["discovery"]["polish"]["max_evals"] == 40
    assert d["selection"]["rule"] == "discovery" and d["discovery"]["converged"]
    assert d["integral_form"]["thetaddot"]["terms"] == d["discovery"]["thetaddot"]["terms"]
    assert d["fallback"] is None and not d["loss"]["final"]["blown_up"]
    # oracle standard error beside every selected term; per-run entries and z-scores as docs/formats.md asks
    for eq, terms in d["equations"].items():
        assert set(d["oracle"][eq]) == set(terms) and all(d["oracle"][eq][t]["std_error"] > 0 for t in terms)
        for t in terms:  # and the closest alias, never closer to zero than the term itself
            o = d["oracle"][eq][t]
            assert o["alias"] in TERMS and o["alias"] not in terms and 0 < o["alias_z"] <= o["z"] * (1 + 1e-9)
    assert len(d["per_run"]) == 4 and len(d["zscores"]["thetaddot"]) == len(TERMS)
    runs = [type("R", (), {"dt": float(r["t"][1] - r["t"][0])}) for r in raw]
    _check(TRUTH, _Fitted(d), _oracle_se(TRUTH, runs, [r["state"] for r in raw], CFG))


def test_default_fit_with_tracking_glitches_meets_the_criterion(tmp_path, without_front):
    # 6 glitches per run with y off by 100 times the tracking noise: masked by the loader, and the discovered
    # model keeps its restoring term (the glitch-free support), integrates over every run and meets the criterion
    raw = generate_runs(TRUTH, CFG)
    data = _write(tmp_path / "glitchy", raw, glitches_per_run=6, size=100 * CFG.noise_y, seed=3)
    res = fit_dataset(data, FitConfig(method=DiscoveryMethodConfig(polish=RefineConfig(max_evals=40))), progress=False)
    assert res.n_glitches >= 6 * CFG.n_runs
    assert res.fallback is None and not res.joint.loss_end.blown_up
    runs = [type("R", (), {"dt": float(r["t"][1] - r["t"][0])}) for r in raw]
    _check(TRUTH, _Fitted({"equations": res.model.equations()}),
           _oracle_se(TRUTH, runs, [r["state"] for r in raw], CFG))


def test_method_is_validated():
    assert FitConfig().method_name == "discovery" and FitConfig.for_method("paper").method_name == "paper"
    assert FitConfig.for_method("paper").method == PaperMethodConfig()
    with pytest.raises(ValueError, match="unknown method 'sindy'"):
        FitConfig.for_method("sindy")
    with pytest.raises(ValueError, match="settings of a registered method"):
        FitConfig(method="paper")  # a name is not the method's settings: FitConfig.for_method("paper")
    with pytest.raises(ValueError, match="polish_se"):
        DiscoveryMethodConfig(polish_se=0.0)
    assert main(["fit", "nowhere", "--out", "x", "--selection", "zscore"]) == 2  # a paper-only option
    assert main(["fit", "nowhere", "--out", "x", "--method", "paper", "--heldout-tolerance", "0.002"]) == 2
    assert main(["fit", "nowhere", "--out", "x", "--heldout-tolerance", "1.5"]) == 2  # a fraction in [0, 1)
    assert main(["fit", "nowhere", "--out", "x", "--method", "paper", "--output-error", "off"]) == 2


@pytest.mark.parametrize("mode, refined, selected",
                         [("select", True, True), ("refine", True, False), ("off", False, False)])
def test_output_error_modes_set_the_discovery_config(mode, refined, selected):
    """``--output-error``: the discovery's coefficients under model error refined with the support selected by the
    output error (the default), refined
    only, or the integral form's; model.json's settings record the choice (fit_output serialises the config)."""
    import dataclasses

    from fitting.config import FitConfig

    cfg = FitConfig().with_output_error(mode)
    oe = cfg.method.selection.output_error
    assert (oe is not None) == refined and (oe is not None and oe.support_tolerance is not None) == selected
    assert (oe == FitConfig().method.selection.output_error) == (mode == "select")
    recorded = json.loads(json.dumps(dataclasses.asdict(cfg), default=float))["method"]["selection"]["output_error"]
    assert (recorded is None) == (not refined)
    with pytest.raises(ValueError):
        FitConfig().with_output_error("polish")
    assert FitConfig().with_output_error(None) == FitConfig()


def test_heldout_tolerance_gives_a_smaller_model_on_the_pareto_front(sparse, tmp_path, without_front):
    """The practical threshold: the smallest support within 30 % of the best held-out error.  Every weak term of
    TRUTH improves the held-out error by far less than that, so the model shrinks, and the written support is one
    of the Pareto front's, with its held-out error within the tolerance of the front's best."""
    data, _ = sparse
    out = tmp_path / "out"
    assert main(["fit", str(data), "--out", str(out), "--no-plots", "--quiet", "--workers", "1", "--max-evals", "20",
                 "--heldout-tolerance", "0.3"]) == 0
    d = json.loads((out / "model.json").read_text())
    assert d["settings"]["discovery"]["selection"]["heldout_tolerance"] == 0.3
    n_true = int(TRUTH.support.sum())
    assert sum(len(t) for t in d["equations"].values()) < n_true
    for eq in ("yddot", "thetaddot"):
        front = d["discovery"][eq]["pareto"]
        chosen = [p for p in front if p["selected"]]
        assert len(chosen) == 1 and set(chosen[0]["terms"]) == set(d["discovery"][eq]["terms"])
        assert chosen[0]["heldout_rms"] <= 1.3 * min(p["heldout_rms"] for p in front)


def test_blown_up_discovery_is_never_written_with_exit_0(sparse, tmp_path, monkeypatch, capsys):
    """A discovery that lost the restoring y term (forced) blows up; every fallback lacks the term: exit 2."""
    import fitting.methods.discovery as discovery_fit
    from fitting.selection.integral_discovery import DiscoveryResult

    data, _ = sparse
    # yddot = 1 + ydot + y^2 drifts away under its constant: every run leaves the blow-up bound
    lost = PolynomialModel.from_equations({"yddot": {"1": 50.0, "ydot": -0.3, "y^2": 9.5e6},
                                           "thetaddot": TRUTH.equations()["thetaddot"]})
    fake = DiscoveryResult(mask=lost.support, coef=lost.coef, std_errors=0.01 * np.abs(lost.coef),
                           residual_std=np.array([CFG.noise_y, CFG.noise_theta]), window_s=np.array([0.03, 0.08]),
                           pareto={"yddot": (), "thetaddot": ()}, iterations=(), converged=True)
    monkeypatch.setattr(discovery_fit, "discover_model", lambda *a, **k: fake)
    out = tmp_path / "out"
    assert main(["fit", str(data), "--out", str(out), "--no-plots", "--quiet", "--max-evals", "30"]) == 2
    assert not (out / "model.json").exists()
    err = capsys.readouterr().err
    assert "blows up on 4 of 4 runs" in err and "no model written" in err
