"""The model-vs-simulation report: its numbers, figures, HTML and the headless-browser check.

* :mod:`validation.report.pipeline`: :func:`build_report` runs the fit, the variant comparison, the
  diagnosis, the calibrated sweeps and the coefficient comparison of a data set and writes the report;
* :mod:`validation.report.figures`: the report's figures of the data and the fitted model;
* :mod:`validation.report.diagnosis_section`: the diagnosis's figures and report section;
* :mod:`validation.report.tracking_section`: the tracking's section when the data set came from video;
* :mod:`validation.report.html`: the self-contained HTML writer (:func:`write_report`);
* :mod:`validation.report.browser_check`: render a report in headless Chromium and check it.
"""
from __future__ import annotations

from cubedimer.lazy import lazy_attributes

from .html import Figure, Section, Table, format_number, write_report

__all__ = ["build_report", "write_report", "write_diagnosis", "Figure", "Section", "Table", "format_number",
           "check_report_in_browser"]


__getattr__ = lazy_attributes(__name__, {"build_report": ".pipeline", "write_diagnosis": ".diagnosis_section",
                                         "check_report_in_browser": ".browser_check"})
