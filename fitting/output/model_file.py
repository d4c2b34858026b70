"""The files of a fit: ``model.json`` (docs/formats.md) and the figures, written by the command, not by the fit;
the one reader of ``model.json`` (:func:`read_model_json`) and of the settings it records (:func:`recorded_settings`)."""
from __future__ import annotations

import json
import os
from dataclasses import asdict, dataclass, fields, is_dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from cubedimer.atomic import json_text, write_json
from cubedimer.errors import DatasetError
from cubedimer.meta import META_DEFAULTS
from cubedimer.system import SystemSpec, read_system
from cubedimer.terms import STATE_NAMES, parse_term
from ..method_names import DEFAULT_METHOD, METHODS
from ..model import PolynomialModel
from ..results import FitResult, support_terms

if TYPE_CHECKING:
    from ..config import FitConfig

__all__ = ["model_json", "fit_record", "write_fit", "data_range", "dimer_record", "MODEL_JSON_KEYS", "ModelFile",
           "read_model_json", "recorded_settings", "recorded_stages", "settings_record", "SHARED_SETTINGS"]


#: model.json's keys in the order they are written; a method's own keys (``FitResult.extras.record``) take their
#: place among them, keys not listed follow at the end.
MODEL_JSON_KEYS = ("state", "equations", "zscores", "per_run", "units", "inclusion_frequency", "coefficient_mean",
                   "coefficient_std", "selected_terms", "regression_c0", "joint_start", "loss", "scales", "settings",
                   "skipped_files", "glitch_frames_masked", "selection", "integral_form", "fallback", "oracle", "method",
                   "data_range", "dimer", "discovery")


#: The settings every method shares (:class:`fitting.config.FitConfig`'s stages), at the top of model.json's
#: ``settings``; the method's own settings follow under its name.
SHARED_SETTINGS = ("load", "smoothing", "classify")

#: Keys of the method's settings that model.json files before the per-method layout recorded under another
#: top-level name: (method, field) -> former key (the discovery's selection was ``settings["discovery"]``).
_FORMER_KEYS = {("discovery", "selection"): "discovery"}


def settings_record(config: FitConfig) -> dict:
    """model.json's ``settings`` of ``config``: the shared stages, ``method`` (the name) and the method's settings
    under its name (docs/formats.md)."""
    doc = json.loads(json.dumps(asdict(config), default=float))
    return {**{k: doc[k] for k in SHARED_SETTINGS}, "method": config.method_name, config.method_name: doc["method"]}


def recorded_settings(doc: dict) -> dict:
    """The settings a model.json records (``doc``: the document), in today's layout whatever release wrote them.

    Today's layout (docs/formats.md) is ``{"load", "smoothing", "classify", "method": NAME, NAME: {...}}``: the
    shared stages, the method's name and the method's own settings under its name (the fields of its
    ``config_type``, :mod:`fitting.method_settings`).  Files written before the per-method layout recorded one flat
    dictionary (the shared stages, ``method`` and every method's fields side by side, the discovery's selection as
    ``discovery``); their method's fields are gathered under its name here.  Keys a file leaves out stay out (a
    reader takes the defaults it needs); a document without settings gives ``{"method": NAME, NAME: {}}`` with the
    document's ``method`` (default: the default method).
    """
    settings = doc.get("settings") if isinstance(doc.get("settings"), dict) else {}
    name = settings.get("method") if isinstance(settings.get("method"), str) else doc.get("method", DEFAULT_METHOD)
    method = METHODS.get(name)
    own = settings.get(name)
    if method is None:  # a method not registered here: its settings as recorded
        return {**settings, "method": name, name: own if isinstance(own, dict) else {}}
    keys = tuple(f.name for f in fields(method.config_type))
    if isinstance(own, dict) and all(k in keys for k in own):  # today's layout
        return {**settings, "method": name}
    shared = {k: settings[k] for k in SHARED_SETTINGS if k in settings}
    former = {k: settings[_FORMER_KEYS.get((name, k), k)] for k in keys if _FORMER_KEYS.get((name, k), k) in settings}
    return {**shared, "method": name, name: former}


def _config_from_record(default, record):
    """``default`` (a frozen config) with the fields ``record`` (its JSON record) gives, nested configs included; a
    nested config recorded as null is switched off; keys the config does not have, and callables, stay as they are."""
    if not isinstance(record, dict):
        return default
    changes = {}
    for f in fields(default):
        if f.name not in record:
            continue
        value, current = record[f.name], getattr(default, f.name)
        if is_dataclass(current):
            changes[f.name] = None if value is None else _config_from_record(current, value)
        elif current is None and isinstance(value, dict) or callable(current):
            continue
        else:
            changes[f.name] = tuple(value) if isinstance(value, list) else value
    return replace(default, **changes)


def recorded_stages(doc: dict) -> FitConfig:
    """The fit's shared stages (loading, smoothing, classification) as its model.json records them (either layout,
    :func:`recorded_settings`), at their defaults where the file leaves them out, and the method's default settings:
    what a later step needs to load and prepare the runs exactly as the fit did (``fitting compare``, a report made
    again from its files).

    Raises
    ------
    ValueError
        A recorded value its config refuses (one line, from the config's checks).
    """
    from ..config import FitConfig

    settings = recorded_settings(doc)
    name = settings["method"]
    base = FitConfig.for_method(name) if name in METHODS else FitConfig()
    return replace(base, **{stage: _config_from_record(getattr(base, stage), settings.get(stage))
                            for stage in SHARED_SETTINGS})


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
        "settings": settings_record(res.config),
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
