"""Before the steps: the runs and the simulation at the measured states, computed once per data set.

* :mod:`~validation.diagnosis.prepare.runs`: runs -> smoothed states, accelerations, noise levels and the
  integral-form data (:func:`~validation.diagnosis.prepare.runs.prepare_diagnosis_runs`, ``RunAccelerations``);
* :mod:`~validation.diagnosis.prepare.problem`: ``DiagnosisProblem``, the model and runs of one data set and what is
  computed once for them;
* :mod:`~validation.diagnosis.prepare.simulation_terms`: the simulation's terms at the measured states;
* :mod:`~validation.diagnosis.prepare.candidate_effects`: the candidate effects as linear regressors.
"""
