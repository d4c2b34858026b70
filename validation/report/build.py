"""``python -m validation report``: the model-vs-simulation report of a data set.

:func:`build_report` runs, in order (each step logged): the fitting pipeline (``fitting.fit.fit_dataset``, written as
``fit/model.json``), the variant comparison (the minimal model without its cross-coupling terms, re-optimised:
``fit/variant.json``), the gap diagnosis (:mod:`validation.diagnosis`, which also calibrates the simulation) and the
calibrated simulations side by side (:func:`with_simulations`: every registered model's gaps, static coefficients and
restoring curves, and one run's time-series overlay, stored in ``diagnosis.json``).  The report is then a view of
these stored results, :func:`render_report` (also ``python -m validation report --from REPORT_DIR``): it fills the
:class:`validation.report.context.ReportContext` from the files and makes the sections of
:data:`validation.report.sections.SECTIONS`; it writes ``report.html`` (self-contained), ``figures/*.png``,
``numbers.json`` and ``comparison.json``.
"""
from __future__ import annotations

import logging
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

from fitting.description import model_equation_text
from fitting.methods.registry import get_method

from .sections.model_vs_simulation import effect_static_coefficients, lead_term_reading

if TYPE_CHECKING:
    from acousim.models import ModelSpec
    from fitting.config import FitConfig

__all__ = ["build_report", "render_report", "with_simulations", "model_equation_text", "lead_term_reading", "effect_static_coefficients"]

logger = logging.getLogger(__name__)


def build_report(data_dir: str | Path, out_dir: str | Path, workers: int | None = None, scheduler: str | None = None,
                 progress: bool = True, max_evals: int | None = None, method: str = "discovery",
                 spec: "ModelSpec | None" = None, heldout_tolerance: float | None = None,
                 atlas: str | Path | None = None, fit_config: "FitConfig | None" = None) -> Path:
    """Fit, compare, diagnose and sweep the data set ``data_dir`` and write the report into ``out_dir``.

    Parameters
    ----------
    data_dir : path of the data set (CSV runs and meta.json)
    out_dir : report directory: report.html, ``figures/*.png``, numbers.json, fit/, diagnosis.json, comparison.json
    workers, scheduler : where the fit's refinements run (:class:`cubedimer.executor.ExecutorConfig`)
    progress : progress bars, and the steps logged at INFO level (else DEBUG)
    max_evals : evaluations of every long-time refinement: per run and joint for ``"paper"``, of the polish (and
        of a fallback's joint re-optimisation) for ``"discovery"``, and of the re-optimisation of the variant
        without cross-coupling terms (section 3); default: those of the fit's configuration
    method : the fit's model-discovery method (:data:`fitting.methods.registry.METHODS`), when ``fit_config`` is
        not given
    spec : the simulation model the diagnosis (section 6) calibrates and its own options
        (:class:`acousim.models.ModelSpec`; default: the registry's first, the Gor'kov model); every other registered
        model stands beside it in sections 4, 5 and 7 whenever it applies to the experiment; a model parameter the
        spec leaves unset that the data may determine (the full-wave hinge gap) is calibrated by the diagnosis
    heldout_tolerance : the discovery's practical threshold (:class:`fitting.selection.discovery_config.DiscoveryConfig`;
        default 0), when ``fit_config`` is not given
    atlas : folder of an attractor atlas (``python -m acousim atlas``), shown as the last section
    fit_config : the fit's settings (``python -m validation report`` makes them from the fit's options,
        :func:`fitting.options.fit_config_from_args`; default: those of ``method`` and ``heldout_tolerance``); its
        loading rules for glitches, short runs and gaps (``load.glitches``, ``load.min_periods``, ``load.max_gap``) are
        applied to the one loaded data set, and its method's joint re-optimisation (``method.joint``) re-optimises the
        variant

    Returns
    -------
    Path of report.html
    """
    from cubedimer.atomic import write_json
    from cubedimer.dataset import LoadConfig
    from cubedimer.executor import ExecutorConfig
    from fitting.config import FitConfig
    from acousim.models import ModelSpec
    from fitting.output.model_file import model_json, write_fit
    from fitting.fit import fit_dataset

    from ..diagnosis import DiagnoseConfig, diagnose, load_for_diagnosis, start_diagnosis

    from .context import fit_description, variant_comparison

    level = logging.INFO if progress else logging.DEBUG

    def say(message: str) -> None:
        logger.log(level, "%s", message)

    spec = spec if spec is not None else ModelSpec()
    config = (fit_config if fit_config is not None else
              FitConfig.for_method(method).with_heldout_tolerance(heldout_tolerance)).with_max_evals(max_evals, joint=True)
    # the data set, loaded once with the diagnosis's checks (and the fit's rules for glitches, short runs and gaps):
    # the fit and the diagnosis see the same runs
    load = replace(LoadConfig(), glitches=config.load.glitches, min_periods=config.load.min_periods,
                   max_gap=config.load.max_gap)
    dataset = load_for_diagnosis(data_dir, progress=progress, load=load)
    diagnosis_config = DiagnoseConfig()
    # refuse a model that does not fit the experiment (a dimer outside the full-wave family) before the long fit, and
    # a data set with too few runs for the diagnosis's held-out comparison, with how many it needs; then the runs are
    # prepared once (smoothing, derivatives, frequencies, column states, noise), and the fit and the diagnosis read
    # the one preparation
    start = start_diagnosis(dataset, spec, diagnosis_config.alpha, smoothing=config.smoothing,
                            candidates=diagnosis_config.candidates)
    out = Path(out_dir)
    fit_dir = out / "fit"
    # ---- the fit, the variant comparison and the diagnosis: the stored results the report is a view of -----------
    say(f"1/5 fitting the data ({get_method(config.method_name).summary})")
    res = fit_dataset(start.prepared, config, ExecutorConfig(workers=workers, scheduler=scheduler), progress=progress,
                      cache_dir=fit_dir / "runs")
    write_fit(res, fit_dir)
    say("2/5 comparing the minimal model with its variant without cross-coupling terms")
    variant = variant_comparison(res, fit_dir, config.method.joint)
    if variant is not None:
        write_json(fit_dir / "variant.json", variant.to_json())
    else:
        (fit_dir / "variant.json").unlink(missing_ok=True)
    say("3/5 diagnosing the sim-to-real gap (calibrating the simulation)")
    diag = diagnose(start, diagnosis_config, progress=progress)
    say("4/5 the calibrated simulations side by side: their gaps, static sweeps and coefficients")
    diag = with_simulations(diag, dataset.meta, spec, res, out / "figures")
    write_json(out / "diagnosis.json", diag.to_json())
    # ---- the report: a view of the stored results ---------------------------------------------------------------
    say("5/5 figures and the report")
    path = render_report(out, atlas=atlas, prepared=res.runs, classify=config.classify,
                         described=fit_description(model_json(res), res))
    say(f"written {path}")
    return path


