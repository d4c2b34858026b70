"""A minimal model whose integration blows up is never written with exit 0: a fallback is used, or exit 2."""
import json

import numpy as np
import pytest

import fitting.methods.paper as paper_fit
import fitting.selection.rules as selection_rules
from fitting.uncertainty.final_checks import MAX_SANE_LOSS
from fitting.cli import main
from fitting.model import TERMS

#: A selection that lost the restoring y term (what tracking glitches were seen to produce): yddot = 1 + y^2 + ydot
#: drifts away under its constant term, so every run's integration leaves the blow-up bound.
NO_RESTORING = {"yddot": ("1", "ydot", "y^2"), "thetaddot": ("1", "y", "theta", "thetadot")}


def _mask(terms):
    m = np.zeros((2, len(TERMS)), bool)
    for q, eq in enumerate(("yddot", "thetaddot")):
        for t in terms[eq]:
            m[q, TERMS.index(t)] = True
    return m


@pytest.fixture
def lost_restoring_term(monkeypatch):
    monkeypatch.setattr(selection_rules, "select_significant_terms", lambda *a, **k: _mask(NO_RESTORING))


FAST = ["--method", "paper", "--no-plots", "--quiet", "--workers", "1", "--max-evals", "24", "--joint-max-evals", "24"]


@pytest.mark.slow
def test_blown_up_minimal_model_falls_back_and_says_so(small_dataset, tmp_path, lost_restoring_term, capsys,
                                                       monkeypatch):
    import fitting.output.model_file as fit_output
    from fitting.methods.registry import get_method

    written = []
    write = fit_output.write_fit
    monkeypatch.setattr(fit_output, "write_fit", lambda res, *a, **k: (written.append(res), write(res, *a, **k))[1])
    out = tmp_path / "out"
    assert main(["fit", str(small_dataset), "--out", str(out)] + FAST) == 0
    d = json.loads((out / "model.json").read_text())
    fb = d["fallback"]
    assert "blows up on 3 of 3 runs" in fb["reason"]
    assert fb["order"] == "ensemble p-value"  # the paper's method has no pooled z of its own
    # the model without its weakest terms and the regression-only ensemble still lack the restoring term and blow up;
    # the pooled integral-form model is the one that integrates
    assert fb["used"] == "pooled integral-form model"
    assert all(c["blown_up_runs"] > 0 for c in fb["candidates"] if c["name"] != fb["used"])
    assert fb["blown_up_model"]["loss"]["blown_up"] and set(fb["blown_up_model"]["equations"]["yddot"]) == set(
        NO_RESTORING["yddot"])
    # what is written integrates over every run, has the restoring term, and selected_terms is its support
    assert not d["loss"]["final"]["blown_up"] and d["loss"]["final"]["total"] < MAX_SANE_LOSS
    assert not any(r["loss_minimal_model"]["blown_up"] for r in d["per_run"])
    assert d["equations"]["yddot"]["y"] < 0
    assert d["selected_terms"] == {eq: list(t) for eq, t in d["equations"].items()}
    # the oracle reports every written term
    assert {eq: set(d["oracle"][eq]) for eq in ("yddot", "thetaddot")} == {eq: set(t) for eq, t in d["equations"].items()}
    assert "fallback used: pooled integral-form model" in capsys.readouterr().err
    # the report's account of the fit says that the minimal model was not written, and what was
    text = get_method("paper").describe(written[0]).text
    assert "gave a minimal model of 7 terms. That model was not written: the re-optimised minimal model (7 terms) " \
           "blows up on 3 of 3 runs." in text
    assert "terms dropped with the largest per-run p-value first): pooled integral-form model, re-optimised" in text


def test_nothing_sane_exits_2_and_writes_no_model(small_dataset, tmp_path, lost_restoring_term, monkeypatch, capsys):
    def too_short(*a, **k):
        raise ValueError("runs shorter than one window")

    monkeypatch.setattr(paper_fit, "integral_form_selection", too_short)  # no pooled integral-form model to fall back on
    out = tmp_path / "out"
    assert main(["fit", str(small_dataset), "--out", str(out)] + FAST) == 2
    assert not (out / "model.json").exists()
    err = [line for line in capsys.readouterr().err.splitlines() if line.startswith("error:")]
    assert len(err) == 1 and "no model written" in err[0]


@pytest.mark.slow
def test_sane_fit_records_no_fallback(small_dataset, tmp_path):
    out = tmp_path / "out"
    assert main(["fit", str(small_dataset), "--out", str(out)] + FAST) == 0
    d = json.loads((out / "model.json").read_text())
    assert d["fallback"] is None and not d["loss"]["final"]["blown_up"]
    for eq, terms in d["equations"].items():
        for t, v in terms.items():
            o = d["oracle"][eq][t]
            assert o["std_error"] > 0 and o["z"] == pytest.approx(abs(v) / o["std_error"])
    assert 0.5e-6 < d["oracle"]["noise"]["sigma_y_m"] < 2e-6  # the data's 1 um noise (SyntheticConfig default)
