"""The fitting methods and their registry: what ``--method`` and :class:`fitting.config.FitConfig` ``method`` choose
(the table of names itself is :mod:`fitting.method_names`, which imports nothing of the fitting).

* :mod:`~fitting.methods.registry`: the :class:`~fitting.methods.registry.FittingMethod` protocol,
  :class:`~fitting.methods.registry.FitContext` and :func:`~fitting.methods.registry.register_method`;
* :mod:`~fitting.methods.discovery`: the default method, integral-form discovery with its long-time polish;
* :mod:`~fitting.methods.paper`: the source paper's method, per-run SINDy, ensemble selection and joint fit.

A method runs the steps below it: :mod:`fitting.derivatives` -> :mod:`fitting.selection` -> :mod:`fitting.refinement`
-> :mod:`fitting.uncertainty`.
"""
