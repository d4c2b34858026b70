"""Where the gap lies: library terms, state-space regions and time scales of the acceleration residuals.

Output (diagnosis.json ``localization.before`` / ``localization.after``)::

    {"terms": {"yddot": [{"term", "mean_scaled", "std_scaled", "z", "explained_fraction_alone"}, ...],
               "thetaddot": [...]},
     "regions": {"theta_y": {"x_edges", "y_edges", "rms_yddot", "rms_thetaddot"}, "thetadot_ydot": {...}},
     "time_scales": {"bands_in_units_of_f_y", "fraction_yddot", "fraction_thetaddot"}}
"""
from __future__ import annotations

from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from ..prepare.runs import RunAccelerations

__all__ = ["localize_residuals"]


def localize_residuals(runs: Sequence[RunAccelerations], residuals: Sequence[NDArray], n_bins: int = 8) -> dict:
    """Where the residual lies: library terms (z-scores across runs), state-space bins, time scales.

    * ``terms``: per equation, each library term's coefficient from a per-run least-squares fit of
      the residual on the 35-term library (variables scaled), its mean, std and z-score across runs,
      and the fraction of residual variance each term explains when fitted alone.
    * ``regions``: RMS residual per equation on an (theta, y) grid and an (thetadot, ydot) grid.
    * ``time_scales``: fraction of the residual variance per frequency band, relative to the
      dominant y frequency of the data.
    """
    from cubedimer.terms import evaluate_library, library_terms

    terms = library_terms()
    allstate = np.concatenate([r.state for r in runs])
    scale = np.maximum(np.abs(allstate).max(axis=0), 1e-300)
    coefs = []
    for r, e in zip(runs, residuals):
        lib = evaluate_library(r.state / scale)
        c, *_ = np.linalg.lstsq(lib, e, rcond=None)
        coefs.append(c)
    coefs = np.array(coefs)  # (n_runs, 35, 2)
    libs = [evaluate_library(r.state / scale) for r in runs]
    terms_out = {}
    for q, eq in enumerate(("yddot", "thetaddot")):
        mean, std = coefs[:, :, q].mean(axis=0), coefs[:, :, q].std(axis=0, ddof=1) if len(runs) > 1 else np.full(35, np.nan)
        explained = []
        tot = sum(float(np.sum(e[:, q] ** 2)) for e in residuals)
        for j in range(len(terms)):
            num = 0.0
            for lib, e in zip(libs, residuals):
                col = lib[:, j]
                den = col @ col
                if den > 0:
                    num += (col @ e[:, q]) ** 2 / den
            explained.append(num / max(tot, 1e-300))
        rows = []
        for j, t in enumerate(terms):
            z = mean[j] / std[j] if std[j] > 0 else float("nan")
            rows.append({"term": t, "mean_scaled": float(mean[j]), "std_scaled": float(std[j]), "z": float(z),
                         "explained_fraction_alone": float(explained[j])})
        # rank by the share each term explains alone: along trajectories the library columns are
        # strongly correlated, so multivariate coefficients (and their z-scores) spread over them
        rows.sort(key=lambda d: -d["explained_fraction_alone"])
        terms_out[eq] = rows
    # regions
    res_all = np.concatenate(residuals)
    regions = {}
    for label, (i, j) in (("theta_y", (2, 0)), ("thetadot_ydot", (3, 1))):
        xe = np.quantile(allstate[:, i], np.linspace(0, 1, n_bins + 1))
        ye = np.quantile(allstate[:, j], np.linspace(0, 1, n_bins + 1))
        xi = np.clip(np.searchsorted(xe, allstate[:, i]) - 1, 0, n_bins - 1)
        yi = np.clip(np.searchsorted(ye, allstate[:, j]) - 1, 0, n_bins - 1)
        rms = np.full((2, n_bins, n_bins), np.nan)
        for a in range(n_bins):
            for b in range(n_bins):
                m = (xi == a) & (yi == b)
                if m.sum() >= 5:
                    rms[:, a, b] = np.sqrt(np.mean(res_all[m] ** 2, axis=0))
        regions[label] = {"x_edges": xe.tolist(), "y_edges": ye.tolist(), "rms_yddot": rms[0].tolist(), "rms_thetaddot": rms[1].tolist()}
    # time scales
    from cubedimer.spectra import dominant_frequency

    bands = [(0.0, 0.25), (0.25, 0.75), (0.75, 1.5), (1.5, 2.5), (2.5, np.inf)]
    power = np.zeros((len(bands), 2))
    for r, e in zip(runs, residuals):
        dt = float(np.median(np.diff(r.t)))
        fy = dominant_frequency(r.state[:, 0], dt)
        f = np.fft.rfftfreq(len(e), dt) / max(fy, 1e-12)
        spec = np.abs(np.fft.rfft(e - e.mean(axis=0), axis=0)) ** 2
        for b, (lo, hi) in enumerate(bands):
            m = (f >= lo) & (f < hi)
            power[b] += spec[m].sum(axis=0)
    power /= np.maximum(power.sum(axis=0), 1e-300)
    time_scales = {"bands_in_units_of_f_y": [[lo, hi if np.isfinite(hi) else None] for lo, hi in bands],
                   "fraction_yddot": power[:, 0].tolist(), "fraction_thetaddot": power[:, 1].tolist()}
    return {"terms": terms_out, "regions": regions, "time_scales": time_scales}
