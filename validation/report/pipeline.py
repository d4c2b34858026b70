"""``python -m validation report``: the numbers of the model-vs-simulation report of a data set, and the report.

Runs, in order (each step logged): the fitting pipeline (``fitting.pipeline.fit_dataset``), the
variant comparison (the minimal model without its cross-coupling terms, re-optimised), the gap
diagnosis (:mod:`validation.diagnosis`, which also calibrates the simulation), a static sweep of the
calibrated Gor'kov model over the data's range, the coefficient comparison
(:mod:`validation.coefficients`) and the rendered mesh; then writes ``report.html`` (self-contained),
``figures/*.png`` and ``numbers.json``.
"""
from __future__ import annotations

import logging
from dataclasses import replace
from pathlib import Path

import numpy as np

from fitting.description import model_equation_text
from fitting.methods import get_method

from .claims import PHASE_LINE_FRACTION, long_time_reading, not_significant_text, run_phase
from .html import Figure, Section, Table, write_report

__all__ = ["build_report", "model_equation_text", "lead_term_reading", "effect_static_coefficients"]

logger = logging.getLogger(__name__)


def effect_static_coefficients(diag: dict, wavenumber: float, z_eq: float, theta_max: float, y_max: float) -> dict[str, float]:
    """Velocity-free thetaddot coefficients [SI] that the *identified* effects add to the static model: least
    squares of their accelerations at zero velocity on the velocity-free cubic monomials over the same
    box as the static sweep fit (|theta| <= theta_max, |y| <= y_max), with the effects' y measured from
    the calibrated Z_eq (docs/conventions.md section 5).  E.g. pair scattering's -kappa cos^2(k Z) theta adds
    kappa k^2 cos(2 k Z_eq) to theta*y^2 at the Taylor level."""
    from cubedimer.terms import evaluate_library, is_velocity_free, library_terms

    from ..diagnosis import CANDIDATE_EFFECTS, effect_regressors

    th, y = np.meshgrid(np.linspace(-theta_max, theta_max, 21), np.linspace(-y_max, y_max, 41))
    state = np.column_stack([y.ravel(), np.zeros(y.size), th.ravel(), np.zeros(y.size)])
    total = np.zeros(y.size)
    for name in diag.get("identified", []):
        params = next(e["params"] for e in diag["effects"] if e["name"] == name)
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
        return (f"The theta*y^2 coupling: the pooled integral-form fit (position space, coefficients shared by all runs) "
                f"selects it with {lead.integral:.3g} +- {lead.integral_std_error:.2g} (z = {z:.1f}), against the {sim}; "
                f"they {verdict} ({n_sigma:g} sigma; ratio {lead.ratio:.4g}, {lead.deviation_sigma:.2g} combined standard "
                f"deviations apart). The per-run acceleration fits ({ensemble}) "
                "scatter from run to run far more than the pooled estimate's standard error, so the verdict uses the pooled estimate.")
    return (f"The theta*y^2 coupling: {ensemble}; the pooled integral-form fit does not select it; {sim}. "
            + (f"On the ensemble statistics they {verdict} ({n_sigma:g} sigma"
               + (f"; {lead.deviation_sigma:.2g} combined standard deviations apart" if np.isfinite(lead.deviation_sigma)
                  else "") + ")." if lead.signs_agree is not None else f"On the ensemble statistics they {verdict}."))


def _scattering_section(models) -> Section:
    """Section 7: the gaps of Gor'kov, Gor'kov + fitted pair scattering and the full-wave model side by side."""
    from ..diagnosis.model_comparison import MODEL_LABELS

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


