"""Section 7, placed after the diagnosis: how far the gap shrinks once the scattering between the cubes is added
(Gor'kov, Gor'kov + fitted pair scattering and the full-wave model, each calibrated alone)."""
from __future__ import annotations

from ..context import ReportContext
from ..html import Section, Table

__all__ = ["section"]


def section(context: ReportContext) -> Section:
    """The gaps of Gor'kov, Gor'kov + fitted pair scattering and the full-wave model side by side."""
    from ...diagnosis.model_comparison import MODEL_LABELS

    models = context.models
    rows = {r.model: r for r in models.rows}
    g0, gp = rows["gorkov"], rows["gorkov+pair_scattering"]
    kappa = gp.params.get("pair_scattering", {}).get("kappa", float("nan"))
    text = (f"How far the gap shrinks once the scattering between the cubes is added. Each simulation is calibrated alone "
            f"(pressure and origin) on the same runs. The Gor'kov model leaves a gap of {g0.gap:.3g}; with the phenomenological "
            f"pair scattering, its stiffness kappa = {kappa:.3g} 1/s^2 fitted, {gp.gap:.3g}.")
    fw = rows.get("fullwave")
    if fw is not None:
        text += (f" The full-wave model, whose hinge comes from the boundary-element solution with no fitted stiffness, "
                 f"leaves {fw.gap:.3g} (y equation {fw.components[0]:.3g}, theta equation {fw.components[1]:.3g}, energy "
                 f"{fw.components[2]:.3g}). docs/fullwave.md states how far its hinge numbers are converged and verified.")
    else:
        text += f" The full-wave model is not compared: {models.unavailable}."
    table = Table("Gap of each calibrated simulation (fractions of the variance beyond the noise floor; long-time error: "
                  "0 perfect, about 1 for no motion)",
                  ["simulation", "pressure [Pa]", "origin offset [um]", "y equation", "theta equation", "energy", "gap",
                   "long-time error", "fitted parameters"],
                  [[MODEL_LABELS[r.model], r.pressure_amplitude_pa, r.origin_offset_m * 1e6, *r.components, r.gap,
                    r.long_time_total, ", ".join(f"{p} = {v:.4g}" for e in r.params.values() for p, v in e.items()) or None]
                   for r in models.rows],
                  {"pressure [Pa]": "the simulation's calibrated pressure amplitude",
                   "origin offset [um]": "the data's y origin above this simulation's equilibrium height Z_eq at its "
                                         "calibrated pressure",
                   "y equation": "unexplained fraction of the vertical accelerations beyond the noise floor, mean over runs",
                   "theta equation": "the same for the measured hinge angle (integral form)",
                   "energy": "the same for the energy balance over 0.4-s windows",
                   "gap": "the mean of the three", "long-time error": "mean of the attractor-shape, Poincare and frequency "
                   "errors of the simulation started from each run's first state",
                   "fitted parameters": "the parameters fitted with the simulation (SI)"})
    return Section("scattering", "7. Scattering added: fitted or from physics", text, [], [table], models.to_dict())
