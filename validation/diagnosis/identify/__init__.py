"""Step 2, identify: which candidate effects the data demand, by held-out significance.

* :mod:`~validation.diagnosis.identify.statistics`: the sign-flip and Wilcoxon tests, the p-value format;
* :mod:`~validation.diagnosis.identify.folded`: the K-fold gaps of a fitted model;
* :mod:`~validation.diagnosis.identify.identification`: held-out (K-fold) identification with practical thresholds;
* :mod:`~validation.diagnosis.identify.elimination`: the backward check of the identified effects;
* :mod:`~validation.diagnosis.identify.output_error`: the velocity coupling judged on the runs' whole trajectories
  beside a damping (an output-error fit with the air's damping law).
"""
