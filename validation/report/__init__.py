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

from .html import Figure, Section, Table, format_number, write_report

__all__ = ["build_report", "write_report", "Figure", "Section", "Table", "format_number", "check_report_in_browser"]


def __getattr__(name: str):
    if name == "build_report":
        from .pipeline import build_report

        return build_report
    if name == "check_report_in_browser":
        from .browser_check import check_report_in_browser

        return check_report_in_browser
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
