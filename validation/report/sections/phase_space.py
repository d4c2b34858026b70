"""Section 2, phase space: the data against the minimal model, and its long-time errors."""
from __future__ import annotations

from ..claims import long_time_reading
from ..context import ReportContext
from ..html import Figure, Section

__all__ = ["section"]

#: The fit's own phase-space figures (written with model.json), shown when the report directory holds them.
_FIT_FIGURES = (("phase_portraits.png", "Phase portraits (y, ydot) and (theta, thetadot): data and minimal model, first "
                                        "runs."),
                ("poincare.png", "Poincare maps (theta, thetadot at y = 0, ydot < 0): data and minimal model."))


def section(context: ReportContext) -> Section:
    """The phase-space figures of the data and the model, and the reading of its long-time errors."""
    from ..figures import phase_space_figures

    pfig = phase_space_figures(context.prepared, context.fit_model, context.figs_dir)
    loss = context.model_json["loss"]["final"]
    fit_dir = context.fit_dir
    return Section(
        "phase-space", "2. Phase space",
        long_time_reading(loss),
        [Figure(p, c) for p, c in pfig] + [Figure(fit_dir / name, caption) for name, caption in _FIT_FIGURES
                                           if (fit_dir / name).exists()],
        [], {"loss_final": loss})
