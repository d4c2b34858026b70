"""The candidates' run planner (``python -m validation plan``).

* :mod:`validation.planner.reference_runs` - a twin configuration's noise-free reference runs for a run design, and
  each run's information for the columns the diagnosis fits (the model's own terms and the candidates);
* :mod:`validation.planner.candidate_plan` - the plan: each fitted parameter's oracle standard error against the
  number of runs and the runs for a relative error, and the alias z of (true, rival) pairs of candidates;
* :mod:`validation.planner.trajectory_oracle` - the standard errors of the velocity coupling's trajectory test on the
  same noise-free runs;
* :mod:`validation.planner.plan_command` - the command.
"""
from .candidate_plan import CandidatePlan, CandidatePlanConfig, PairPlan, ParameterPlan, pair_alias_z, plan_candidates
from .reference_runs import ReferenceRuns, RunDesign, reference_runs

__all__ = ["CandidatePlan", "CandidatePlanConfig", "PairPlan", "ParameterPlan", "pair_alias_z", "plan_candidates",
           "ReferenceRuns", "RunDesign", "reference_runs"]