def build_report(data_dir: str | Path, out_dir: str | Path, workers: int | None = None, scheduler: str | None = None,
                 progress: bool = True, max_evals: int | None = None, method: str = "discovery",
                 model: str = "gorkov", heldout_tolerance: float | None = None, gap: float | None = None,
                 edge_radius: float | None = None, atlas: str | Path | None = None) -> Path:
    """Fit, compare, diagnose and sweep the data set ``data_dir`` and write the report into ``out_dir``.

    Parameters
    ----------
    data_dir : path of the data set (CSV runs and meta.json)
    out_dir : report directory: report.html, figures/*.png, numbers.json, fit/, diagnosis.json, comparison.json
    workers, scheduler : where the fit's refinements run (:class:`cubedimer.executor.ExecutorConfig`)
    progress : progress bars, and the steps logged at INFO level (else DEBUG)
    max_evals : evaluations of every long-time refinement: per run and joint for ``"paper"``, of the polish (and
        of a fallback's joint re-optimisation) for ``"discovery"``, and of the re-optimisation of the variant
        without cross-coupling terms (section 3);
        default: the fitting and comparison defaults
    method : the fit's model-discovery method (:data:`fitting.methods.METHODS`)
    model : the simulation model the diagnosis (section 6) calibrates, ``"gorkov"`` or ``"fullwave"``; the other one
        stands beside it in sections 4, 5 and 7 whenever the full-wave table applies to the experiment
    heldout_tolerance : the discovery's practical threshold (:class:`fitting.discovery.DiscoveryConfig`; default 0)
    gap, edge_radius : hinge gap and edge radius [m] of the full-wave model; without ``gap`` a full-wave diagnosis
        calibrates it from the data
    atlas : folder of an attractor atlas (``python -m acousim atlas``), shown as the last section

    Returns
    -------
    Path of report.html
    """
    from acousim.render import render_dimer
    from cubedimer.spectra import peak_frequency
    from acousim.sweep import fit_static_coefficients, static_sweep
    from cubedimer.executor import ExecutorConfig
    from cubedimer.meta import read_meta
    from fitting.compare import compare_models, cross_coupling_mask
    from fitting.config import FitConfig
    from fitting.fit_output import write_fit
    from fitting.pipeline import fit_dataset
    from fitting.refine import JOINT_REFINE
    from fitting.plots import plot_comparison

    from ..coefficients import compare_coefficients
    from ..diagnosis import DiagnoseConfig, compare_simulation_models, diagnose_dataset
    from ..diagnosis.model_comparison import MODEL_LABELS
    from ..simulation import model_from_meta
    from .diagnosis_section import diagnosis_figures, diagnosis_section
    from .figures import data_figures, phase_space_figures, restoring_overlay_figure

    level = logging.INFO if progress else logging.DEBUG

    def say(message: str) -> None:
        logger.log(level, "%s", message)

    # refuse a model that does not fit the experiment (a gap with Gor'kov, a dimer outside the full-wave family)
    # before the long fit, not after it
    model_from_meta(read_meta(data_dir), model=model, gap=gap, edge_radius=edge_radius)
    # and a data set with too few runs for the diagnosis's held-out comparison, with how many it needs
    _check_runs(data_dir)
    out = Path(out_dir)
    figs_dir = out / "figures"
    fit_dir = out / "fit"
    config = FitConfig(method=method).with_heldout_tolerance(heldout_tolerance)
    if max_evals is not None:
        config = replace(config, refine=replace(config.refine, max_evals=max_evals),
                         polish=replace(config.polish, max_evals=max_evals),
                         joint=replace(config.joint, max_evals=max_evals))
    say(f"1/5 fitting the data ({get_method(method).summary})")
    res = fit_dataset(data_dir, config, ExecutorConfig(workers=workers, scheduler=scheduler), progress=progress,
                      cache_dir=fit_dir / "runs")
    write_fit(res, fit_dir)
    import json

    model_json = json.loads((fit_dir / "model.json").read_text())
    prepared = res.runs
    say("2/5 comparing the minimal model with its variant without cross-coupling terms")
    mask = cross_coupling_mask(res.model)
    variant = res.model.with_mask(res.model.support & ~mask) if mask.any() else None
    cmp = None
    if variant is not None:
        cmp_config = JOINT_REFINE if max_evals is None else replace(JOINT_REFINE, max_evals=max_evals)
        cmp = compare_models(res.model, variant, [p.derivs for p in prepared], res.scales,
                             [p.run.name for p in prepared], config=cmp_config)
        plot_comparison(cmp, fit_dir)
    say("3/5 diagnosing the sim-to-real gap (calibrating the simulation)")
    diag, internals = diagnose_dataset(data_dir, DiagnoseConfig(), progress=progress, model=model, gap=gap,
                                       edge_radius=edge_radius)
    meta = read_meta(data_dir)
    # the full-wave model beside the diagnosis's one: at its calibrated (or given) gap
    fw_gap = diag["calibration"].get("gap_m", gap)
    say("   the gaps of Gor'kov, Gor'kov + fitted pair scattering and the full-wave model, side by side")
    models = compare_simulation_models(internals.problem, meta, base=internals.base, gap=fw_gap)
    # each simulation at its own calibration: the diagnosis's final one for its model, the bare one for the other
    cals = {k: f.calibration for k, f in models.fits.items() if k in MODEL_LABELS and "+" not in k}  # simulations
    cals[model] = internals.final.calibration
    cal = cals["gorkov"]
    say("4/5 sweeping the calibrated simulations and comparing coefficients")
    sim = model_from_meta(meta, pressure_amplitude_pa=cal.pressure_amplitude_pa)
    states = np.concatenate([p.derivs.state for p in prepared])
    delta = cal.origin_offset_m
    theta_max = float(min(0.9, np.quantile(np.abs(states[:, 2]), 0.98)))
    y_max = float(np.quantile(np.abs(states[:, 0] + delta), 0.98))

    def sweep_and_compare(simulation, offset: float):
        plot = static_sweep(simulation, np.linspace(-0.9, 0.9, 61), np.linspace(-1.3 * y_max, 1.3 * y_max, 41))
        fit = fit_static_coefficients(static_sweep(simulation, np.linspace(-theta_max, theta_max, 41),
                                                   np.linspace(-y_max, y_max, 41)))
        return plot, compare_coefficients(model_json, fit.coefficients, fit.std_errors, origin_offset=offset,
                                          static_box=fit.box, origin_source="calibrated (section 6)")

    sweep_plot, coef_cmp = sweep_and_compare(sim, delta)
    fw_sweep, fw_cmp = None, None
    if cals.get("fullwave") is not None:
        fw_sim = model_from_meta(meta, pressure_amplitude_pa=cals["fullwave"].pressure_amplitude_pa, model="fullwave",
                                 gap=fw_gap)
        fw_sweep, fw_cmp = sweep_and_compare(fw_sim, cals["fullwave"].origin_offset_m)
    say("5/5 figures and the report")
    sections = []
    # 1 data
    dfig = data_figures(prepared, figs_dir)
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
    sections.append(Section(
        "data", "1. The data",
        f"{len(prepared)} runs ({len(res.skipped)} files skipped as unreadable or invalid). The vertical motion's spectrum "
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
         "frequency_resolution_hz": resolution}))
    # the tracking, when the data set came from video (its own section module)
    from .tracking_section import tracking_section

    tracked = tracking_section(data_dir, figs_dir)
    if tracked is not None:
        sections.append(tracked)
    # 2 phase space
    pfig = phase_space_figures(prepared, res.model, figs_dir)
    loss = model_json["loss"]["final"]
    sections.append(Section(
        "phase-space", "2. Phase space",
        long_time_reading(loss),
        [Figure(p, c) for p, c in pfig] + [Figure(fit_dir / "phase_portraits.png", "Phase portraits (y, ydot) and (theta, thetadot): data and minimal model, first runs."),
                                           Figure(fit_dir / "poincare.png", "Poincare maps (theta, thetadot at y = 0, ydot < 0): data and minimal model.")],
        [], {"loss_final": loss}))
    # 3 the fit, in the method's own words
    rows = []
    if cmp is not None:
        rows = [["attractor shape", cmp.shape_test.median_difference, cmp.shape_test.p_greater, cmp.shape_test.n],
                ["Poincare map", cmp.poincare_test.median_difference, cmp.poincare_test.p_greater, cmp.poincare_test.n]]
    described = get_method(res.method).describe(res)
    fit_figs = [Figure(fit_dir / name, caption) for name, caption in described.figures if (fit_dir / name).exists()]
    if cmp is not None and (fit_dir / "compare.png").exists():
        fit_figs.append(Figure(fit_dir / "compare.png", "Per-run errors of the minimal model and of its variant without cross-coupling terms."))
    cmp_text = "" if cmp is None else (
        " Without its cross-coupling terms (re-optimised) the model's per-run errors are "
        + " and ".join(f"{'' if t.p_greater < 0.05 else 'not significantly '}larger for the {what} "
                       + not_significant_text(t.p_greater, t.n, 0.05)
                       for t, what in ((cmp.shape_test, "attractor shape"), (cmp.poincare_test, "Poincare map"))) + ".")
    fit_text = described.text
    fit_table = Table(described.table.title, list(described.table.header), [list(r) for r in described.table.rows])
    sections.append(Section(
        "fit", "3. The fit",
        fit_text + cmp_text,
        fit_figs,
        [fit_table]
        + ([Table("Variant without cross-coupling terms vs the minimal model (per-run errors)",
                  ["error", "median difference (variant - minimal)", "Wilcoxon p (variant worse)", "runs"], rows)] if rows else []),
        {"equations": model_json["equations"], "wilcoxon_shape_p": None if cmp is None else cmp.shape_test.p_greater,
         "wilcoxon_poincare_p": None if cmp is None else cmp.poincare_test.p_greater}))
    # 4 the simulation
    overlay_models = [(sweep_plot, delta, "Gor'kov")]
    if fw_sweep is not None:
        overlay_models.append((fw_sweep, cals["fullwave"].origin_offset_m, "full-wave"))
    overlay = restoring_overlay_figure(overlay_models, prepared, figs_dir)
    render = render_dimer(sim, 0.3, 0.0, figs_dir / "dimer_gorkov.png")
    fw_text = ""
    if fw_sweep is not None:
        fc = cals["fullwave"]
        fw_text = (f" Beside it (red) the full-wave model, calibrated the same way ({fc.pressure_amplitude_pa:.0f} Pa; the data's "
                   f"y origin lies {fc.origin_offset_m * 1e6:+.2f} um above the full-wave model's calibrated Z_eq, against "
                   f"{delta * 1e6:+.2f} um above the Gor'kov model's calibrated Z_eq): the scattering between the cubes "
                   "holds the hinge with no fitted stiffness.")
    elif models.unavailable:
        fw_text = f" The full-wave model is not shown: {models.unavailable}."
    sections.append(Section(
        "simulation", "4. The simulation",
        f"The Gor'kov model at the calibrated pressure {cal.pressure_amplitude_pa:.0f} Pa (nominal "
        f"{cal.nominal_pressure_pa:.0f} Pa) holds the dimer {abs(sim.equilibrium_height) * 1e6:.0f} um below the node. Its "
        "restoring force follows the measured vertical accelerations; where the measured hinge accelerations lie far "
        "outside the model's torque curve, the hinge is held by something the model omits." + fw_text,
        [Figure(*overlay), Figure(render, "The posed dimer mesh (theta = 0.3) coloured by the Gor'kov potential density u.")],
        [], {"calibrated_pressure_pa": cal.pressure_amplitude_pa, "equilibrium_height_m": sim.equilibrium_height,
             "fullwave_calibrated_pressure_pa": getattr(cals.get("fullwave"), "pressure_amplitude_pa", None)}))
    # 5 model vs simulation
    lead = coef_cmp.rows[0]
    comparisons = {"gorkov": coef_cmp, "fullwave": fw_cmp}
    if comparisons.get(model) is None:  # any other registered model: its own calibrated sweep
        own = model_from_meta(meta, pressure_amplitude_pa=cals[model].pressure_amplitude_pa, model=model,
                              gap=gap, edge_radius=edge_radius)
        comparisons[model] = sweep_and_compare(own, cals[model].origin_offset_m)[1]
    main_cmp = comparisons[model]  # the diagnosis's model's comparison
    main_lead, main_cal = main_cmp.rows[0], cals[model]
    # what the identified effects add to the static theta*y^2 of the diagnosis's model (the diagnosis is section 6)
    added = effect_static_coefficients(diag, sim.wave.wavenumber, main_cal.equilibrium_height_m, theta_max, y_max)
    effects_reading = ""
    fitted_lead = main_lead.integral if main_lead.verdict_from == "integral form" else main_lead.fitted_mean
    fitted_se = main_lead.integral_std_error if main_lead.verdict_from == "integral form" else main_lead.fitted_std
    if added.get("y^2*theta") and np.isfinite(fitted_lead):
        with_effects = main_lead.simulated + added["y^2*theta"]
        n_sig = abs(fitted_lead - with_effects) / np.hypot(fitted_se, main_lead.simulated_std)
        effects_reading = (f" The effects identified in section 6 ({', '.join(diag['identified'])}) add {added['y^2*theta']:.3g} to the "
                           f"static theta*y^2 (least squares over the same box); with them the "
                           f"{MODEL_LABELS.get(model, model).split(' (')[0]} simulation predicts "
                           f"{with_effects:.3g}, {n_sig:.1f} combined standard deviations from the fit.")
    fw_reading = ""
    fw_rows = {}
    if fw_cmp is not None:
        fl = fw_cmp.rows[0]
        fw_rows = {(r.equation, r.term): r for r in fw_cmp.rows}
        fw_reading = (f" The full-wave model, with no fitted stiffness, gives {fl.simulated:.3g} +- {fl.simulated_std:.2g} for "
                      f"theta*y^2 (the paper's finite-element check), against the Gor'kov {lead.simulated:.3g}; its column "
                      "below is its own calibrated sweep over the same box.")
    header = ["equation", "term", "kind", "fitted", "ensemble mean", "ensemble std", "z", "integral form", "integral SE",
              "simulated", "simulated std", "verdict from", "ratio", "signs agree", "deviation [combined sigma]",
              f"within {coef_cmp.n_sigma:g} sigma"]
    if fw_cmp is not None:
        header += ["full wave", "full-wave std"]

    def table_row(r) -> list:
        row = [r.equation, r.term, "static" if r.kind == "static" else "dynamic only", r.fitted, r.fitted_mean, r.fitted_std,
               r.fitted_z, r.integral, r.integral_std_error, r.simulated, r.simulated_std,
               r.verdict_from if r.kind == "static" else None, r.ratio, r.signs_agree, r.deviation_sigma,
               r.within_uncertainty]
        if fw_cmp is not None:
            f = fw_rows.get((r.equation, r.term))
            row += [f.simulated if f else None, f.simulated_std if f else None]
        return row

    shown = [r for r in coef_cmp.rows if r.kind != "static" or r.in_minimal_model or abs(r.simulated) > 0
             or abs(getattr(fw_rows.get((r.equation, r.term)), "simulated", 0.0) or 0.0) > 0]
    numbers5 = coef_cmp.to_dict()
    if fw_cmp is not None:
        numbers5["fullwave"] = fw_cmp.to_dict()
    sections.append(Section(
        "model-vs-simulation", "5. Model vs simulation",
        lead_term_reading(lead, coef_cmp.n_sigma) + fw_reading + effects_reading + " Static coefficients are "
        f"least squares on the calibrated sweep over |theta| <= {theta_max:.2f}, |y| <= {y_max * 1e6:.0f} um and re-expanded "
        f"about the data's origin ({coef_cmp.origin}). Velocity terms have no static prediction.",
        [],
        [Table("Coefficients (SI), the theta*y^2 term first; 'simulated' is the Gor'kov model; the verdict columns use the "
               "estimate named in 'verdict from'", header, [table_row(r) for r in shown])],
        numbers5))
    # 7 (placed after the diagnosis) how far the gap shrinks once scattering is added
    sections_after = [_scattering_section(models)]
    # 6 the gap
    dfigs = diagnosis_figures(diag, internals, figs_dir)
    sec = diagnosis_section(diag, dfigs)
    sections.append(Section("diagnosis", f"6. The sim-to-real gap ({MODEL_LABELS.get(model, model).split(' (')[0]} model)",
                            sec.reading, sec.figures, sec.tables, sec.numbers))
    sections += sections_after
    if atlas is not None:
        from .atlas_section import atlas_section

        sections.append(atlas_section(atlas))
    from cubedimer.atomic import write_json

    write_json(out / "diagnosis.json", diag)
    write_json(out / "comparison.json", numbers5)
    path = write_report(sections, out, "Cube dimer: model vs simulation",
                        f"data set {Path(data_dir).resolve()}; all quantities SI unless an axis says otherwise")
    say(f"written {path}")
    return path


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


def _check_runs(data_dir) -> None:
    """:func:`validation.diagnosis.pipeline.check_enough_runs` on the data set as the diagnosis loads it."""
    from acousim.analytic import nominal_trap_frequency
    from cubedimer.dataset import LoadConfig, load_dataset

    from ..diagnosis import DiagnoseConfig
    from ..diagnosis.pipeline import check_enough_runs

    dataset = load_dataset(data_dir, config=LoadConfig(trap_frequency=nominal_trap_frequency), report=lambda m: None)
    check_enough_runs(data_dir, len(dataset.runs), len(dataset.skipped_files()), DiagnoseConfig().alpha)


def _late_phase(p) -> float | None:
    """The runs table's phase: over the stretch the attractor was classified on (the run's second half)."""
    d = p.derivs
    half = len(d.t) // 2
    return run_phase(d.state[half:, 2], float(d.t[1] - d.t[0]), p.attractor.f_y, p.attractor.phase)