def with_simulations(diag, meta: dict, spec, res, figs_dir: Path):
    """The diagnosis with the records a report reads (docs/formats.md): every registered model calibrated on the runs
    (``model_comparison``) and one run's time-series overlay (``overlay``); the reference model's posed mesh is
    rendered into ``figs_dir`` when the model can render it."""

    import numpy as np
    from acousim.models import force_model_type

    from ..diagnosis import compare_simulation_models
    from ..diagnosis.summarise.calibrated_simulations import model_comparison_record, overlay_record

    internals = diag.internals
    models = compare_simulation_models(internals.problem, spec, meta, base=internals.base)
    states = np.concatenate([p.derivs.state for p in res.runs])
    record, statics = model_comparison_record(models, internals, spec, meta, diag.calibration, states)
    reference = record["simulations"][0]["name"]
    if "render" in force_model_type(reference).capabilities:
        from acousim.gorkov.render import render_dimer

        render_dimer(statics[reference], 0.3, 0.0, figs_dir / f"dimer_{reference}.png")
    return replace(diag, model_comparison=record, overlay=overlay_record(internals))


def render_report(out_dir: str | Path, *, data_dir: str | Path | None = None, atlas: str | Path | None = None,
                  prepared=None, classify=None, described=None) -> Path:
    """The report of a finished run's stored results in ``out_dir`` (:func:`validation.report.context.load_context`):
    report.html, ``figures/*.png``, numbers.json and comparison.json, made from diagnosis.json, fit/model.json and
    fit/variant.json (and the data set's runs for the figures of the data) without fitting or simulating again.

    Raises
    ------
    DatasetError
        One line naming a missing or unreadable stored file.
    """
    from cubedimer.atomic import write_json

    from .context import load_context
    from .html import write_report
    from .sections import SECTIONS

    context = load_context(out_dir, data_dir=data_dir, atlas=atlas, prepared=prepared, classify=classify,
                           described=described)
    sections = [s for _, make in SECTIONS if (s := make(context)) is not None]
    write_json(context.out / "comparison.json", next(s.numbers for s in sections if s.id == "model-vs-simulation"))
    return write_report(sections, context.out, "Cube dimer: model vs simulation",
                        f"data set {context.data_dir}; all quantities SI unless an axis says otherwise")
