"""The files of a fit: ``model.json`` (docs/formats.md) and the figures, written by the command, not by the fit;
and the one reader of ``model.json`` (:func:`read_model_json`)."""
from __future__ import annotations

import json
import os
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from cubedimer.atomic import json_text, write_json
from cubedimer.errors import DatasetError
from cubedimer.meta import META_DEFAULTS
from cubedimer.system import SystemSpec, read_system
from cubedimer.terms import STATE_NAMES, parse_term
from ..method_names import METHODS
from ..model import PolynomialModel
from ..results import FitResult, support_terms

__all__ = ["model_json", "fit_record", "write_fit", "data_range", "dimer_record", "MODEL_JSON_KEYS", "ModelFile",
           "read_model_json"]


#: model.json's keys in the order they are written; a method's own keys (``FitResult.extras.record``) take their
#: place among them, keys not listed follow at the end.
MODEL_JSON_KEYS = ("state", "equations", "zscores", "per_run", "units", "inclusion_frequency", "coefficient_mean",
                   "coefficient_std", "selected_terms", "regression_c0", "joint_start", "loss", "scales", "settings",
                   "skipped_files", "glitch_frames_masked", "selection", "integral_form", "fallback", "oracle", "method",
                   "data_range", "dimer", "discovery")


def _recorded_settings(res: FitResult) -> dict:
    """The configuration, without the fields only the other methods read."""
    settings = json.loads(json.dumps(asdict(res.config), default=float))
    for name, method in METHODS.items():
        if name != res.method:
            for key in method.private_settings:
                settings.pop(key, None)
    return settings


def model_json(res: FitResult) -> dict:
    """The docs/formats.md ``model.json`` content (plus extra keys): what every method produces and the method's own
    keys (``res.extras.record``)."""
    per_run = []
    for p, f, lt in zip(res.runs, res.run_fits, res.joint.per_run_end):
        d = f.model_json()
        d["attractor"] = p.attractor.to_dict()
        d["loss_minimal_model"] = lt.to_dict()
        d["glitch_frames_masked"], d["frames_averaged"] = p.run.n_glitches, p.frames_averaged
        per_run.append(d)
    out = {
        "state": list(STATE_NAMES),
        "equations": res.model.equations(),
        "per_run": per_run,
        "units": "SI",
        "selected_terms": support_terms(res.mask),
        "regression_c0": res.pooled_regression.equations(),
        "joint_start": res.joint_start.equations(),
        "loss": {"joint_start": res.joint.loss_start.to_dict(), "final": res.joint.loss_end.to_dict(),
                 "n_evals": res.joint.n_evals, "nlopt_status": res.joint.status},
        "scales": res.scales.to_dict(),
        "settings": _recorded_settings(res),
        "skipped_files": list(res.skipped),
        "glitch_frames_masked": res.n_glitches,
        "fallback": res.fallback,
        "oracle": res.oracle.to_json() if res.oracle is not None else None,
        "method": res.method,
        "data_range": data_range(res),
    }
    if not res.system.generic:
        out["dimer"] = dimer_record(res.meta)
    if res.extras is not None:
        out.update(res.extras.record(res))
    place = {k: i for i, k in enumerate(MODEL_JSON_KEYS)}
    return dict(sorted(out.items(), key=lambda item: place.get(item[0], len(place))))  # stable: others keep order


def fit_record(res: FitResult) -> dict:
    """:func:`model_json` as a reader of the file sees it (strict JSON: non-finite numbers as None, plain Python
    numbers), in the library's own names: what the methods' descriptions read (``FittingMethod.describe``)."""
    return json.loads(json_text(model_json(res)))


def data_range(res: FitResult) -> dict:
    """The box the fitted data span, ``{"theta_abs_max", "y_abs_max_m"}``: the largest |theta| and |y| [m] of
    the runs the fit saw (filled frames included, origin as in the data).  ``validation compare`` fits the
    simulated static coefficients over this box unless told otherwise."""
    theta = max(float(np.max(np.abs(p.run.theta))) for p in res.runs)
    y = max(float(np.max(np.abs(p.run.y))) for p in res.runs)
    return {"theta_abs_max": theta, "y_abs_max_m": y}


def dimer_record(meta: dict) -> dict:
    """The fitted data's dimer and experiment, ``{key: value, ..., "from_meta_json": [keys]}``: every physical
    constant of meta.json (:data:`cubedimer.meta.META_DEFAULTS`'s keys, SI: side, density, bulk modulus, frequency,
    sound speed, air density, nominal pressure), the default of docs/conventions.md where meta.json states none, and
    which ones meta.json stated.  ``validation compare`` checks a sweep's dimer against it."""
    return {**{k: float(meta.get(k, v)) for k, v in META_DEFAULTS.items()},
            "from_meta_json": [k for k in META_DEFAULTS if k in meta]}


def write_fit(res: FitResult, out_dir: str | os.PathLike, plots: bool = True) -> Path:
    """Write ``out_dir/model.json`` and, if ``plots``, the fit's figures (:func:`fitting.output.plots.plot_fit`);
    returns the model.json path."""
    out = Path(out_dir)
    path = out / "model.json"
    doc = model_json(res)
    if res.system.generic:  # the declared coordinates' names (cubedimer.system)
        doc = {**res.system.rename(doc), "system": res.system.to_json()}
    write_json(path, doc)
    if plots:
        from .plots import plot_fit  # matplotlib only when figures are asked for
        plot_fit(res, out)
    return path


@dataclass(frozen=True)
class ModelFile:
    """A read ``model.json``: the document as written, the system it records and its model in the library's names."""

    path: Path
    document: dict
    system: SystemSpec
    model: PolynomialModel


def read_model_json(path: str | os.PathLike) -> ModelFile:
    """Read and check a ``model.json`` (docs/formats.md; a ``truth.json`` has the same model part).

    Raises
    ------
    DatasetError
        One line naming the file and the problem: unreadable, not JSON, no ``equations`` object, an unknown
        equation, a bad term or coefficient, another unit system or state.
    """
    path = Path(path)
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise DatasetError(f"{path}: cannot read ({exc.strerror or exc}); give the model.json `fitting fit` writes") \
            from None
    except json.JSONDecodeError as exc:
        raise DatasetError(f"{path}: not valid JSON ({exc.msg} at line {exc.lineno})") from None
    except UnicodeDecodeError:
        raise DatasetError(f"{path}: not valid JSON (not UTF-8 text)") from None
    if not isinstance(doc, dict) or not isinstance(doc.get("equations"), dict):
        raise DatasetError(f"{path}: not a model.json (no 'equations' object)")
    system = read_system({"system": doc.get("system")}, str(path))
    for eq, coefs in doc["equations"].items():
        if eq not in system.equation_names or not isinstance(coefs, dict):
            raise DatasetError(f"{path}: unknown equation {eq!r}; expected {' and '.join(system.equation_names)}")
        for term, v in coefs.items():
            try:
                parse_term(term, system.state_names)
                float(v)
            except (ValueError, TypeError):
                raise DatasetError(f"{path}: bad term or value {term!r}: {v!r} in {eq}") from None
    try:
        model = PolynomialModel.from_json(doc)
    except (ValueError, KeyError, TypeError) as exc:
        raise DatasetError(f"{path}: not a readable model.json ({exc})") from None
    return ModelFile(path, doc, system, model)
