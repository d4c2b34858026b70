"""Which library terms a model keeps.

* :mod:`~fitting.selection.integral_discovery`: the discovery method's selection on the pooled integral form with
  model-based column states (:func:`~fitting.selection.integral_discovery.discover_model`), with its settings in
  :mod:`~fitting.selection.discovery_config`;
* :mod:`~fitting.selection.support_search`: the support search on the R factor of the pooled design;
* :mod:`~fitting.selection.sparse_regression`: the paper method's per-run sparse regression (pysindy, C0);
* :mod:`~fitting.selection.ensemble`: statistics over the per-run models and the ensemble's selection;
* :mod:`~fitting.selection.rules`: the registry of the ensemble's selection rules and :class:`SelectionConfig`;
* :mod:`~fitting.selection.backward_elimination`: elimination on the joint long-time loss.

Holm's rule, shared with the integral form, is :mod:`fitting.multiple_testing`.
"""
