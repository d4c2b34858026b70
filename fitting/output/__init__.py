"""The files of a fit, written by the command and not by the fit.

* :mod:`~fitting.output.model_file`: model.json (docs/formats.md), its one reader, and :func:`write_fit`;
* :mod:`~fitting.output.plots`: the figures of a fit and of a comparison.
"""
