"""Section 4, the simulation: the calibrated reference model (and every other compared model beside it) against the
measured accelerations, and the posed dimer mesh."""
from __future__ import annotations

from ..context import ReportContext
from ..html import Figure, Section

__all__ = ["section"]

#: The overlay's colours after the reference model's blue (restoring_overlay_figure).
_COLOURS = ("red", "green")


def section(context: ReportContext) -> Section:
    """The restoring-force overlay of the calibrated simulations, the rendered mesh and the calibrated pressure."""
    from acousim.models import force_model_names, force_model_type

    from ..figures import restoring_overlay_figure

    ref, figs_dir = context.reference, context.figs_dir
    cal, sim, delta = ref.calibration, ref.static, ref.calibration.origin_offset_m
    overlay = restoring_overlay_figure([(s.sweep_plot, s.calibration.origin_offset_m, s.label)
                                        for s in context.simulations], context.prepared, figs_dir)
    figures = [Figure(*overlay)]
    if "render" in force_model_type(ref.name).capabilities:
        from acousim.gorkov.render import render_dimer

        render = render_dimer(sim, 0.3, 0.0, figs_dir / f"dimer_{ref.name}.png")
        figures.append(Figure(render, f"The posed dimer mesh (theta = 0.3) coloured by the {ref.label} potential "
                                      "density u."))
    pressures = {o.name: o.calibration.pressure_amplitude_pa for o in context.others}
    others_text = "".join(
        f" Beside it ({colour}) the {o.label} model, calibrated the same way ({o.calibration.pressure_amplitude_pa:.0f} "
        f"Pa; the data's y origin lies {o.calibration.origin_offset_m * 1e6:+.2f} um above the {o.label} model's "
        f"calibrated Z_eq, against {delta * 1e6:+.2f} um above the {ref.label} model's calibrated Z_eq): it holds the "
        "hinge with no fitted stiffness."
        for o, colour in zip(context.others, _COLOURS))
    others_text += "".join(f" The {force_model_type(n).label} model is not shown: {why}."
                           for n, why in context.unavailable().items())
    return Section(
        "simulation", "4. The simulation",
        f"The {ref.label} model at the calibrated pressure {cal.pressure_amplitude_pa:.0f} Pa (nominal "
        f"{cal.nominal_pressure_pa:.0f} Pa) holds the dimer {abs(sim.equilibrium_height) * 1e6:.0f} um below the node. Its "
        "restoring force follows the measured vertical accelerations; where the measured hinge accelerations lie far "
        "outside the model's torque curve, the hinge is held by something the model omits." + others_text,
        figures, [],
        {"calibrated_pressure_pa": cal.pressure_amplitude_pa, "equilibrium_height_m": sim.equilibrium_height,
         # every other registered model's, None where it is not compared
         **{f"{n}_calibrated_pressure_pa": pressures.get(n) for n in force_model_names()[1:]}})
