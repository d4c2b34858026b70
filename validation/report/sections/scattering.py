"""Section 7, placed after the diagnosis: how far the gap shrinks once the scattering between the cubes is added
(the reference model alone and with fitted pair scattering, and every other registered model with no fitted
stiffness, each calibrated alone)."""
from __future__ import annotations

from ..claims import gap_value
from ..context import ReportContext
from ..html import Section, Table

__all__ = ["section", "long_time_value", "model_description"]


def long_time_value(row) -> float | str:
    """A row's long-time error as the table shows it: the number, or, where the simulation stopped before the runs'
    end, the number with what it is (a penalty for the lost frames, worse than no motion), never a bare 1636 beside
    "about 1 for no motion"."""
    value = row.long_time_total
    stopped = getattr(row, "long_time_stopped", None)
    if value is None or (not stopped and value <= 1):
        return value
    if not stopped:
        return f"{value:.3g}: worse than no motion (the simulated motion lies far from the data's attractor)"
    runs, of, why = stopped
    return (f"{value:.3g}: the simulation stops early in {runs} of {of} runs ({why}); a penalty for the lost frames, "
            "worse than no motion")


def model_description(key: str, reference: str, given: dict | None = None) -> str:
    """What a row's simulation was given and what it fits: every row takes the experiment's constants and fits the
    pressure amplitude and the height origin; the reference model's second row also fits the pair scattering's
    stiffness; a model's own parameters (the full-wave hinge gap) are given with their source."""
    name, _, effect = key.partition("+")
    fits = "fits the pressure amplitude and the height origin"
    if effect:
        fits += f", and the {effect.replace('_', ' ')} stiffness kappa"
    elif name != reference:
        fits += "; no fitted stiffness: its hinge comes from its own physics"
    own = "".join(f", the hinge {k.rsplit('_', 1)[0]} {v * 1e6:.2f} um ({src})" if k.endswith("_m") else
                  f", {k} {v:.4g} ({src})" for k, (v, src) in (given or {}).items())
    return f"given the experiment's constants{own}; {fits}"


def section(context: ReportContext) -> Section:
    """The gaps of the reference model, of it with fitted pair scattering and of the other models side by side."""
    from acousim.models import force_model_type

    from ...diagnosis.summarise.model_comparison import row_label

    models = context.models
    g0, gp = models.rows[0], models.rows[1]
    given = {s.name: {k: (v, (s.record.parameter_sources or {}).get(k, "given"))
                      for k, v in (s.record.parameters or {}).items()}
             for s in getattr(context, "simulations", ())}
    ref_label = force_model_type(g0.model).label
    kappa = gp.params.get("pair_scattering", {}).get("kappa", float("nan"))
    floor = context.diagnosis.noise_floor

    def shown(gap: float, noise_floor: float | None = floor) -> str:
        """A gap as said in the reading: 3 digits, or below the noise floor."""
        value = gap_value(gap, noise_floor)
        return value if isinstance(value, str) else f"{value:.3g}"

    text = (f"How far the gap shrinks once the scattering between the cubes is added. Each simulation is calibrated alone "
            f"(pressure and origin) on the same runs. The {ref_label} model leaves a gap of {shown(g0.gap)}; with the "
            f"phenomenological pair scattering, its stiffness kappa = {kappa:.3g} 1/s^2 fitted, {shown(gp.gap)}.")
    for r in models.rows[2:]:
        t = force_model_type(r.model)
        text += (f" The {t.label} model, whose hinge comes from its own physics with no fitted stiffness, "
                 f"leaves {shown(r.gap)} (y equation {shown(r.components[0], None)}, theta equation "
                 f"{shown(r.components[1], None)}, energy {shown(r.components[2], None)})"
                 + (": its theta equation leaves more of the hinge accelerations' variance unexplained than predicting "
                    "no hinge acceleration at all (1), so its own hinge stiffness does not hold these data's hinge "
                    "(section 4)." if r.components[1] > 1 else "."))
    text += "".join(f" The {force_model_type(n).label} model is not compared: {why}."
                    for n, why in context.unavailable().items())
    table = Table("Gap of each calibrated simulation (fractions of the variance beyond the noise floor; long-time error: "
                  "0 perfect, about 1 for no motion; a simulation that stops early scores a penalty)",
                  ["simulation", "given and fitted", "pressure [Pa]", "origin offset [um]", "y equation", "theta equation", "energy", "gap",
                   "long-time error", "fitted parameters"],
                  [[row_label(r.model), model_description(r.model, g0.model, given.get(r.model.partition("+")[0])),
                    r.pressure_amplitude_pa, r.origin_offset_m * 1e6,
                    *(gap_value(c, None) for c in r.components), gap_value(r.gap, floor),
                    long_time_value(r), ", ".join(f"{p} = {v:.4g}" for e in r.params.values() for p, v in e.items()) or None]
                   for r in models.rows],
                  {"given and fitted": "what the simulation was built with and what was fitted to the runs",
                   "pressure [Pa]": "the simulation's calibrated pressure amplitude",
                   "origin offset [um]": "the data's y origin above this simulation's equilibrium height Z_eq at its "
                                         "calibrated pressure",
                   "y equation": "unexplained fraction of the vertical accelerations beyond the noise floor, mean over runs",
                   "theta equation": "the same for the measured hinge angle (integral form)",
                   "energy": "the same for the energy balance over 0.4-s windows",
                   "gap": "the mean of the three", "long-time error": "mean of the attractor-shape, Poincare and frequency "
                   "errors of the simulation started from each run's first state (0 perfect, about 1 for no motion, "
                   "above 1 worse than no motion: the simulated motion lies far from the data's attractor); a "
                   "simulation that stops before a run's end (the cube faces touch) scores a penalty for the frames it "
                   "lost, up to about 2000, which says that it leaves the data, not by how much",
                   "fitted parameters": "the parameters fitted with the simulation (SI)"})
    return Section("scattering", "7. Scattering added: fitted or from physics", text, [], [table], models.to_dict())
