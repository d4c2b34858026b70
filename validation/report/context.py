"""What the report's sections read: :class:`ReportContext`, a view of a finished run's stored results.

Every number a section prints is stored in the report directory's ``diagnosis.json`` (the diagnosis, its calibrated
simulations side by side, the constants used, the time-series overlay) or in ``fit/model.json`` (the fit), with the
variant comparison in ``fit/variant.json``; the data set itself gives the figures of the data.  :func:`load_context`
reads them, so that ``python -m validation report --from DIR`` rebuilds a report in seconds, and the sections are
tested on stored results.
"""
from __future__ import annotations

import json
import logging
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

from cubedimer.errors import DatasetError

__all__ = ["ReportContext", "CalibratedSimulation", "variant_comparison", "load_context", "fit_description",
           "STORED_FILES"]

logger = logging.getLogger(__name__)

#: The stored results a report is a view of, relative to its directory (the variant file is optional: a model
#: without cross-coupling terms has none).
STORED_FILES = ("diagnosis.json", "fit/model.json", "fit/variant.json")


@dataclass(frozen=True, eq=False)
class CalibratedSimulation:
    """One registered force model calibrated on the data set (its stored record) and its static coefficients
    compared with the fit (:func:`validation.coefficients.compare_coefficients` on the stored coefficients).

    Attributes
    ----------
    record : validation.diagnosis.summarise.calibrated_simulations.SimulationRecord
    coefficients : validation.coefficients.CoefficientComparison
    """

    record: Any
    coefficients: Any

    @property
    def name(self) -> str:
        return self.record.name

    @property
    def label(self) -> str:
        return self.record.label


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
    model_json : dict
        The fit's model.json document.
    fit_model : fitting.model.PolynomialModel
        The fitted minimal model.
    described : fitting.description.MethodDescription
        The fitting method's account of its model (from model.json).
    prepared : list of fitting.results.PreparedRun
        The fitted runs, smoothed and classified (for the figures of the data).
    classify : cubedimer.attractors.ClassifyConfig
        The classifier's tolerances of the runs table.
    variant : dict or None
        The minimal model against its variant without cross-coupling terms (``fit/variant.json``; None: none).
    diagnosis : validation.diagnosis.Diagnosis
        The diagnosis, read from diagnosis.json.
    meta : dict
        The data set's meta.json.
    models : validation.diagnosis.summarise.model_comparison.ModelComparison
        The gaps of every registered model side by side, and the reference model with fitted pair scattering.
    simulations : tuple of CalibratedSimulation
        Every compared model, the reference model (the registry's first) first, in registry order.
    theta_max, y_max : float
        The box of the static fits (diagnosis.json ``model_comparison.static_box``).
    """

    data_dir: Path
    out: Path
    spec: Any
    atlas: Path | None
    model_json: dict
    fit_model: Any
    described: Any
    prepared: list
    classify: Any
    variant: dict | None
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


def variant_comparison(res, fit_dir: Path, joint=None):
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
    prepared = res.runs
    cmp = compare_models(res.model, variant, [p.derivs for p in prepared], res.scales,
                         [p.run.name for p in prepared], config=JOINT_REFINE if joint is None else joint)
    plot_comparison(cmp, fit_dir)
    return cmp


def fit_description(model_json: dict, result=None):
    """The fitting method's account of its model (:class:`fitting.description.MethodDescription`): its ``describe`` of
    the fit's ``result`` when given (the report's pipeline), else its ``describe_record`` of the stored model.json
    document; a method without one is described by its equations, with the method named."""
    from fitting.description import DescriptionTable, MethodDescription, model_equation_text
    from fitting.methods.registry import get_method

    method = get_method(model_json.get("method", "discovery"))
    if result is not None:
        return method.describe(result)
    if hasattr(method, "describe_record"):
        return method.describe_record(json.loads(json.dumps(model_json)))
    eqs = model_json["equations"]
    return MethodDescription(
        f"The {method.name} method's minimal model (its own account needs the fit in memory): "
        + "; ".join(model_equation_text(eqs)),
        DescriptionTable("Minimal model (SI)", ("equation", "term", "coefficient"),
                         tuple((eq, t, c) for eq in ("yddot", "thetaddot") for t, c in eqs.get(eq, {}).items())))


def _read_json(path: Path, what: str) -> dict:
    """A stored JSON document, or a one-line :class:`DatasetError` naming the file and what to do."""
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise DatasetError(f"{path}: missing; give the directory `python -m validation report` wrote ({what})") \
            from None
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise DatasetError(f"{path}: unreadable ({exc}); rebuild it with `python -m validation report`") from None
    if not isinstance(doc, dict):
        raise DatasetError(f"{path}: not a JSON object; rebuild it with `python -m validation report`")
    return doc


def _diagnosis(path: Path):
    """The stored diagnosis, with the records a report reads (a diagnosis.json of ``validation diagnose`` has none)."""
    from ..diagnosis import Diagnosis

    doc = _read_json(path, "the diagnosis")
    missing = [k for k in ("model_comparison", "data_set", "constants") if k not in doc]
    if missing:
        raise DatasetError(f"{path}: no {', '.join(missing)}: not written by `python -m validation report` (or by an "
                           "older version); make the report with `python -m validation report DATA --out DIR`")
    try:
        return Diagnosis.from_json(doc)
    except (KeyError, TypeError, ValueError) as exc:
        raise DatasetError(f"{path}: not a diagnosis.json ({type(exc).__name__}: {exc}); rebuild it with "
                           "`python -m validation report`") from None


def _prepared_runs(data_dir: Path, names: Sequence[str], config):
    """The fitted runs of the data set, prepared as the fit prepared them (``config``: its smoothing and
    classification, :func:`fitting.output.model_file.recorded_stages`), in model.json's order."""
    from fitting.fit import prepare_runs

    from ..diagnosis import load_for_diagnosis

    dataset = load_for_diagnosis(data_dir, progress=False)
    by_name = {r.name: r for r in dataset.runs}
    lost = [n for n in names if n not in by_name]
    if lost:
        raise DatasetError(f"{data_dir}: the fitted run(s) {', '.join(lost)} are missing; give the data set the report "
                           "was made from (--data)")
    return prepare_runs([by_name[n] for n in names], config)[0]


