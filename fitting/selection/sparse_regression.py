"""Sparse regression of accelerations on the cubic library with pysindy (the initial model C0).

Variables are scaled for conditioning (:class:`~fitting.model.Scales`: y / L_y,
theta / L_theta, t / T with T = 1 / (2 pi f_y)), so every library column and both targets are
O(1); the sequentially thresholded least squares (STLSQ) threshold is therefore a dimensionless
coefficient size.  Coefficients are converted back and reported in SI.
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from cubedimer.config_checks import check_non_negative, check_positive, check_whole
from cubedimer.terms import STATE_NAMES, parse_term
from ..derivatives.savitzky_golay import Derivatives
from ..model import EXPONENTS, TERMS, PolynomialModel, Scales

__all__ = ["RegressionConfig", "dataset_scales", "fit_regression", "fit_ensemble_regression",
           "scaled_data", "scaled_library", "pysindy_to_canonical"]


@dataclass(frozen=True)
class RegressionConfig:
    """STLSQ settings (dimensionless, in scaled variables).

    Parameters
    ----------
    threshold : float
        Coefficients below this size (scaled) are cut.
    alpha : float
        Ridge regularisation.
    max_iter : int
    matched_filter : bool
        Regress the Savitzky-Golay accelerations on library columns filtered by the same kernel
        (:meth:`~fitting.derivatives.savitzky_golay.Derivatives.matched`), which removes the filter's attenuation
        bias (y^2 and y*ydot*thetadot live at 2 f_y, where it is strongest); pysindy's STLSQ is then
        applied to the precomputed library.  False: plain ``pysindy.SINDy`` on the smoothed states.
    relative_threshold : bool
        Apply ``threshold`` to each equation relative to its signal scale (the RMS of its
        least-squares prediction) over the larger equation's.  The time scale of the scaled variables
        is the y period, so on a soft hinge (f_theta << f_y) every scaled theta coefficient is small:
        measured on Gor'kov twin data (f_theta = 1.7 Hz), y*theta (18 % of the hinge stiffness at the
        y amplitude) has a scaled coefficient of 0.001 and is cut by the absolute threshold 0.003; with
        this option it is found (20 runs, theta noise 2e-4).  Off by default: on the 30-run benchmark
        of the reduced model (f_theta = 9 Hz) the lower theta threshold let more collinear terms into
        the per-run fits and y*thetadot^2 lost its significance (missing; with the absolute threshold
        all 11 terms are found).  ``python -m fitting fit --relative-threshold``.
    """

    threshold: float = 0.003
    alpha: float = 0.3
    max_iter: int = 20
    matched_filter: bool = True
    relative_threshold: bool = False

    def __post_init__(self) -> None:
        check_positive(self, "threshold")
        check_non_negative(self, "alpha")
        check_whole(self, "max_iter")


def dataset_scales(derivs: Sequence[Derivatives], f_y: Sequence[float]) -> Scales:
    """Common scales of a data set: median over runs of max|y|, max|theta| and 1/(2 pi f_y) (1 for a coordinate that
    does not move, whatever its unit)."""
    ly = float(np.median([np.max(np.abs(d.state[:, 0])) for d in derivs]))
    lt = float(np.median([np.max(np.abs(d.state[:, 2])) for d in derivs]))
    return Scales(length_y=ly if ly > 0 else 1.0, length_theta=lt if lt > 0 else 1.0, time=1.0 / (2 * np.pi * float(np.median(f_y))))


def scaled_data(derivs: Sequence[Derivatives], scales: Scales) -> tuple[list[NDArray], list[NDArray]]:
    """Interior states and accelerations of every run in scaled variables."""
    X, A = [], []
    for d in derivs:
        s, a = d.interior()
        X.append(s / scales.state)
        A.append(a / scales.accel)
    return X, A


def scaled_library(derivs: Sequence[Derivatives], scales: Scales, matched_filter: bool = True) -> list[NDArray]:
    """Per run: the 35-term library of the scaled smoothed states on the interior frames, its columns
    filtered by the acceleration kernel when ``matched_filter`` (see :class:`RegressionConfig`)."""
    from cubedimer.terms import evaluate_library

    out = []
    for d in derivs:
        lib = evaluate_library(d.state / scales.state)
        if matched_filter:
            lib = d.matched(lib)
        out.append(lib[d.trim: d.state.shape[0] - d.trim])
    return out


def pysindy_to_canonical(names: list[str], coef: NDArray) -> NDArray:
    """Reorder pysindy's feature columns (names like ``y ydot^2``) to the canonical library."""
    index = {tuple(e): j for j, e in enumerate(EXPONENTS)}
    out = np.zeros((coef.shape[0], len(TERMS)))
    for k, nm in enumerate(names):
        canon = "*".join(nm.split()) if nm != "1" else "1"
        out[:, index[tuple(parse_term(canon))]] = coef[:, k]
    return out


