"""What a diagnosis used and what it warns about: diagnosis.json's ``constants`` and the data warnings read from the
data set itself (misspelt meta.json keys, too few runs to name an effect, the loader's own warnings).

Every constant the simulation was built from is stored with where it came from: the data set's meta.json, a command-
line option of the model (``--gap``), the calibration (from the data), or the default of docs/conventions.md.
"""
from __future__ import annotations

from typing import TYPE_CHECKING, Any, Mapping

if TYPE_CHECKING:
    from acousim.models import ModelSpec

__all__ = ["constants_used", "data_set_warnings", "CONSTANT_NAMES", "SOURCES"]

#: The experiment's constants (meta.json keys) in the order the report lists them, with their names in prose.
CONSTANT_NAMES = {
    "side_length_m": ("cube side", "m"),
    "frequency_hz": ("drive frequency", "Hz"),
    "particle_density_kg_m3": ("cube density", "kg/m^3"),
    "bulk_modulus_pa": ("cube bulk modulus", "Pa"),
    "sound_speed_m_s": ("speed of sound", "m/s"),
    "air_density_kg_m3": ("air density", "kg/m^3"),
    "pressure_amplitude_pa": ("nominal pressure amplitude", "Pa"),
}

#: Where a constant came from (``constants[i]["source"]``).
SOURCES = {"meta.json": "the data set's meta.json", "default": "the default of docs/conventions.md section 1",
           "option": "a command-line option of the model", "calibrated": "calibrated from the runs",
           "model default": "the model's own default"}


def _model_parameter(name: str, spec: "ModelSpec", calibration: Mapping[str, Any]) -> dict:
    """A model's own parameter (the full-wave hinge gap): given as an option, calibrated, or the model's default."""
    base, unit = name.rsplit("_", 1)
    value = calibration.get(name)
    if name in dict(spec.options):
        source = "option"
    elif calibration.get(f"{base}_calibrated"):
        source = "calibrated"
    else:
        source = "model default"
    iv = (calibration.get("uncertainty") or {}).get(name) or {}
    return {"key": name, "name": f"hinge {base}" if base == "gap" else base.replace("_", " "), "value": value,
            "unit": unit, "std_error": iv.get("std_error"), "source": source,
            "note": calibration.get(f"{base}_note")}


def constants_used(meta: Mapping[str, Any], spec: "ModelSpec", calibration: Mapping[str, Any]) -> list[dict]:
    """diagnosis.json's ``constants``: ``[{"key", "name", "value", "unit", "std_error", "source", "note"}, ...]``,
    the experiment's constants (meta.json or the defaults), the model's own calibratable parameters, then the
    calibrated pressure amplitude with its standard error (``source`` one of :data:`SOURCES`)."""
    from cubedimer.meta import META_DEFAULTS

    out = []
    for key, (name, unit) in CONSTANT_NAMES.items():
        given = key in meta
        out.append({"key": key, "name": name, "value": float(meta[key] if given else META_DEFAULTS[key]),
                    "unit": unit, "std_error": None, "source": "meta.json" if given else "default", "note": None})
    for key in (k for k in calibration if k.endswith("_m") and f"{k.rsplit('_', 1)[0]}_calibrated" in calibration):
        out.append(_model_parameter(key, spec, calibration))
    iv = (calibration.get("uncertainty") or {}).get("pressure_amplitude_pa") or {}
    out.append({"key": "calibrated_pressure_amplitude_pa", "name": "calibrated pressure amplitude",
                "value": calibration["pressure_amplitude_pa"], "unit": "Pa", "std_error": iv.get("std_error"),
                "source": "calibrated", "note": "standard error over runs (delete-one-run jackknife) with the "
                                                "calibration's systematic error"})
    return out


def data_set_warnings(dataset, n_runs: int, settings: Mapping[str, Any]) -> list[dict]:
    """The data warnings a diagnosis reads from the data set (``{"code", "message"}``): meta.json keys this suite does
    not know, each with the known key it most likely misspells (``meta_unknown_keys``); too few runs for the held-out
    test to name any effect (``too_few_runs``); runs split at a tracking gap into parts (``run_split``, from each
    part's ``Run.source``); and any warning the loader recorded on the data set (``dataset.warnings``, when it has
    them)."""
    from cubedimer.meta import META_BLOCK_KEYS, META_RANGES, META_TEXT_KEYS, unknown_keys_message

    out = []
    meta = dataset.meta or {}
    unknown = [k for k in meta if k not in META_RANGES and k not in META_TEXT_KEYS and k not in META_BLOCK_KEYS
               and k != "system"]
    if unknown:
        out.append({"code": "meta_unknown_keys", "message": f"meta.json: {unknown_keys_message(unknown)}"})
    if settings.get("identification_possible") is False:
        out.append({"code": "too_few_runs", "message": (
            f"with {n_runs} runs no effect can be named: the held-out sign-flip test's smallest p is "
            f"{settings['smallest_attainable_p']:.3g} (2^-{n_runs}), above alpha = {settings['alpha']:g}; record at "
            f"least {settings['runs_needed']} runs")})
    parts: dict[str, list] = {}
    for r in getattr(dataset, "runs", ()):
        if getattr(r, "source", None):
            parts.setdefault(r.source, []).append(r)
    for source, runs in parts.items():
        out.append({"code": "run_split", "message": f"{source} split at a tracking gap longer than the fill limit into "
                    + ", ".join(f"{r.name} (frames {r.frames[0]}-{r.frames[1] - 1})" if getattr(r, "frames", None)
                                else r.name for r in runs)})
    for w in getattr(dataset, "warnings", ()) or ():
        out.append(dict(w) if isinstance(w, Mapping) else {"code": "loader", "message": str(w)})
    return out
