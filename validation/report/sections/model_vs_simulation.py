"""Section 5, model vs simulation: the fitted coefficients against the calibrated simulations' static coefficients,
the theta*y^2 coupling first, with what the identified effects add to it."""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..claims import RATIO_NOT_DETERMINED, ratio_value
from ..context import ReportContext
from ..html import Section, Table

if TYPE_CHECKING:
    from ...diagnosis import Diagnosis

__all__ = ["section", "lead_term_reading", "effect_static_coefficients"]


def effect_static_coefficients(diag: "Diagnosis", wavenumber: float, z_eq: float, theta_max: float, y_max: float) -> dict[str, float]:
    """Velocity-free thetaddot coefficients [SI] that the *identified* effects add to the static model: least
    squares of their accelerations at zero velocity on the velocity-free cubic monomials over the same
    box as the static sweep fit (|theta| <= theta_max, |y| <= y_max), with the effects' y measured from
    the calibrated Z_eq (docs/conventions.md section 5).  E.g. pair scattering's -kappa cos^2(k Z) theta adds
    kappa k^2 cos(2 k Z_eq) to theta*y^2 at the Taylor level."""
    from cubedimer.terms import evaluate_library, is_velocity_free, library_terms

    from ...diagnosis import CANDIDATE_EFFECTS, effect_regressors

    th, y = np.meshgrid(np.linspace(-theta_max, theta_max, 21), np.linspace(-y_max, y_max, 41))
    state = np.column_stack([y.ravel(), np.zeros(y.size), th.ravel(), np.zeros(y.size)])
    total = np.zeros(y.size)
    for name in diag.identified:
        params = next(e.params for e in diag.effects if e.name == name)
        pv = np.array([params[p] for p in CANDIDATE_EFFECTS[name]])
        total += effect_regressors(name, state, z_eq + state[:, 0], wavenumber, z_eq)[:, 1, :] @ pv
    if not np.any(total):
        return {}
    terms = [t for t in library_terms() if is_velocity_free(t)]
    lib = evaluate_library(state)[:, [library_terms().index(t) for t in terms]]
    coef = np.linalg.lstsq(lib / np.abs(lib).max(axis=0), total, rcond=None)[0] / np.abs(lib).max(axis=0)
    return dict(zip(terms, coef.tolist()))


def lead_term_reading(lead, n_sigma: float) -> str:
    """Section 5's sentences on the theta*y^2 coupling (a :class:`validation.coefficients.TermComparison`), with numbers."""
    verdict = ("agree in sign and within their combined uncertainty" if lead.signs_agree and lead.within_uncertainty else
               "agree in sign but not within their combined uncertainty" if lead.signs_agree else
               "disagree in sign" if lead.signs_agree is False else "cannot be compared (the term was not selected)")
    if not lead.in_minimal_model and lead.fitted_mean == 0 and lead.fitted_std == 0:
        ensemble = "not selected in the minimal model and absent from every run's refined model"
    else:
        ensemble = (f"fitted {lead.fitted:.3g}{' (not selected in the minimal model)' if not lead.in_minimal_model else ''}, "
                    f"ensemble mean over the runs' refined models {lead.fitted_mean:.3g} +- {lead.fitted_std:.3g}")
    sim = f"simulated {lead.simulated:.3g} +- {lead.simulated_std:.3g} 1/(m^2 s^2)"
    if lead.verdict_from == "integral form":
        z = lead.integral / lead.integral_std_error
        ratio = ratio_value(lead.ratio, lead.simulated, lead.simulated_std, n_sigma)
        return (f"The theta*y^2 coupling: the pooled integral-form fit (position space, coefficients shared by all runs) "
                f"selects it with {lead.integral:.3g} +- {lead.integral_std_error:.2g} (z = {z:.1f}), against the {sim}; "
                f"they {verdict} ({n_sigma:g} sigma; ratio {ratio if isinstance(ratio, str) else f'{ratio:.4g}'}, {lead.deviation_sigma:.2g} combined standard "
                f"deviations apart). The per-run acceleration fits ({ensemble}) "
                "scatter from run to run far more than the pooled estimate's standard error, so the verdict uses the pooled estimate.")
    return (f"The theta*y^2 coupling: {ensemble}; the pooled integral-form fit does not select it; {sim}. "
            + (f"On the ensemble statistics they {verdict} ({n_sigma:g} sigma"
               + (f"; {lead.deviation_sigma:.2g} combined standard deviations apart" if np.isfinite(lead.deviation_sigma)
                  else "") + ")." if lead.signs_agree is not None else f"On the ensemble statistics they {verdict}."))


