"""Section 1, the data: the runs, their spectra's peaks and attractor classes."""
from __future__ import annotations

import numpy as np

from cubedimer.attractors import ClassifyConfig

from ..claims import PHASE_LINE_FRACTION, run_phase
from ..context import ReportContext
from ..html import Figure, Section, Table

__all__ = ["section", "RUN_COLUMNS", "run_columns", "class_definition"]


def class_definition(classify: ClassifyConfig) -> str:
    """The runs table's class column, with the classifier's tolerances, so that a run labelled ``independent`` at a
    phase near 0 or 180 degrees reads as what it is."""
    phase = np.degrees(classify.phase_tol)
    return (f"the attractor class of the run's second half (docs/fitting.md): theta-at-rest when theta's amplitude is "
            f"below {classify.theta_rest:g}; locked when theta's frequency lies within {100 * classify.lock_tol:g} % of "
            f"f_y and theta's phase at the crossings of y = 0 keeps a coherence of at least {classify.coherence_min:g} (1: "
            f"a perfect lock; a p:q lock, up to order {classify.max_lock_order}, the same for its ratio): in phase within "
            f"{phase:.0f} deg of 0, anti-phase within {phase:.0f} deg of 180, quadrature in between; independent "
            "otherwise, whatever the phase column shows (a phase near 0 or 180 deg with a coherence below "
            f"{classify.coherence_min:g}, or a frequency off f_y, is a drifting phase, not a lock)")


def run_columns(classify: ClassifyConfig) -> dict[str, str]:
    """What each column of the runs table holds, the class with ``classify``'s tolerances."""
    return {"class": class_definition(classify), **_COLUMNS}


#: the runs table's columns other than the class
_COLUMNS = {
    "coherence": "length of the circular mean of theta's phase at the crossings of y = 0 (1: locked, near 0: "
                 "drifting); what the class compares with its threshold",
    "f_y [Hz]": "the peak of the zero-padded spectrum of y", "f_theta [Hz]": "the same for theta",
    "resolution [Hz]": "1/duration of the run, the spacing of independent spectral values",
    "amplitude y [um]": "half the range between the 1 % and 99 % quantiles of the smoothed y over the run's second half "
                        "(the late motion, after the decay from the drop)",
    "amplitude theta": "the same for theta [-]",
    "phase [deg]": f"phase of theta relative to y at f_y from their cross spectrum over the run's second half; given only "
                   f"where theta's line at f_y reaches {PHASE_LINE_FRACTION:g} of its largest spectral line (blank: theta "
                   "has no line at f_y, so there is no phase)",
}

#: the runs table's columns with the fit's default classifier
RUN_COLUMNS = run_columns(ClassifyConfig())


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
        f"{len(prepared)} runs ({len(context.model_json.get('skipped_files') or [])} files skipped as unreadable or invalid). The vertical motion's spectrum "
        f"peaks at a median {fy:.2f} Hz and {ft_text} (peaks of the zero-padded spectra; runs of "
        f"{1 / resolution:.3g} s resolve {resolution:.2g} Hz); the spectra show whether theta carries the y frequency and "
        "its second harmonic (theta locked to y). The runs fall into the attractor classes "
        + ", ".join(f"{k} ({v})" for k, v in classes.items()) + ", read from the phase of theta relative to y at f_y.",
        [Figure(p, c) for p, c in dfig],
        [Table("Runs (frequencies: peaks of the zero-padded spectra, each run resolving 1/duration)",
               ["file", "class", "coherence", "f_y [Hz]", "f_theta [Hz]", "resolution [Hz]", "amplitude y [um]", "amplitude theta",
                "phase [deg]"],
               [[p.run.name, p.attractor.label, p.attractor.coherence, py[0], pt[0], py[1], p.attractor.amp_y * 1e6,
                 p.attractor.amp_theta, _late_phase(p)] for p, (py, pt) in zip(prepared, peaks)],
               run_columns(context.classify))],
        {"n_runs": len(prepared), "classes": classes, "median_f_y_hz": fy, "median_f_theta_hz": ft,
         "frequency_resolution_hz": resolution})
