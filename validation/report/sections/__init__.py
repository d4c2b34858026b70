"""The report's sections, one module each, in the order the report prints them (:data:`SECTIONS`).

Each module has ``section(context)``: a function of the shared :class:`validation.report.context.ReportContext` that
returns a :class:`validation.report.html.Section`, or None when the data set has nothing for it (the tracking of a
data set not tracked from video, the atlas when none is given).

* :mod:`.answer`: the first screen, the answer (causes, constants, data warnings, force models, one run's time series);
* :mod:`.data`: 1, the runs, their spectra and attractor classes;
* :mod:`.tracking`: the tracking, when the data set came from video;
* :mod:`.phase_space`: 2, the data against the minimal model in phase space;
* :mod:`.fit`: 3, the fitting method's own account of its model (``FittingMethod.describe``) and the variant
  without cross-coupling terms;
* :mod:`.simulation`: 4, the calibrated simulations against the measured accelerations;
* :mod:`.model_vs_simulation`: 5, fitted against simulated static coefficients;
* :mod:`.diagnosis`: 6, the sim-to-real gap (and the diagnose command's own report, :func:`.diagnosis.write_diagnosis`);
* :mod:`.scattering`: 7, the gap with the scattering between the cubes added;
* :mod:`.atlas`: the attractor atlas (``--atlas``).
"""
from __future__ import annotations

from typing import Callable

from ..context import ReportContext
from ..html import Section
from . import (answer, atlas, data, fit, gap_diagnosis, model_vs_simulation, phase_space, scattering, simulated_forces,
               tracking)

__all__ = ["SECTIONS"]

#: (name, section function) in the report's order.
SECTIONS: tuple[tuple[str, Callable[[ReportContext], Section | None]], ...] = (
    ("answer", answer.section),
    ("data", data.section),
    ("tracking", tracking.section),
    ("phase-space", phase_space.section),
    ("fit", fit.section),
    ("simulation", simulated_forces.section),
    ("model-vs-simulation", model_vs_simulation.section),
    ("diagnosis", gap_diagnosis.section),
    ("scattering", scattering.section),
    ("atlas", atlas.section),
)
