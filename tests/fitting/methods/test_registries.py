"""The fit's extension points keep their promise: a method or a selection rule registered once is chosen by name
everywhere (FitConfig, fit_runs, the fit command's choices, model.json), and unknown names fail before any work."""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np
import pytest

from fitting.methods import registry as methods
from fitting.selection import rules as selection_rules
from fitting.cli import build_parser, main
from fitting.config import FitConfig, MethodConfig, PaperMethodConfig
from fitting.description import DescriptionTable, MethodDescription, model_equation_text
from fitting.selection.ensemble import EnsembleConfig, least_squares_on_support, select_terms, term_statistics
from fitting.output.model_file import model_json
from fitting.model import TERMS, PolynomialModel, damping_mask
from fitting.fit import fit_dataset
from fitting.refinement.long_time import RefineConfig, refine
from fitting.selection.sparse_regression import scaled_data
from fitting.results import EnsembleExtras, FitResult, RunEstimate
from fitting.selection.rules import SelectionConfig

#: yddot = y + ydot, thetaddot = theta + thetadot: the linear oscillator, the support of the dummy method
LINEAR = np.zeros((2, len(TERMS)), bool)
LINEAR[0, [TERMS.index("y"), TERMS.index("ydot")]] = True
LINEAR[1, [TERMS.index("theta"), TERMS.index("thetadot")]] = True


@dataclass(frozen=True)
class LinearConfig(MethodConfig):
    """The dummy method's own settings: the ensemble's z-score rule it reports and its joint refinement."""

    name: ClassVar[str] = "dummy-linear"
    ensemble: EnsembleConfig = field(default_factory=EnsembleConfig)
    joint: RefineConfig = field(default_factory=lambda: RefineConfig(max_evals=4, horizons=(1.0,)))


@dataclass(frozen=True)
class LinearMethod:
    """A dummy method: least squares of the linear oscillator, pooled and per run, a 4-evaluation polish."""

    name: str = "dummy-linear"
    summary: str = "least squares of the linear oscillator (test)"
    config_type: type = LinearConfig

    def fit(self, prepared, scales, config, context) -> FitResult:
        derivs = [p.derivs for p in prepared]
        X, A = scaled_data(derivs, scales)
        pooled = PolynomialModel(scales.to_si(least_squares_on_support(X, A, LINEAR)))
        joint = refine(pooled, derivs, scales, config.method.joint, mask=LINEAR)
        runs = [RunEstimate(p.run.name, PolynomialModel(scales.to_si(least_squares_on_support([X[k]], [A[k]], LINEAR))),
                            joint.per_run_start[k]) for k, p in enumerate(prepared)]
        stats = term_statistics([r.model for r in runs])
        return FitResult(runs=list(prepared), scales=scales, pooled_regression=pooled, run_fits=runs,
                         mask=LINEAR.copy(), joint_start=pooled, joint=joint, config=config,
                         extras=EnsembleExtras(stats, select_terms(stats, config.method.ensemble)))

    def describe(self, result) -> MethodDescription:
        eqs = result.model.equations()
        return MethodDescription("Least squares of the linear oscillator gives " + "; ".join(model_equation_text(eqs)),
                                 DescriptionTable("Linear model (SI)", ("equation", "term", "coefficient"),
                                                  tuple((eq, t, c) for eq in eqs for t, c in eqs[eq].items())),
                                 figures=(), selected_by="by construction")


@dataclass(frozen=True)
class DampingOnlyRule:
    """A dummy rule: keeps the candidates' damping terms and the restoring y and theta terms."""

    name: str = "dummy-restoring"
    summary: str = "the damping and the linear restoring terms (test)"
    methods: tuple[str, ...] = ("paper",)
    description: str = "the damping and the linear restoring terms"
    selected_by: str = "as damping or linear restoring terms"

    def eliminates(self, config) -> bool:
        return False

    def support(self, evidence, config):
        return (LINEAR & evidence.candidates) | damping_mask()


@pytest.fixture
def dummy_method():
    method = methods.register_method(LinearMethod())
    yield method
    del methods.METHODS[method.name]  # registered for this test only


@pytest.fixture
def dummy_rule():
    rule = selection_rules.register_selection_rule(DampingOnlyRule())
    yield rule
    del selection_rules.SELECTION_RULES[rule.name]


def test_the_builtin_entries_and_the_command_choices_come_from_the_registries():
    assert tuple(methods.METHODS) == ("discovery", "paper") and methods.DEFAULT_METHOD == "discovery"
    assert selection_rules.selection_rule_names() == ("significance", "zscore", "backward")
    assert selection_rules.selection_rule_names("discovery") == ()  # the discovery selects its own terms
    fit = build_parser()._subparsers._group_actions[0].choices["fit"]
    choices = {a.dest: a.choices for a in fit._actions if a.choices}
    assert tuple(choices["method"]) == tuple(methods.METHODS)
    assert tuple(choices["selection"]) == tuple(selection_rules.SELECTION_RULES)


