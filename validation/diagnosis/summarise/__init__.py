"""Step 4, summarise: the joint model's verdicts, where the rest lies, and the typed result.

* :mod:`~validation.diagnosis.summarise.verdicts`: every candidate's verdict, ranked;
* :mod:`~validation.diagnosis.summarise.cavity_verdicts`: the verdicts beside the levitator's cavity (pair scattering
  within its share of the hinge's stiffness, its mode beside a negative damping of y);
* :mod:`~validation.diagnosis.summarise.localization`: where the residual lies (terms, regions, time scales);
* :mod:`~validation.diagnosis.summarise.long_time`: attractor, Poincare and frequency errors;
* :mod:`~validation.diagnosis.summarise.model_comparison`: the gaps of the registered simulation models side by side;
* :mod:`~validation.diagnosis.summarise.result`: the typed result, ``Diagnosis`` (``to_json``/``from_json``:
  diagnosis.json).
"""
