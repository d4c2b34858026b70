"""What the report's sections read: :class:`ReportContext`, and the steps that fill it after the fit and the
diagnosis (the variant comparison, the calibrated simulations and their static sweeps).

Every section of :mod:`validation.report.sections` is a function of one frozen :class:`ReportContext`; nothing a
section needs is computed twice.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable

import numpy as np

if TYPE_CHECKING:
    from fitting.refinement.long_time import RefineConfig

__all__ = ["ReportContext", "variant_comparison", "report_context"]

logger = logging.getLogger(__name__)


@dataclass(frozen=True, eq=False)
class CalibratedSimulation:
    """One registered force model calibrated on the data set, swept and compared with the fit.

    Attributes
    ----------
    name, label : str
        The registry name and the model's label in tables and prose.
    calibration : validation.diagnosis.calibrate.calibration.Calibration
        Its calibration (pressure, origin): the diagnosis's final one for the diagnosis's model.
    static : acousim.static_model.StaticModel
        The model at its calibrated pressure (with the diagnosis's calibrated parameters for the diagnosis's model).
    sweep_plot : acousim.statics.sweep.SweepResult
        Its static sweep over the plotted range.
    coefficients : validation.coefficients.CoefficientComparison
        Its static coefficients over the data's box against the fit.
    """

    name: str
    label: str
    calibration: Any
    static: Any
    sweep_plot: Any
    coefficients: Any


@dataclass(frozen=True, eq=False)
class ReportContext:
    """Everything the report's sections read.

    Attributes
    ----------
    data_dir, out : Path
        The data set and the report directory (figures in ``out/figures``, the fit in ``out/fit``).
    spec : acousim.models.ModelSpec
        The simulation model the diagnosis calibrated and its own options.
    atlas : Path or None
        Folder of an attractor atlas (the last section), if given.
    fit : fitting.FitResult
        The fit of the data set.
    model_json : dict
        The fit's model.json document.
    variant : fitting.compare.Comparison or None
        The minimal model against its variant without cross-coupling terms (None: the model has none).
    diagnosis : validation.diagnosis.Diagnosis
        The diagnosis (with its internals: the runs and fits for its figures).
    meta : dict
        The data set's meta.json.
    models : validation.diagnosis.summarise.model_comparison.ModelComparison
        The gaps of every registered model side by side, and the reference model with fitted pair scattering.
    simulations : tuple of CalibratedSimulation
        Every compared model, the reference model (the registry's first) first, in registry order.
    theta_max, y_max : float
        The box of the static fits: the 98 % quantiles of |theta| (at most 0.9) and of |y| [m] (y from the
        reference model's calibrated Z_eq).
    """

    data_dir: Path
    out: Path
    spec: Any
    atlas: Path | None
    fit: Any
    model_json: dict
    variant: Any
    diagnosis: Any
    meta: Any
    models: Any
    simulations: tuple
    theta_max: float
    y_max: float

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

    @property
    def reference(self) -> CalibratedSimulation:
        """The reference model (the registry's first, the Gor'kov model)."""
        return self.simulations[0]

    @property
    def others(self) -> tuple:
        """The other compared models, beside the reference one."""
        return self.simulations[1:]

    @property
    def diagnosed(self) -> CalibratedSimulation:
        """The diagnosis's model."""
        return next(s for s in self.simulations if s.name == self.spec.name)

    def unavailable(self) -> dict:
        """Why a registered model is not compared, by name (only the missing ones)."""
        return {n: r for n, r in self.models.unavailable.items() if r}


def variant_comparison(res, fit_dir: Path, joint: "RefineConfig | None" = None):
    """The minimal model against its variant without cross-coupling terms, re-optimised with the fit's joint
    re-optimisation ``joint`` (default: :data:`fitting.refinement.long_time.JOINT_REFINE`), with its figure in
    ``fit_dir``; None when the model has no cross-coupling terms."""
    from fitting.compare import compare_models, cross_coupling_mask
    from fitting.output.plots import plot_comparison
    from fitting.refinement.long_time import JOINT_REFINE

    mask = cross_coupling_mask(res.model)
    if not mask.any():
        return None
    variant = res.model.with_mask(res.model.support & ~mask)
    cmp_config = JOINT_REFINE if joint is None else joint
    prepared = res.runs
    cmp = compare_models(res.model, variant, [p.derivs for p in prepared], res.scales,
                         [p.run.name for p in prepared], config=cmp_config)
    plot_comparison(cmp, fit_dir)
    return cmp


def report_context(dataset, out: Path, res, model_json: dict, variant, diag, spec, *, atlas,
                   say: Callable[[str], None]) -> ReportContext:
    """The :class:`ReportContext` of a fitted and diagnosed data set: the simulations side by side, each calibrated
    simulation's static sweep over the data's box and its coefficient comparison with the fit."""
    from acousim.models import ModelSpec, force_model_type
    from acousim.statics.sweep import static_sweep

    from ..coefficients import static_comparison
    from ..diagnosis import compare_simulation_models
    from ..simulation import calibrated_model

    meta, internals = dataset.meta, diag.internals
    say("   the gaps of every registered simulation model and the reference one with fitted pair scattering, side by side")
    models = compare_simulation_models(internals.problem, spec, meta, base=internals.base)
    # each simulation at its own calibration: the diagnosis's final one for its model, the bare one for the others
    cals = {k: f.calibration for k, f in models.fits.items() if "+" not in k}
    cals[spec.name] = internals.final.calibration
    reference = models.rows[0].model
    say("4/5 sweeping the calibrated simulations and comparing coefficients")
    states = np.concatenate([p.derivs.state for p in res.runs])
    theta_max = float(min(0.9, np.quantile(np.abs(states[:, 2]), 0.98)))
    y_max = float(np.quantile(np.abs(states[:, 0] + cals[reference].origin_offset_m), 0.98))

    def simulation(name: str) -> CalibratedSimulation:
        mtype, cal = force_model_type(name), cals[name]
        own = spec if name == spec.name else ModelSpec(name)
        static = calibrated_model(meta, own, cal.pressure_amplitude_pa, diag.calibration if own is spec else None)
        plot = static_sweep(static, np.linspace(-0.9, 0.9, 61), np.linspace(-1.3 * y_max, 1.3 * y_max, 41))
        cmp = static_comparison(model_json, static, theta_max, y_max, origin_offset=cal.origin_offset_m,
                                origin_source="calibrated (section 6)")[1]
        return CalibratedSimulation(name, mtype.label, cal, static, plot, cmp)

    return ReportContext(data_dir=Path(dataset.path), out=Path(out), spec=spec,
                         atlas=None if atlas is None else Path(atlas), fit=res, model_json=model_json, variant=variant,
                         diagnosis=diag, meta=meta, models=models,
                         simulations=tuple(simulation(n) for n in cals), theta_max=theta_max, y_max=y_max)
