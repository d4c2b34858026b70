"""The fit's settings: the shared stages and each method's own settings, and what the options set on them."""
from __future__ import annotations

import pytest

from fitting.config import DiscoveryMethodConfig, FitConfig, PaperMethodConfig
from fitting.method_names import method_options, methods_accepting
from fitting.refinement.long_time import JOINT_REFINE


@pytest.mark.parametrize("name, main", [("discovery", "polish"), ("paper", "refine")])
def test_max_evals_set_the_method_s_own_refinement_and_joint_only_when_asked(name, main):
    """``--max-evals`` is the method's main long-time refinement (``max_evals_setting``); the report's ``max_evals``
    also sets the joint re-optimisation; nothing else of the settings changes."""
    base = FitConfig.for_method(name)
    cfg = base.with_max_evals(7)
    assert getattr(cfg.method, main).max_evals == 7 and cfg.method.max_evals_setting == main
    assert cfg.method.joint == base.method.joint == JOINT_REFINE
    both = base.with_max_evals(7, joint=True)
    assert (getattr(both.method, main).max_evals, both.method.joint.max_evals) == (7, 7)
    assert base.with_max_evals(None) == base
    assert (cfg.load, cfg.smoothing, cfg.classify) == (base.load, base.smoothing, base.classify)


def test_each_method_option_is_accepted_by_the_methods_that_list_it_and_refused_by_the_others():
    """Every method-specific option belongs to at least one method's settings, and a method whose settings do not
    list it refuses it in one line naming the methods that take it."""
    values = {"max_evals": 7, "joint_max_evals": 9, "heldout_tolerance": 0.002, "output_error": "refine",
              "max_terms": 3, "selection": "zscore", "relative_threshold": True}
    assert set(values) == set(method_options())
    for option, value in values.items():
        assert methods_accepting(option)
        for name in ("discovery", "paper"):
            cfg = FitConfig.for_method(name)
            if cfg.method.command_option(option) is not None:
                assert cfg.with_method_option(option, value) != cfg
            else:
                with pytest.raises(ValueError, match=f"^applies to --method {', '.join(methods_accepting(option))}$"):
                    cfg.with_method_option(option, value)
    assert FitConfig().with_heldout_tolerance(0.002).method.selection.heldout_tolerance == 0.002
    assert FitConfig.for_method("paper").with_method_option("relative_threshold", True).method.regression.relative_threshold
    with pytest.raises(ValueError, match=r"1\.5: needs a fraction in \[0, 1\)"):
        FitConfig().with_heldout_tolerance(1.5)


def test_the_method_s_settings_are_its_own():
    """The discovery's settings hold no paper-only step and the other way round; FitConfig takes a method's settings,
    not its name."""
    assert FitConfig().method == DiscoveryMethodConfig() and FitConfig().method_name == "discovery"
    assert not hasattr(DiscoveryMethodConfig(), "refine") and not hasattr(DiscoveryMethodConfig(), "candidate_joint")
    assert not hasattr(PaperMethodConfig(), "polish")
    with pytest.raises(ValueError, match="FitConfig: method must be the settings of a registered method"):
        FitConfig(method="paper")
