"""The coefficients of a selected model, refined on what the trajectories do over many periods.

* :mod:`~fitting.refinement.long_time`: the long-time refinement with nlopt (:class:`RefineConfig`);
* :mod:`~fitting.refinement.losses`: the long-time loss (attractor shape, Poincare map, frequency), with the
  nearest-point distances of :mod:`~fitting.refinement.nearest`;
* :mod:`~fitting.refinement.model_states`: model-based state estimates (each stretch of a run replaced by the model's
  own trajectory);
* :mod:`~fitting.refinement.output_error`: output-error refinement, with its term pruning and additions in
  :mod:`~fitting.refinement.output_error_support`.
"""
