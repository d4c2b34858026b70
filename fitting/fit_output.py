"""The files of a fit: ``model.json`` (docs/formats.md) and the figures, written by the command, not by the fit."""
from __future__ import annotations

import json
import os
from dataclasses import asdict
from pathlib import Path

import numpy as np

from cubedimer.atomic import json_text, write_json
from cubedimer.terms import EQUATION_NAMES, STATE_NAMES
from .ensemble import mean_pvalues
from .integral_form import METHOD as INTEGRAL_METHOD
from .methods import METHODS
from .model import TERMS
from .results import FitResult

__all__ = ["model_json", "fit_record", "write_fit", "data_range"]


def _terms(mask) -> dict[str, list[str]]:
    return {eq: [t for t, k in zip(TERMS, mask[q]) if k] for q, eq in enumerate(EQUATION_NAMES)}


def _recorded_settings(res: FitResult) -> dict:
    """The configuration, without the fields only the other methods read."""
    settings = json.loads(json.dumps(asdict(res.config), default=float))
    for name, method in METHODS.items():
        if name != res.method:
            for key in method.private_settings:
                settings.pop(key, None)
    return settings


def model_json(res: FitResult) -> dict:
    """The docs/formats.md ``model.json`` content (plus extra keys)."""
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
        "zscores": res.stats.as_dict(res.stats.zscore),
        "per_run": per_run,
        "units": "SI",
        "inclusion_frequency": res.stats.as_dict(res.stats.inclusion),
        "coefficient_mean": res.stats.as_dict(res.stats.mean),
        "coefficient_std": res.stats.as_dict(res.stats.std),
        "selected_terms": _terms(res.mask),
        "regression_c0": res.pooled_regression.equations(),
        "joint_start": res.joint_start.equations(),
        "loss": {"joint_start": res.joint.loss_start.to_dict(), "final": res.joint.loss_end.to_dict(),
                 "n_evals": res.joint.n_evals, "nlopt_status": res.joint.status},
        "scales": res.scales.to_dict(),
        "settings": _recorded_settings(res),
        "skipped_files": list(res.skipped),
        "glitch_frames_masked": res.n_glitches,
        "selection": _selection_json(res),
        "integral_form": _integral_form_json(res),
        "fallback": res.fallback,
        "oracle": res.oracle.to_json() if res.oracle is not None else None,
        "method": res.method,
        "data_range": data_range(res),
    }
    if res.discovery is not None:
        out["discovery"] = disc = res.discovery.to_json()
        # the discovery is the pooled integral form: its estimates in the cross-check's place (same keys)
        out["integral_form"] = {"method": disc["method"], **{
            eq: {k: disc[eq][k] for k in ("terms", "window_s", "residual_std")} for eq in EQUATION_NAMES}}
    return out


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


def _integral_form_json(res: FitResult) -> dict | None:
    """The pooled integral-form selection per equation (a cross-check; not the minimal model)."""
    if res.integral_form is None:
        return None
    return {"method": INTEGRAL_METHOD, **{eq: s.to_json() for eq, s in res.integral_form.items()}}


def _selection_json(res: FitResult) -> dict:
    """Which rule produced ``equations`` (the method's name when it selects the terms itself) and what the
    z-score rule gives."""
    out: dict = {"rule": res.rule if res.rule is not None else res.method,
                 "mean_pvalues": res.stats.as_dict(mean_pvalues(res.stats))}
    out["zscore_rule"] = {"z_threshold": res.config.ensemble.z_threshold, "selected_terms": _terms(res.mask_zscore)}
    if res.selection is not None:
        out["backward"] = {"alpha": res.config.selection.alpha, "selected_terms": _terms(res.selection.mask),
                           "steps": [s.to_dict() for s in res.selection.steps]}
    if res.candidate_fit is not None:
        out["candidate_fit"] = {"equations": res.candidate_fit.model.equations(),
                                "loss": res.candidate_fit.loss_end.to_dict()}
    return out


def write_fit(res: FitResult, out_dir: str | os.PathLike, plots: bool = True) -> Path:
    """Write ``out_dir/model.json`` and, if ``plots``, the fit's figures (:func:`fitting.plots.plot_fit`);
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