def load_context(out_dir: str | Path, *, data_dir: str | Path | None = None, atlas: str | Path | None = None,
                 prepared: list | None = None, classify=None, described=None) -> ReportContext:
    """The :class:`ReportContext` of a finished report directory ``out_dir`` (:data:`STORED_FILES`).

    Parameters
    ----------
    out_dir : the report directory (``python -m validation report`` wrote it)
    data_dir : the data set (default: the one diagnosis.json records)
    atlas : folder of an attractor atlas, shown as the last section
    prepared, classify : the fit's prepared runs and classifier settings, when the caller has them (the report's
        pipeline); otherwise the data set's runs are prepared again with the smoothing and classifier settings
        model.json records
    described : the fitting method's account of its model, when the caller has it (:func:`fit_description`)

    Raises
    ------
    DatasetError
        One line naming a missing or unreadable file, or a data set without the fitted runs.
    """
    from acousim.models import ModelSpec
    from cubedimer.attractors import ClassifyConfig
    from fitting.output.model_file import read_model_json

    from ..coefficients import compare_coefficients
    from ..diagnosis.summarise.calibrated_simulations import SimulationRecord
    from ..diagnosis.summarise.model_comparison import ModelComparison

    out = Path(out_dir)
    if not out.is_dir():
        raise DatasetError(f"{out}: not a directory; give the directory `python -m validation report` wrote (--out)")
    diag = _diagnosis(out / "diagnosis.json")
    model_file = read_model_json(out / "fit" / "model.json")
    model_json = model_file.document
    variant = _read_json(out / "fit" / "variant.json", "the variant comparison") \
        if (out / "fit" / "variant.json").exists() else None
    described = described if described is not None else fit_description(model_json)
    record = diag.model_comparison
    data = Path(data_dir) if data_dir is not None else Path(diag.data_set["path"])
    if prepared is None:
        from fitting.output.model_file import recorded_stages

        stages = recorded_stages(model_json)
        prepared = _prepared_runs(data, [r["file"] for r in model_json.get("per_run", [])]
                                  if all("file" in r for r in model_json.get("per_run", [])) else diag.data_set["runs"],
                                  stages)
        classify = stages.classify if classify is None else classify
    simulations = []
    for doc in record["simulations"]:
        rec = SimulationRecord.from_dict(doc)
        cmp = compare_coefficients(model_json, rec.static_coefficients, rec.static_std_errors,
                                   origin_offset=rec.origin_offset_m, static_box=rec.static_fit_box,
                                   origin_source="calibrated (section 6)")
        simulations.append(CalibratedSimulation(rec, cmp))
    options = (diag.data_set or {}).get("model_options") or {}
    return ReportContext(data_dir=data, out=out, spec=ModelSpec(diag.model, options),
                         atlas=None if atlas is None else Path(atlas), model_json=model_json,
                         fit_model=model_file.model, described=described, prepared=list(prepared),
                         classify=classify if classify is not None else ClassifyConfig(), variant=variant,
                         diagnosis=diag, meta=(diag.data_set or {}).get("meta", {}),
                         models=ModelComparison.from_dict(record), simulations=tuple(simulations),
                         theta_max=float(record["static_box"]["theta_max"]),
                         y_max=float(record["static_box"]["y_max_m"]))