@pytest.mark.parametrize("bad", [dict(method="sindy"), dict(selection=None)])
def test_unknown_names_fail_on_construction_before_any_work(bad):
    with pytest.raises(ValueError, match="unknown (method|selection rule)"):
        if "method" in bad:
            FitConfig.for_method(bad["method"])
        else:
            SelectionConfig(rule="lasso")


def test_registering_needs_the_protocol():
    with pytest.raises(TypeError, match="not a FittingMethod"):
        methods.register_method(object())
    with pytest.raises(TypeError, match="not a SelectionRule"):
        selection_rules.register_selection_rule(LinearMethod())


def test_a_registered_method_runs_end_to_end_through_the_command(dummy_method, small_dataset, tmp_path):
    out = tmp_path / "out"
    assert main(["fit", str(small_dataset), "--out", str(out), "--method", dummy_method.name, "--no-plots",
                 "--quiet"]) == 0
    d = json.loads((out / "model.json").read_text())
    assert d["method"] == dummy_method.name and d["selection"]["rule"] == dummy_method.name
    assert d["selected_terms"] == {"yddot": ["y", "ydot"], "thetaddot": ["theta", "thetadot"]}
    assert [r["file"] for r in d["per_run"]] == ["run01.csv", "run02.csv", "run03.csv"]
    # the truth's linear restoring coefficients are negative (a trap), and least squares finds that sign
    assert d["equations"]["yddot"]["y"] < 0 and d["equations"]["thetaddot"]["theta"] < 0
    # the method's own settings under its name; the discovery's are left out of another method's record
    assert d["settings"]["method"] == dummy_method.name and d["settings"][dummy_method.name]["joint"]["max_evals"] == 4
    assert "polish" not in d["settings"] and "discovery" not in d["settings"]


@pytest.fixture(scope="module")
def two_short_runs(tmp_path_factory, truth):
    """Two noisy 1-s runs: the least the paper's method fits (its ensemble needs two runs)."""
    from fitting.synthetic import SyntheticConfig, write_dataset

    d = tmp_path_factory.mktemp("two_runs")
    write_dataset(d, truth, SyntheticConfig(n_runs=2, duration=1.0, seed=7))
    return d


def test_a_registered_selection_rule_selects_the_paper_model(dummy_rule, two_short_runs, monkeypatch):
    import fitting.methods.paper as paper_fit

    def no_cross_check(*a, **k):  # the pooled integral-form cross-check (9 s here) plays no part in the selection
        raise ValueError("skipped in this test")

    monkeypatch.setattr(paper_fit, "integral_form_selection", no_cross_check)
    cfg = FitConfig(method=PaperMethodConfig(
        refine=RefineConfig(max_evals=8, horizons=(1.0,)),
        joint=RefineConfig(max_evals=8, rel_bound=0.3, abs_bound=0.005, horizons=(1.0,)),
        selection=SelectionConfig(rule=dummy_rule.name)))
    res = fit_dataset(two_short_runs, cfg, progress=False)
    assert res.extras.rule == dummy_rule.name and model_json(res)["selection"]["rule"] == dummy_rule.name
    assert not (res.mask & ~(LINEAR | damping_mask())).any()  # nothing beyond what the rule allows
    assert res.mask[0, TERMS.index("ydot")] and res.mask[1, TERMS.index("thetadot")]


def test_the_report_describes_a_registered_method_in_its_own_words(dummy_method, small_dataset, tmp_path):
    """Section 3 of the report is the method's own description: the dummy's sentence, table and (no) figures,
    with no word of the paper's method or of the discovery."""
    from fitting.output.model_file import write_fit
    from validation.report.context import ReportContext, fit_description
    from validation.report.sections import fit as fit_section

    res = fit_dataset(small_dataset, FitConfig.for_method(dummy_method.name), progress=False)
    out = tmp_path / "report"
    write_fit(res, out / "fit", plots=False)
    doc = json.loads((out / "fit" / "model.json").read_text())
    # what the report's pipeline gives the view (the method's describe of its result)
    context = ReportContext(
        data_dir=small_dataset, out=out, spec=None, atlas=None, model_json=doc, fit_model=res.model,
        described=fit_description(doc, res), prepared=res.runs, classify=None, variant=None, diagnosis=None,
        meta=None, models=None, simulations=(), theta_max=0.3, y_max=1e-4)
    section = fit_section.section(context)
    eqs = res.model.equations()
    assert section.reading == "Least squares of the linear oscillator gives " + "; ".join(model_equation_text(eqs))
    for words in ("Regression on accelerations", "ensemble rule", "z > 3", "integral-form", "Holm", "Pareto"):
        assert words not in section.reading
    (table,) = section.tables  # no variant comparison: the linear model has no cross-coupling terms
    assert table.title == "Linear model (SI)" and table.header == ["equation", "term", "coefficient"]
    assert table.rows == [["yddot", "y", eqs["yddot"]["y"]], ["yddot", "ydot", eqs["yddot"]["ydot"]],
                          ["thetaddot", "theta", eqs["thetaddot"]["theta"]],
                          ["thetaddot", "thetadot", eqs["thetaddot"]["thetadot"]]]
    assert section.figures == [] and section.numbers["equations"] == context.model_json["equations"]
