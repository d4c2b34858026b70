"""How well the data determine a fitted model.

* :mod:`~fitting.uncertainty.oracle`: the oracle standard errors of integral-form least squares on a support, the
  closest library aliases, the recorded tracking noise;
* :mod:`~fitting.uncertainty.final_checks`: what every method does to its final model (the fallback when it blows
  up, its oracle standard errors);
* :mod:`~fitting.uncertainty.run_planning`: how many runs make a term resolvable (``python -m fitting plan``).
"""
