"""Section 4, the simulation: the calibrated Gor'kov model (and the full-wave model beside it) against the measured
accelerations, and the posed dimer mesh."""
from __future__ import annotations

from ..context import ReportContext
from ..html import Figure, Section

__all__ = ["section"]


def section(context: ReportContext) -> Section:
    """The restoring-force overlay of the calibrated simulations, the rendered mesh and the calibrated pressure."""
    from acousim.render import render_dimer

    from ..figures import restoring_overlay_figure

    cals, sim, figs_dir = context.calibrations, context.simulation, context.figs_dir
    cal = cals["gorkov"]
    delta = cal.origin_offset_m
    overlay_models = [(context.sweep_plot, delta, "Gor'kov")]
    if context.fullwave_sweep is not None:
        overlay_models.append((context.fullwave_sweep, cals["fullwave"].origin_offset_m, "full-wave"))
    overlay = restoring_overlay_figure(overlay_models, context.prepared, figs_dir)
    render = render_dimer(sim, 0.3, 0.0, figs_dir / "dimer_gorkov.png")
    fw_text = ""
    if context.fullwave_sweep is not None:
        fc = cals["fullwave"]
        fw_text = (f" Beside it (red) the full-wave model, calibrated the same way ({fc.pressure_amplitude_pa:.0f} Pa; the data's "
                   f"y origin lies {fc.origin_offset_m * 1e6:+.2f} um above the full-wave model's calibrated Z_eq, against "
                   f"{delta * 1e6:+.2f} um above the Gor'kov model's calibrated Z_eq): the scattering between the cubes "
                   "holds the hinge with no fitted stiffness.")
    elif context.models.unavailable:
        fw_text = f" The full-wave model is not shown: {context.models.unavailable}."
    return Section(
        "simulation", "4. The simulation",
        f"The Gor'kov model at the calibrated pressure {cal.pressure_amplitude_pa:.0f} Pa (nominal "
        f"{cal.nominal_pressure_pa:.0f} Pa) holds the dimer {abs(sim.equilibrium_height) * 1e6:.0f} um below the node. Its "
        "restoring force follows the measured vertical accelerations; where the measured hinge accelerations lie far "
        "outside the model's torque curve, the hinge is held by something the model omits." + fw_text,
        [Figure(*overlay), Figure(render, "The posed dimer mesh (theta = 0.3) coloured by the Gor'kov potential density u.")],
        [], {"calibrated_pressure_pa": cal.pressure_amplitude_pa, "equilibrium_height_m": sim.equilibrium_height,
             "fullwave_calibrated_pressure_pa": getattr(cals.get("fullwave"), "pressure_amplitude_pa", None)})
