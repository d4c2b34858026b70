"""Section 1, the data: the runs, their spectra's peaks and attractor classes."""
from __future__ import annotations

import numpy as np

from ..claims import PHASE_LINE_FRACTION, run_phase
from ..context import ReportContext
from ..html import Figure, Section, Table

__all__ = ["section", "RUN_COLUMNS"]

#: what each column of the runs table holds
RUN_COLUMNS = {
    "class": "the attractor class of the run's second half (docs/fitting.md), from theta's frequency and its phase "
             "relative to y",
    "f_y [Hz]": "the peak of the zero-padded spectrum of y", "f_theta [Hz]": "the same for theta",
    "resolution [Hz]": "1/duration of the run, the spacing of independent spectral values",
    "amplitude y [um]": "half the range between the 1 % and 99 % quantiles of the smoothed y over the run's second half "
                        "(the late motion, after the decay from the drop)",
    "amplitude theta": "the same for theta [-]",
    "phase [deg]": f"phase of theta relative to y at f_y from their cross spectrum over the run's second half; given only "
                   f"where theta's line at f_y reaches {PHASE_LINE_FRACTION:g} of its largest spectral line (blank: theta "
                   "has no line at f_y, so there is no phase)",
}


def _late_phase(p) -> float | None:
    """The runs table's phase: over the stretch the attractor was classified on (the run's second half)."""
    d = p.derivs
    half = len(d.t) // 2
    return run_phase(d.state[half:, 2], float(d.t[1] - d.t[0]), p.attractor.f_y, p.attractor.phase)


def section(context: ReportContext) -> Section:
    """The runs, how many were skipped, the median spectral peaks and the attractor classes."""
    from cubedimer.spectra import peak_frequency

    from ..figures import data_figures

    prepared = context.prepared
    dfig = data_figures(prepared, context.figs_dir)
    classes: dict[str, int] = {}
    for p in prepared:
        classes[p.attractor.label] = classes.get(p.attractor.label, 0) + 1
    peaks = [(peak_frequency(p.run.y, p.run.dt), peak_frequency(p.run.theta, p.run.dt)) for p in prepared]
    fy = float(np.median([py[0] for py, _ in peaks]))
    ft = float(np.median([pt[0] for _, pt in peaks]))
    resolution = float(max(py[1] for py, _ in peaks))  # of the shortest run
    # a peak closer to 0 than two resolution widths (the Hann main lobe) is not resolved from the slow motion
    ft_text = (f"the hinge's spectrum peaks at a median {ft:.2f} Hz" if ft >= 2 * resolution else
               f"the hinge's spectrum peaks at a median {ft:.2f} Hz, within two resolution widths of 0 Hz, so the runs are "
               "too short to resolve the hinge frequency")
    return Section(
        "data", "1. The data",
        f"{len(prepared)} runs ({len(context.fit.skipped)} files skipped as unreadable or invalid). The vertical motion's spectrum "
        f"peaks at a median {fy:.2f} Hz and {ft_text} (peaks of the zero-padded spectra; runs of "
        f"{1 / resolution:.3g} s resolve {resolution:.2g} Hz); the spectra show whether theta carries the y frequency and "
        "its second harmonic (theta locked to y). The runs fall into the attractor classes "
        + ", ".join(f"{k} ({v})" for k, v in classes.items()) + ", read from the phase of theta relative to y at f_y.",
        [Figure(p, c) for p, c in dfig],
        [Table("Runs (frequencies: peaks of the zero-padded spectra, each run resolving 1/duration)",
               ["file", "class", "f_y [Hz]", "f_theta [Hz]", "resolution [Hz]", "amplitude y [um]", "amplitude theta",
                "phase [deg]"],
               [[p.run.name, p.attractor.label, py[0], pt[0], py[1], p.attractor.amp_y * 1e6,
                 p.attractor.amp_theta, _late_phase(p)] for p, (py, pt) in zip(prepared, peaks)],
               RUN_COLUMNS)],
        {"n_runs": len(prepared), "classes": classes, "median_f_y_hz": fy, "median_f_theta_hz": ft,
         "frequency_resolution_hz": resolution})
