"""The model-vs-simulation report: its numbers, figures, HTML and the headless-browser check.

* :mod:`validation.report.build`: :func:`build_report` runs the fit, the variant comparison and the diagnosis
  of a data set and stores their results; :func:`render_report` makes the report from a finished run's stored
  results (a view: nothing is fitted or simulated again);
* :mod:`validation.report.context`: :class:`~validation.report.context.ReportContext`, everything the sections read,
  filled from the stored results (:func:`~validation.report.context.load_context`);
* :mod:`validation.report.sections`: one module per section (data, tracking, phase space, fit, simulation, model vs
  simulation, diagnosis, scattering, atlas), each ``section(context)``, in the order of ``SECTIONS``;
* :mod:`validation.report.figures`: the report's figures of the data and the fitted model;
* :mod:`validation.report.html`: the self-contained HTML writer (:func:`write_report`);
* :mod:`validation.report.browser_check`: render a report in headless Chromium and check it.
"""
from __future__ import annotations

from cubedimer.lazy import lazy_attributes

from .html import Figure, Section, Table, format_number, write_report

__all__ = ["build_report", "render_report", "write_report", "write_diagnosis", "Figure", "Section", "Table", "format_number",
           "check_report_in_browser"]


__getattr__ = lazy_attributes(__name__, {"build_report": ".build", "render_report": ".build", "write_diagnosis": ".sections.gap_diagnosis",
                                         "check_report_in_browser": ".browser_check"})
