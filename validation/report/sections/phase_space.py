"""Section 2, phase space: the data against the minimal model, and its long-time errors."""
from __future__ import annotations

from ..claims import long_time_reading
from ..context import ReportContext
from ..html import Figure, Section

__all__ = ["section"]


def section(context: ReportContext) -> Section:
    """The phase-space figures of the data and the model, and the reading of its long-time errors."""
    from ..figures import phase_space_figures

    pfig = phase_space_figures(context.prepared, context.fit_model, context.figs_dir)
    loss = context.model_json["loss"]["final"]
    fit_dir = context.fit_dir
    return Section(
        "phase-space", "2. Phase space",
        long_time_reading(loss),
        [Figure(p, c) for p, c in pfig] + [Figure(fit_dir / "phase_portraits.png", "Phase portraits (y, ydot) and (theta, thetadot): data and minimal model, first runs."),
                                           Figure(fit_dir / "poincare.png", "Poincare maps (theta, thetadot at y = 0, ydot < 0): data and minimal model.")],
        [], {"loss_final": loss})
