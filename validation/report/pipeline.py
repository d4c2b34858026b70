"""``python -m validation report``: the model-vs-simulation report of a data set.

:func:`build_report` runs, in order (each step logged): the fitting pipeline (``fitting.pipeline.fit_dataset``), the
variant comparison (the minimal model without its cross-coupling terms, re-optimised), the gap diagnosis
(:mod:`validation.diagnosis`, which also calibrates the simulation); then it fills the
:class:`validation.report.context.ReportContext` (the simulations side by side, static sweeps of the calibrated
simulations over the data's range and the coefficient comparison, :mod:`validation.coefficients`) and makes the
sections of :data:`validation.report.sections.SECTIONS` from it; it writes ``report.html`` (self-contained),
``figures/*.png``, ``numbers.json``, ``diagnosis.json`` and ``comparison.json``.
"""
from __future__ import annotations

import json
import logging
from dataclasses import replace
from pathlib import Path

from fitting.description import model_equation_text
from fitting.methods import get_method

from .sections.model_vs_simulation import effect_static_coefficients, lead_term_reading

__all__ = ["build_report", "model_equation_text", "lead_term_reading", "effect_static_coefficients"]

logger = logging.getLogger(__name__)


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
    from cubedimer.atomic import write_json
    from cubedimer.executor import ExecutorConfig
    from cubedimer.meta import read_meta
    from fitting.config import FitConfig
    from fitting.fit_output import write_fit
    from fitting.pipeline import fit_dataset

    from ..diagnosis import DiagnoseConfig, diagnose_dataset
    from ..simulation import model_from_meta
    from .context import report_context, variant_comparison
    from .html import write_report
    from .sections import SECTIONS

    level = logging.INFO if progress else logging.DEBUG

    def say(message: str) -> None:
        logger.log(level, "%s", message)

    # refuse a model that does not fit the experiment (a gap with Gor'kov, a dimer outside the full-wave family)
    # before the long fit, not after it
    model_from_meta(read_meta(data_dir), model=model, gap=gap, edge_radius=edge_radius)
    # and a data set with too few runs for the diagnosis's held-out comparison, with how many it needs
    _check_runs(data_dir)
    out = Path(out_dir)
    fit_dir = out / "fit"
    # ---- the fit, the variant comparison and the diagnosis: what the report reads --------------------------------
    config = FitConfig(method=method).with_heldout_tolerance(heldout_tolerance)
    if max_evals is not None:
        config = replace(config, refine=replace(config.refine, max_evals=max_evals),
                         polish=replace(config.polish, max_evals=max_evals),
                         joint=replace(config.joint, max_evals=max_evals))
    say(f"1/5 fitting the data ({get_method(method).summary})")
    res = fit_dataset(data_dir, config, ExecutorConfig(workers=workers, scheduler=scheduler), progress=progress,
                      cache_dir=fit_dir / "runs")
    write_fit(res, fit_dir)
    model_json = json.loads((fit_dir / "model.json").read_text())
    say("2/5 comparing the minimal model with its variant without cross-coupling terms")
    variant = variant_comparison(res, fit_dir, max_evals)
    say("3/5 diagnosing the sim-to-real gap (calibrating the simulation)")
    diag, internals = diagnose_dataset(data_dir, DiagnoseConfig(), progress=progress, model=model, gap=gap,
                                       edge_radius=edge_radius)
    # ---- the calibrated simulations and their sweeps (steps 3-4), then the sections from the one context ---------
    context = report_context(data_dir, out, res, model_json, variant, diag, internals, model=model, gap=gap,
                             edge_radius=edge_radius, atlas=atlas, say=say)
    say("5/5 figures and the report")
    sections = [s for _, make in SECTIONS if (s := make(context)) is not None]
    write_json(out / "diagnosis.json", diag)
    write_json(out / "comparison.json", next(s.numbers for s in sections if s.id == "model-vs-simulation"))
    path = write_report(sections, out, "Cube dimer: model vs simulation",
                        f"data set {Path(data_dir).resolve()}; all quantities SI unless an axis says otherwise")
    say(f"written {path}")
    return path


def _check_runs(data_dir) -> None:
    """:func:`validation.diagnosis.pipeline.check_enough_runs` on the data set as the diagnosis loads it."""
    from acousim.analytic import nominal_trap_frequency
    from cubedimer.dataset import LoadConfig, load_dataset

    from ..diagnosis import DiagnoseConfig
    from ..diagnosis.pipeline import check_enough_runs

    dataset = load_dataset(data_dir, config=LoadConfig(trap_frequency=nominal_trap_frequency), report=lambda m: None)
    check_enough_runs(data_dir, len(dataset.runs), len(dataset.skipped_files()), DiagnoseConfig().alpha)
