"""What the report's sections read: :class:`ReportContext`, and the steps that fill it after the fit and the
diagnosis (the variant comparison, the calibrated simulations and their static sweeps).

Every section of :mod:`validation.report.sections` is a function of one frozen :class:`ReportContext`; nothing a
section needs is computed twice.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Callable

import numpy as np

__all__ = ["ReportContext", "variant_comparison", "report_context"]

logger = logging.getLogger(__name__)


@dataclass(frozen=True, eq=False)
class ReportContext:
    """Everything the report's sections read.

    Attributes
    ----------
    data_dir, out : Path
        The data set and the report directory (figures in ``out/figures``, the fit in ``out/fit``).
    model : str
        The simulation model the diagnosis calibrated (``--model``).
    gap, edge_radius : float or None
        The full-wave model's hinge gap and edge radius [m] as given.
    atlas : Path or None
        Folder of an attractor atlas (the last section), if given.
    fit : fitting.FitResult
        The fit of the data set.
    model_json : dict
        The fit's model.json as written.
    variant : fitting.compare.Comparison or None
        The minimal model against its variant without cross-coupling terms (None: the model has none).
    diagnosis : dict
        The diagnosis (diagnosis.json's content).
    internals : validation.diagnosis.DiagnosisInternals
        The diagnosis's runs and fits (for its figures).
    meta : dict
        The data set's meta.json.
    models : validation.diagnosis.model_comparison.ModelComparison
        The gaps of Gor'kov, Gor'kov + fitted pair scattering and the full-wave model.
    calibrations : dict
        Simulation model name -> its calibration (the diagnosis's final one for ``model``).
    simulation : the Gor'kov model at its calibrated pressure.
    theta_max, y_max : float
        The box of the static fits: the 98 % quantiles of |theta| (at most 0.9) and of |y| [m] (y from the
        Gor'kov model's calibrated Z_eq).
    sweep_plot, fullwave_sweep : SweepResult, SweepResult or None
        The calibrated Gor'kov and full-wave sweeps over the plotted range (full wave: None when not applicable).
    coefficients : dict
        Simulation model name -> its :class:`validation.coefficients.CoefficientComparison` (Gor'kov, the full-wave
        model when applicable, and the diagnosis's model).
    """

    data_dir: Path
    out: Path
    model: str
    gap: float | None
    edge_radius: float | None
    atlas: Path | None
    fit: Any
    model_json: dict
    variant: Any
    diagnosis: dict
    internals: Any
    meta: Any
    models: Any
    calibrations: dict
    simulation: Any
    theta_max: float
    y_max: float
    sweep_plot: Any
    fullwave_sweep: Any
    coefficients: dict

    @property
    def figs_dir(self) -> Path:
        """Where the report's own figures go."""
        return self.out / "figures"

    @property
    def fit_dir(self) -> Path:
        """The fit's output directory (model.json and its figures)."""
        return self.out / "fit"

    @property
    def prepared(self) -> list:
        """The fitted runs (:class:`fitting.results.PreparedRun`)."""
        return self.fit.runs


def variant_comparison(res, fit_dir: Path, max_evals: int | None):
    """The minimal model against its variant without cross-coupling terms, re-optimised (``max_evals`` evaluations;
    default: the joint re-optimisation's), with its figure in ``fit_dir``; None when the model has no cross-coupling
    terms."""
    from fitting.compare import compare_models, cross_coupling_mask
    from fitting.plots import plot_comparison
    from fitting.refine import JOINT_REFINE

    mask = cross_coupling_mask(res.model)
    if not mask.any():
        return None
    variant = res.model.with_mask(res.model.support & ~mask)
    cmp_config = JOINT_REFINE if max_evals is None else replace(JOINT_REFINE, max_evals=max_evals)
    prepared = res.runs
    cmp = compare_models(res.model, variant, [p.derivs for p in prepared], res.scales,
                         [p.run.name for p in prepared], config=cmp_config)
    plot_comparison(cmp, fit_dir)
    return cmp


def report_context(data_dir, out: Path, res, model_json: dict, variant, diag: dict, internals, *, model: str,
                   gap: float | None, edge_radius: float | None, atlas, say: Callable[[str], None]) -> ReportContext:
    """The :class:`ReportContext` of a fitted and diagnosed data set: the simulations side by side, each calibrated
    simulation's static sweep over the data's box and its coefficient comparison with the fit."""
    from acousim.sweep import static_sweep
    from cubedimer.meta import read_meta

    from ..coefficients import static_comparison
    from ..diagnosis import compare_simulation_models
    from ..diagnosis.model_comparison import MODEL_LABELS
    from ..simulation import model_from_meta

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
    states = np.concatenate([p.derivs.state for p in res.runs])
    theta_max = float(min(0.9, np.quantile(np.abs(states[:, 2]), 0.98)))
    y_max = float(np.quantile(np.abs(states[:, 0] + cal.origin_offset_m), 0.98))

    def sweep_and_compare(simulation, offset: float):
        plot = static_sweep(simulation, np.linspace(-0.9, 0.9, 61), np.linspace(-1.3 * y_max, 1.3 * y_max, 41))
        return plot, static_comparison(model_json, simulation, theta_max, y_max, origin_offset=offset,
                                       origin_source="calibrated (section 6)")[1]

    sweep_plot, coefficients = sweep_and_compare(sim, cal.origin_offset_m)
    comparisons = {"gorkov": coefficients}
    fw_sweep = None
    if cals.get("fullwave") is not None:
        fw_sim = model_from_meta(meta, pressure_amplitude_pa=cals["fullwave"].pressure_amplitude_pa, model="fullwave",
                                 gap=fw_gap)
        fw_sweep, comparisons["fullwave"] = sweep_and_compare(fw_sim, cals["fullwave"].origin_offset_m)
    if model not in comparisons:  # any other registered model: its own calibrated sweep
        own = model_from_meta(meta, pressure_amplitude_pa=cals[model].pressure_amplitude_pa, model=model,
                              gap=gap, edge_radius=edge_radius)
        comparisons[model] = sweep_and_compare(own, cals[model].origin_offset_m)[1]
    return ReportContext(data_dir=Path(data_dir), out=Path(out), model=model, gap=gap, edge_radius=edge_radius,
                         atlas=None if atlas is None else Path(atlas), fit=res, model_json=model_json, variant=variant,
                         diagnosis=diag, internals=internals, meta=meta, models=models, calibrations=cals,
                         simulation=sim, theta_max=theta_max, y_max=y_max, sweep_plot=sweep_plot,
                         fullwave_sweep=fw_sweep, coefficients=comparisons)