def section(context: ReportContext) -> Section:
    """The reading of the theta*y^2 coupling (fitted, the reference model, the other models, with the identified
    effects) and the table of every coefficient; its numbers are comparison.json."""
    ref, others = context.reference, context.others
    coef_cmp = ref.coefficients
    diag, theta_max, y_max = context.diagnosis, context.theta_max, context.y_max
    lead = coef_cmp.rows[0]
    main = context.diagnosed  # the diagnosis's model
    main_lead = main.coefficients.rows[0]
    # what the identified effects add to the static theta*y^2 of the diagnosis's model (the diagnosis is section 6)
    added = effect_static_coefficients(diag, ref.record.wavenumber, main.record.equilibrium_height_m,
                                       theta_max, y_max)
    effects_reading = ""
    fitted_lead = main_lead.integral if main_lead.verdict_from == "integral form" else main_lead.fitted_mean
    fitted_se = main_lead.integral_std_error if main_lead.verdict_from == "integral form" else main_lead.fitted_std
    if added.get("y^2*theta") and np.isfinite(fitted_lead):
        with_effects = main_lead.simulated + added["y^2*theta"]
        n_sig = abs(fitted_lead - with_effects) / np.hypot(fitted_se, main_lead.simulated_std)
        effects_reading = (f" The effects identified in section 6 ({', '.join(diag.identified)}) add "
                           f"{added['y^2*theta']:.3g} to the static theta*y^2 (least squares over the same box); with "
                           f"them the {main.label} simulation predicts {with_effects:.3g}, {n_sig:.1f} combined standard "
                           "deviations from the fit.")
    other_rows = [{(r.equation, r.term): r for r in o.coefficients.rows} for o in others]
    others_reading = "".join(
        f" The {o.label} model, with no fitted stiffness, gives {o.coefficients.rows[0].simulated:.3g} +- "
        f"{o.coefficients.rows[0].simulated_std:.2g} for theta*y^2, against the {ref.label} {lead.simulated:.3g}; its "
        "column below is its own calibrated sweep over the same box." for o in others)
    ratio_note = {"ratio": f"the verdict's estimate / simulated; {RATIO_NOT_DETERMINED} where the "
                           f"simulated value is within {coef_cmp.n_sigma:g} of its standard errors of zero"}
    header = ["equation", "term", "kind", "fitted", "ensemble mean", "ensemble std", "z", "integral form", "integral SE",
              "simulated", "simulated std", "verdict from", "ratio", "signs agree", "deviation [combined sigma]",
              f"within {coef_cmp.n_sigma:g} sigma"]
    for o in others:
        header += [o.label, f"{o.label} std"]

    def table_row(r) -> list:
        row = [r.equation, r.term, "static" if r.kind == "static" else "dynamic only", r.fitted, r.fitted_mean, r.fitted_std,
               r.fitted_z, r.integral, r.integral_std_error, r.simulated, r.simulated_std,
               r.verdict_from if r.kind == "static" else None,
               ratio_value(r.ratio, r.simulated, r.simulated_std, coef_cmp.n_sigma), r.signs_agree, r.deviation_sigma,
               r.within_uncertainty]
        for rows in other_rows:
            f = rows.get((r.equation, r.term))
            row += [f.simulated if f else None, f.simulated_std if f else None]
        return row

    shown = [r for r in coef_cmp.rows if r.kind != "static" or r.in_minimal_model or abs(r.simulated) > 0
             or any(abs(getattr(rows.get((r.equation, r.term)), "simulated", 0.0) or 0.0) > 0 for rows in other_rows)]
    numbers5 = coef_cmp.to_dict()
    for o in others:
        numbers5[o.name] = o.coefficients.to_dict()
    return Section(
        "model-vs-simulation", "5. Model vs simulation",
        lead_term_reading(lead, coef_cmp.n_sigma) + others_reading + effects_reading + " Static coefficients are "
        f"least squares on the calibrated sweep over |theta| <= {theta_max:.2f}, |y| <= {y_max * 1e6:.0f} um and re-expanded "
        f"about the data's origin ({coef_cmp.origin}). Velocity terms have no static prediction.",
        [],
        [Table(f"Coefficients (SI), the theta*y^2 term first; 'simulated' is the {ref.label} model; the verdict columns "
               "use the estimate named in 'verdict from'", header, [table_row(r) for r in shown], ratio_note)],
        numbers5)