def _sindy(optimizer, X: list[NDArray], A: list[NDArray], dt: float) -> tuple[list[str], NDArray]:
    import pysindy as ps

    model = ps.SINDy(optimizer=optimizer, feature_library=ps.PolynomialLibrary(degree=3))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model.fit(X if len(X) > 1 else X[0], t=dt, x_dot=A if len(A) > 1 else A[0],
                  feature_names=list(STATE_NAMES))
    return model.get_feature_names(), model


def fit_regression(derivs: Sequence[Derivatives], scales: Scales,
                   config: RegressionConfig = RegressionConfig(),
                   candidates: NDArray[np.bool_] | None = None) -> PolynomialModel:
    """STLSQ fit of [yddot, thetaddot] on the 35-term library (several runs fitted jointly).

    Parameters
    ----------
    derivs : list of Derivatives
    scales : Scales
    config : RegressionConfig
    candidates : ndarray of bool (2, 35), optional
        Restrict each equation to these library terms (pysindy ``STLSQ`` is then applied to the
        candidate columns of the precomputed library).

    Returns
    -------
    PolynomialModel
        SI coefficients (C0).
    """
    import pysindy as ps

    X, A = scaled_data(derivs, scales)
    if candidates is None and not config.matched_filter:
        dt = float(derivs[0].t[1] - derivs[0].t[0]) / scales.time
        opt = ps.STLSQ(threshold=config.threshold, alpha=config.alpha, max_iter=config.max_iter)
        names, model = _sindy(opt, X, A, dt)
        coef = pysindy_to_canonical(names, model.coefficients())
        return PolynomialModel(scales.to_si(coef))
    if candidates is None:
        candidates = np.ones((2, len(TERMS)), bool)
    Theta = np.vstack(scaled_library(derivs, scales, config.matched_filter))
    acc = np.vstack(A)
    coef = np.zeros((2, len(TERMS)))
    ratio = np.ones(2)
    if config.relative_threshold:
        # each equation's signal scale: RMS of its least-squares prediction on its candidate columns
        # (the noise goes to the residual); the threshold applies relative to the larger of the two
        sig = np.zeros(2)
        for q in range(2):
            cols = np.flatnonzero(candidates[q])
            if cols.size:
                c_ls = np.linalg.lstsq(Theta[:, cols], acc[:, q], rcond=None)[0]
                sig[q] = float(np.sqrt(np.mean((Theta[:, cols] @ c_ls) ** 2)))
        if sig.max() > 0:
            ratio = np.where(sig > 0, sig / sig.max(), 1.0)
    for q in range(2):
        cols = np.flatnonzero(candidates[q])
        if cols.size == 0:
            continue
        opt = ps.STLSQ(threshold=config.threshold, alpha=config.alpha, max_iter=config.max_iter)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            opt.fit(Theta[:, cols], acc[:, q:q + 1] / ratio[q])
        coef[q, cols] = np.asarray(opt.coef_).reshape(-1) * ratio[q]
    return PolynomialModel(scales.to_si(coef))


def fit_ensemble_regression(derivs: Sequence[Derivatives], scales: Scales,
                            config: RegressionConfig = RegressionConfig(), n_models: int = 50,
                            inclusion: float = 0.5, seed: int = 0) -> tuple[PolynomialModel, NDArray]:
    """pysindy ``EnsembleOptimizer`` baseline (bagged STLSQ, E-SINDy).

    A term is kept when its inclusion probability over the bagged fits is at least
    ``inclusion``; kept coefficients are the median over the bags.

    Returns
    -------
    model : PolynomialModel (SI)
    inclusion_probability : ndarray (2, 35)
    """
    import pysindy as ps

    X, A = scaled_data(derivs, scales)
    dt = float(derivs[0].t[1] - derivs[0].t[0]) / scales.time
    np.random.seed(seed)  # EnsembleOptimizer draws from numpy's global generator
    opt = ps.EnsembleOptimizer(ps.STLSQ(threshold=config.threshold, alpha=config.alpha,
                                        max_iter=config.max_iter), bagging=True, n_models=n_models)
    names, model = _sindy(opt, X, A, dt)
    coefs = np.array([pysindy_to_canonical(names, c) for c in opt.coef_list])
    p = np.mean(coefs != 0, axis=0)
    med = np.where(p >= inclusion, np.median(coefs, axis=0), 0.0)
    return PolynomialModel(scales.to_si(med)), p
