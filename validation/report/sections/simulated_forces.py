"""Section 4, the simulation: the calibrated reference model (and every other compared model beside it) against the
measured accelerations, and the posed dimer mesh."""
from __future__ import annotations

from ..claims import gap_value
from ..context import ReportContext
from ..html import Figure, Section

__all__ = ["section", "hinge_reading", "PREDICTS_NOTHING"]

#: The overlay's colours after the reference model's blue (restoring_overlay_figure).
_COLOURS = ("red", "green")

#: A gap component of 1 is the fraction left unexplained by predicting no acceleration at all.
PREDICTS_NOTHING = 1.0


def hinge_reading(label: str, theta_gap: float, reference_label: str, reference_theta_gap: float,
                  scattering_theta_gap: float | None) -> str:
    """What a model with no fitted stiffness does with the hinge, from its theta-equation gap (section 7): it holds
    the hinge (the gap is small), or it does not, and how badly (above 1: worse than predicting no hinge acceleration
    at all), beside the reference model alone and with fitted pair scattering."""
    def shown(gap: float) -> str:
        value = gap_value(gap, None)  # a component below the subtracted noise floor is said so, never negative
        return value if isinstance(value, str) else f"{value:.3g}"

    beside = (f"; the {reference_label} model leaves {shown(reference_theta_gap)}"
              + (f", and {shown(scattering_theta_gap)} with the pair scattering fitted"
                 if scattering_theta_gap is not None else ""))
    if theta_gap > PREDICTS_NOTHING:
        return (f"its hinge torque, from its own physics with no fitted stiffness, does not hold these data's hinge: its "
                f"theta equation leaves {theta_gap:.3g} of the hinge accelerations' variance unexplained, more than "
                f"predicting no hinge acceleration at all would (1){beside}. The data's hinge is held by a stiffness its "
                "physics does not give at this hinge gap")
    if theta_gap > 0.1:
        return (f"its hinge torque, from its own physics with no fitted stiffness, explains part of the hinge motion: "
                f"its theta equation leaves {theta_gap:.3g} of the variance unexplained{beside}")
    return (f"it holds the hinge with no fitted stiffness: its theta equation leaves {theta_gap:.3g} of the variance "
            f"unexplained{beside}")


def _given(o) -> str:
    """What a model was given beside the experiment's constants: its own parameters and where each came from."""
    sources = o.record.parameter_sources or {}
    parts = [f"hinge {n.rsplit('_', 1)[0]} {v * 1e6:.2f} um ({sources.get(n, 'given')})" if n.endswith("_m") else
             f"{n} {v:.4g} ({sources.get(n, 'given')})" for n, v in (o.record.parameters or {}).items()]
    return f"; given {', '.join(parts)}" if parts else ""


def section(context: ReportContext) -> Section:
    """The restoring-force overlay of the calibrated simulations, the rendered mesh and the calibrated pressure."""
    from acousim.models import force_model_names, force_model_type

    from ..figures import restoring_overlay_figure

    ref, figs_dir = context.reference, context.figs_dir
    rec = ref.record
    delta = rec.origin_offset_m
    overlay = restoring_overlay_figure([(s.record.curves, s.record.origin_offset_m, s.label)
                                        for s in context.simulations], context.prepared, figs_dir)
    figures = [Figure(*overlay)]
    render = figs_dir / f"dimer_{ref.name}.png"
    if render.exists():
        figures.append(Figure(render, f"The posed dimer mesh (theta = 0.3) coloured by the {ref.label} potential "
                                      "density u."))
    rows = {r.model: r for r in context.models.rows}
    ref_row = rows.get(ref.name)
    scattering = next((r for k, r in rows.items() if k.startswith(f"{ref.name}+")), None)
    others_text = ""
    for o, colour in zip(context.others, _COLOURS):
        r = o.record
        others_text += (f" Beside it ({colour}) the {o.label} model, calibrated the same way ({r.pressure_amplitude_pa:.0f} "
                        f"Pa{_given(o)}; the data's y origin lies {r.origin_offset_m * 1e6:+.2f} um above the {o.label} "
                        f"model's calibrated Z_eq, against {delta * 1e6:+.2f} um above the {ref.label} model's "
                        "calibrated Z_eq)")
        row = rows.get(o.name)
        others_text += (": " + hinge_reading(o.label, row.components[1], ref.label, ref_row.components[1],
                                             None if scattering is None else scattering.components[1]) + "."
                        if row is not None and ref_row is not None else ".")
    others_text += "".join(f" The {force_model_type(n).label} model is not shown: {why}."
                           for n, why in context.unavailable().items())
    pressures = {o.name: o.record.pressure_amplitude_pa for o in context.others}
    return Section(
        "simulation", "4. The simulation",
        f"The {ref.label} model at the calibrated pressure {rec.pressure_amplitude_pa:.0f} Pa (nominal "
        f"{rec.nominal_pressure_pa:.0f} Pa) holds the dimer {abs(rec.model_equilibrium_height_m) * 1e6:.0f} um below "
        "the node. Its restoring force follows the measured vertical accelerations; where the measured hinge "
        "accelerations lie far outside the model's torque curve, the hinge is held by something the model omits."
        + others_text,
        figures, [],
        {"calibrated_pressure_pa": rec.pressure_amplitude_pa, "equilibrium_height_m": rec.model_equilibrium_height_m,
         # every other registered model's, None where it is not compared
         **{f"{n}_calibrated_pressure_pa": pressures.get(n) for n in force_model_names()[1:]}})
