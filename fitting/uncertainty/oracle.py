"""The oracle: the standard errors that integral-form least squares on a model's support can reach.

What it is
----------
For a polynomial model (its support: the non-zero terms) and a data set's runs (initial states,
lengths, frame rates) and tracking noise (white, ``sigma_y`` [m], ``sigma_theta`` [-]), the oracle
standard error of a term is the standard error of the pooled integral-form estimator of
:mod:`fitting.derivatives.integral_form` (measured positions minus each window's straight line regressed on the
detrended double integrals of the library columns; windows of 0.75 periods of the coordinate's own
dominant frequency; coefficients shared by all runs) when its columns are evaluated at the model's
*own noise-free trajectories* (the model integrated from each run's initial state with
:func:`fitting.integrate.integrate_batch`).  The only noise is then the tracking noise in the target,
and the detrending projection maps it to white noise on the design's range, so ordinary least squares
has the covariance ``sigma^2 (X^T X)^-1`` exactly (X: the stacked detrended design).  The oracle z of a
term is ``|coefficient| / oracle standard error``: roughly the best any estimator can do with the data.

Runs add information: ``X^T X`` is a sum of per-run matrices, so for runs drawn from the same
distribution of initial states the standard error falls like ``1 / sqrt(n_runs)``.  :func:`fitting.uncertainty.run_planning.plan_runs`
measures the per-run information on reference runs (and checks the exponent on nested subsets) and
tells how many runs make a term of a given size resolvable at a target oracle z.

Aliases.  The oracle z measures a term against *zero*.  A selection also has to tell it from its
*aliases*: a library term that can stand in for it.  On a nearly harmonic hinge y*thetadot^2 and
y*theta^2 differ only by an amplitude-dependent y term (thetadot^2 = omega^2 (A^2 - theta^2)), so the two
supports can fit the same data almost equally well however large the term is.  The **alias z** of a term
is ``sqrt(dRSS) / sigma``, with dRSS the noise-free residual sum of squares that remains when the term is
replaced by the best other library term (one for one, the other terms refitted): the number of noise
standard deviations by which the true support beats its closest one-for-one rival.  It never exceeds
the oracle z (dropping the term is one of the rivals' special cases).  With noise, the observed
difference of the two residual sums of squares is about ``dRSS + 2 sigma sqrt(dRSS) xi`` (xi standard
normal), so even the best estimator prefers the alias with probability ``Phi(-alias_z / 2)``: 16 % at
alias z 2, 2.3 % at 4.

Noise floor: a data set tracked from video records its tracking noise in ``meta.json``
(:func:`recorded_tracking_noise`), which is used when present; otherwise :func:`estimate_tracking_noise`
estimates the white tracking noise of each coordinate from the fourth differences of the raw positions (the motion's share is ``(omega dt)^4`` of its
amplitude), with the median absolute deviation, so isolated tracking glitches do not inflate it.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Mapping, Sequence

import numpy as np
from numpy.typing import NDArray

from cubedimer.config_checks import check_positive
from cubedimer.noise import white_noise_std
from cubedimer.spectra import dominant_frequency
from cubedimer.terms import EQUATION_NAMES, evaluate_library, parse_term
from ..derivatives.integral_form import integral_columns, integral_window, window_starts
from ..integrate import integrate_batch
from ..model import EXPONENTS, TERMS, PolynomialModel

if TYPE_CHECKING:
    from cubedimer.dataset import Run
    from ..derivatives.savitzky_golay import Derivatives

__all__ = ["NoiseLevels", "OracleRun", "OracleTerm", "OracleResult", "estimate_tracking_noise",
           "recorded_tracking_noise", "runs_from_data", "oracle_trajectories", "oracle_information", "oracle_aliases",
           "oracle_standard_errors", "covariance_diagonal", "integral_design", "schur_complement", "replacement_rss",
           "alias_probability", "canonical_term", "METHOD"]

#: The positions each equation is the second derivative of.
_COORD = {"yddot": 0, "thetaddot": 2}

#: One-line description written next to the result in model.json.
METHOD = ("oracle: standard error of pooled integral-form least squares on the model's support (windows of 0.75 of the "
          "coordinate's dominant period, 30-500 ms) with the columns at the model's own noise-free trajectories from "
          "each run's initial state and white tracking noise of the stated std; z = |coefficient| / oracle SE; alias: the "
          "library term that best replaces the term one for one, alias_z = sqrt(noise-free residual sum of squares of "
          "that replacement) / noise")


@dataclass(frozen=True)
class NoiseLevels:
    """White tracking noise of the positions.

    Parameters
    ----------
    sigma_y : float
        Standard deviation of the y noise [m].
    sigma_theta : float
        Standard deviation of the theta noise [-].
    source : str
        Where the levels come from (written beside them in model.json).
    """

    sigma_y: float
    sigma_theta: float
    source: str = "estimated from the data (fourth differences of the positions)"

    def __post_init__(self) -> None:
        for name in ("sigma_y", "sigma_theta"):
            check_positive(self, name)
            object.__setattr__(self, name, float(getattr(self, name)))

    def of(self, equation: str) -> float:
        """The noise of the coordinate ``equation`` is the second derivative of."""
        return self.sigma_y if equation == "yddot" else self.sigma_theta

    def to_json(self) -> dict:
        return {"sigma_y_m": self.sigma_y, "sigma_theta": self.sigma_theta, "source": self.source}


def recorded_tracking_noise(meta: Mapping) -> "NoiseLevels | None":
    """The tracking noise a data set records in ``meta.json`` (the ``tracking`` block that ``python -m tracking``
    writes: ``noise_y_m`` [m] and ``noise_theta`` [-], measured frame by frame from the images), or None when
    it records none (or an unusable one).  When present it is the oracle's noise level: it is measured from the
    images themselves, independently of the motion."""
    block = meta.get("tracking") if isinstance(meta, Mapping) else None
    if not isinstance(block, Mapping):
        return None
    try:
        return NoiseLevels(float(block["noise_y_m"]), float(block["noise_theta"]),
                           source="recorded by the tracking in meta.json (per-frame image-noise propagation)")
    except (KeyError, TypeError, ValueError):
        return None


@dataclass(frozen=True)
class OracleRun:
    """One run as the oracle sees it.

    Parameters
    ----------
    x0 : array (4,)
        Initial state [m, m/s, -, 1/s].
    n_frames : int
        Number of frames (including the initial one).
    dt : float
        Frame interval [s].
    bound : array (4,), optional
        Blow-up bound per state component (SI); only non-finite values stop the integration if None.
    """

    x0: NDArray[np.float64]
    n_frames: int
    dt: float
    bound: NDArray[np.float64] | None = None

    def __post_init__(self) -> None:
        x0 = np.asarray(self.x0, float).reshape(4)
        if not np.all(np.isfinite(x0)):
            raise ValueError("initial state must be finite")
        if int(self.n_frames) < 2 or not (float(self.dt) > 0):
            raise ValueError(f"need n_frames >= 2 and dt > 0, got {self.n_frames}, {self.dt}")
        object.__setattr__(self, "x0", x0)
        object.__setattr__(self, "n_frames", int(self.n_frames))
        object.__setattr__(self, "dt", float(self.dt))
        if self.bound is not None:
            object.__setattr__(self, "bound", np.broadcast_to(np.asarray(self.bound, float), (4,)).copy())


@dataclass(frozen=True)
class OracleTerm:
    """Oracle standard error of one term (SI units of its coefficient)."""

    coefficient: float
    std_error: float
    #: the library term that comes closest to standing in for this one (None: not computed)
    alias: str | None = None
    #: sqrt(noise-free residual sum of squares with the term replaced by ``alias``) / noise (module docstring)
    alias_z: float = float("nan")

    @property
    def z(self) -> float:
        """|coefficient| / standard error."""
        return abs(self.coefficient) / self.std_error if self.std_error > 0 else float("inf")

    @property
    def alias_probability(self) -> float:
        """Probability that least squares prefers the alias over the true support: Phi(-alias_z / 2)."""
        return alias_probability(self.alias_z) if np.isfinite(self.alias_z) else float("nan")

    def to_json(self) -> dict:
        """``{"coefficient", "std_error", "z", "alias", "alias_z"}``."""
        return {"coefficient": self.coefficient, "std_error": self.std_error, "z": self.z, "alias": self.alias,
                "alias_z": self.alias_z}


@dataclass(frozen=True)
class OracleResult:
    """Oracle standard errors of every term of a model on a set of runs.

    Attributes
    ----------
    terms : dict
        ``{equation: {term: OracleTerm}}`` for the model's support.
    noise : NoiseLevels
    n_runs : int
        Runs used (those whose trajectory did not blow up and is long enough for one window).
    n_blown_up : int
        Runs whose noise-free trajectory left its bound (they enter with their valid part only).
    window_s : dict
        Median window per equation [s].
    """

    terms: dict[str, dict[str, OracleTerm]]
    noise: NoiseLevels
    n_runs: int
    n_blown_up: int
    window_s: dict[str, float]

    def to_json(self) -> dict:
        """``{"method", "noise", "n_runs", "n_blown_up", "window_s",
        eq: {term: {"coefficient", "std_error", "z", "alias", "alias_z"}}}``."""
        out: dict = {"method": METHOD, "noise": self.noise.to_json(), "n_runs": self.n_runs,
                     "n_blown_up": self.n_blown_up, "window_s": dict(self.window_s)}
        for eq, terms in self.terms.items():
            out[eq] = {t: o.to_json() for t, o in terms.items()}
        return out


def alias_probability(alias_z: float) -> float:
    """Probability that least squares prefers the alias over the true support: Phi(-alias_z / 2) (module docstring)."""
    from scipy.special import ndtr

    return float(ndtr(-0.5 * alias_z))


def canonical_term(spec: str) -> tuple[str, str]:
    """``"thetaddot:y^2*theta"`` -> (equation, canonical library name), e.g. ``("thetaddot", "y^2*theta")``.

    Any factor order is accepted (``theta*y^2``); raises ValueError for an unknown equation or term."""
    eq, sep, name = str(spec).partition(":")
    if not sep or eq not in EQUATION_NAMES:
        raise ValueError(f"term {spec!r}: expected EQUATION:TERM with EQUATION one of {', '.join(EQUATION_NAMES)}")
    e = tuple(parse_term(name.strip()))
    for t, ex in zip(TERMS, EXPONENTS):
        if tuple(ex) == e:
            return eq, t
    raise ValueError(f"term {name!r} is not in the cubic library")


def estimate_tracking_noise(runs: Sequence["Run"]) -> NoiseLevels:
    """White tracking noise of y and theta from the data, pooled over the runs (:func:`cubedimer.noise.white_noise_std`:
    the robust scale of the fourth differences).

    Parameters
    ----------
    runs : the raw runs (gap-filled y [m], theta [-] at every frame)

    Returns
    -------
    NoiseLevels
    """
    return NoiseLevels(*(white_noise_std([getattr(r, name) for r in runs]) for name in ("y", "theta")))


def runs_from_data(derivs: Sequence["Derivatives"], bound_factor: float = 5.0) -> list[OracleRun]:
    """The oracle runs of a data set: each run's smoothed state at its first interior frame, its
    interior length (the Savitzky-Golay edge frames left out, as in the long-time refinement) and a
    blow-up bound of ``bound_factor`` times the run's max |state| per component."""
    out = []
    for d in derivs:
        sl = slice(int(d.trim), len(d.t) - int(d.trim))
        st = d.state[sl]
        dt = float((d.t[-1] - d.t[0]) / (d.t.size - 1))
        out.append(OracleRun(st[0], st.shape[0], dt, bound_factor * np.max(np.abs(st), axis=0)))
    return out


def oracle_trajectories(model: PolynomialModel, runs: Sequence[OracleRun],
                        h_omega: float = 0.01) -> list[NDArray[np.float64]]:
    """The model's noise-free trajectories (n_valid, 4) from each run's initial state (RK4, at least 8
    steps per frame and ``h * omega <= h_omega``; rows after a blow-up are cut off)."""
    if not runs:
        return []
    x0s = np.array([r.x0 for r in runs])
    dts = np.array([r.dt for r in runs])
    ns = np.array([r.n_frames for r in runs], dtype=np.int64)
    bounds = np.array([r.bound if r.bound is not None else np.full(4, np.inf) for r in runs])
    substeps = max(8, max(model.default_substeps(float(dt), h_omega) for dt in np.unique(dts)))
    traj, nv = integrate_batch(model.coef, EXPONENTS, x0s, dts, ns, substeps, bounds)
    return [traj[i, :int(nv[i])] for i in range(len(runs))]


def _support(model: PolynomialModel, equation: str) -> list[int]:
    return [int(j) for j in np.flatnonzero(model.coef[EQUATION_NAMES.index(equation)])]


def integral_design(columns: NDArray, coordinate: NDArray, dt: float, periods: float = 0.75
                    ) -> tuple[NDArray[np.float64], int] | None:
    """The integral-form design of any columns along one run's noise-free trajectory, and its window [frames].

    Parameters
    ----------
    columns : array (n, P)
        The columns (accelerations per unit parameter, SI) at the run's n frames: library monomials, or any
        other linear regressors of an equation (a candidate effect's, a model's own terms).
    coordinate : array (n,)
        The coordinate the equation is the second derivative of (y [m] or theta [-]); its dominant frequency sets
        the window (:func:`fitting.derivatives.integral_form.integral_window`).
    dt : float
        Frame interval [s].
    periods : float
        Window length in periods of that frequency.

    Returns
    -------
    (X, window) with X (rows, P) the detrended double integrals per window [s^2 x column units], or None when the
    run is too short for one window.  ``X.T @ X`` is the run's unit-noise information matrix.
    """
    columns = np.asarray(columns, float)
    if columns.shape[0] < 16:
        return None
    w = integral_window(dt, dominant_frequency(np.asarray(coordinate, float), dt), periods)
    starts = window_starts(columns.shape[0], w)
    if starts.size == 0:
        return None
    return integral_columns(columns, dt, starts, w), w


def _run_design(run: OracleRun, trajectory: NDArray, equation: str, periods: float,
                cols: Sequence[int] | None = None) -> tuple[NDArray[np.float64], int] | None:
    """The integral-form design of one run's noise-free trajectory for ``equation`` (library columns ``cols``, all
    by default) and its window [frames]; None when the trajectory is too short for one window."""
    if trajectory.shape[0] < 16:
        return None
    lib = evaluate_library(trajectory)
    return integral_design(lib if cols is None else lib[:, list(cols)], trajectory[:, _COORD[equation]], run.dt,
                           periods)


def oracle_information(model: PolynomialModel, runs: Sequence[OracleRun], periods: float = 0.75,
                       trajectories: Sequence[NDArray] | None = None) -> dict[str, dict]:
    """Per run and equation, the unit-noise information matrix ``X_r^T X_r`` of the integral form.

    Parameters
    ----------
    model : PolynomialModel
        Its non-zero terms per equation are the support.
    runs : sequence of OracleRun
    periods : float
        Window in periods of the coordinate's dominant frequency (:func:`fitting.derivatives.integral_form.integral_window`).
    trajectories : optional
        Precomputed :func:`oracle_trajectories`.

    Returns
    -------
    ``{equation: {"terms": [names], "information": ndarray (R, P, P), "window_s": ndarray (R,), "used": bool (R,)}}``
    with zero matrices for runs too short (after a blow-up) for one window.  Units: the square of the
    columns' double integral [s^4 x monomial units^2].
    """
    traj = list(trajectories) if trajectories is not None else oracle_trajectories(model, runs)
    out = {}
    for eq in EQUATION_NAMES:
        cols = _support(model, eq)
        p = len(cols)
        info = np.zeros((len(runs), p, p))
        win = np.full(len(runs), np.nan)
        used = np.zeros(len(runs), bool)
        for i, (r, s) in enumerate(zip(runs, traj)):
            design = _run_design(r, s, eq, periods, cols) if p else None
            if design is None:
                continue
            X, w = design
            info[i] = X.T @ X
            win[i] = w * r.dt
            used[i] = True
        out[eq] = {"terms": [TERMS[j] for j in cols], "information": info, "window_s": win, "used": used}
    return out


def oracle_aliases(model: PolynomialModel, runs: Sequence[OracleRun], noise: NoiseLevels, periods: float = 0.75,
                   trajectories: Sequence[NDArray] | None = None) -> dict[str, dict[str, tuple[str | None, float]]]:
    """Each support term's closest one-for-one alias in the library and its alias z (module docstring).

    The columns of the whole library are evaluated at the model's noise-free trajectories, with the
    windows of :func:`oracle_information`; the runs' stacked designs are reduced to one R factor per
    equation (35 x 35, columns scaled to unit norm), on which every swap is an exact small least squares.

    Parameters
    ----------
    model, runs, noise, periods, trajectories : as :func:`oracle_standard_errors`

    Returns
    -------
    ``{equation: {term: (alias term or None, alias z)}}`` for every term of the model's support.
    """
    traj = list(trajectories) if trajectories is not None else oracle_trajectories(model, runs)
    n_lib = len(TERMS)
    out: dict[str, dict[str, tuple[str | None, float]]] = {}
    for q, eq in enumerate(EQUATION_NAMES):
        cols = _support(model, eq)
        out[eq] = {}
        if not cols:
            continue
        R = np.zeros((0, n_lib))
        for r, s in zip(runs, traj):
            design = _run_design(r, s, eq, periods)
            if design is not None:
                R = np.linalg.qr(np.vstack([R, design[0]]), mode="r")
        if R.shape[0] == 0:
            out[eq] = {TERMS[i]: (None, float("nan")) for i in cols}
            continue
        scale = np.linalg.norm(R, axis=0)
        empty = scale == 0.0  # a column that vanishes on these trajectories cannot stand in for anything
        scale[empty] = 1.0
        Rs = R / scale
        signal = Rs[:, cols] @ (model.coef[q, cols] * scale[cols])
        sigma = noise.of(eq)
        for i in cols:
            rest = [k for k in cols if k != i]
            best: tuple[str | None, float] = (None, float("inf"))
            for j in range(n_lib):
                if j in cols or empty[j]:
                    continue
                A = Rs[:, rest + [j]]
                beta = np.linalg.lstsq(A, signal, rcond=None)[0]
                z = float(np.linalg.norm(signal - A @ beta)) / sigma
                if z < best[1]:
                    best = (TERMS[j], z)
            out[eq][TERMS[i]] = best if best[0] is not None else (None, float("nan"))
    return out


def schur_complement(information: NDArray, keep: Sequence[int], rest: Sequence[int]) -> NDArray[np.float64]:
    """The information on the parameters ``keep`` with the parameters ``rest`` fitted beside them (projected out):
    the Schur complement ``G_kk - G_kr G_rr^+ G_rk`` of an information (Gram) matrix, computed with the matrix scaled
    to unit diagonal (SI columns span many decades).

    Parameters
    ----------
    information : array (P, P)
        ``X^T X`` (or a Gauss-Newton ``J^T J``).
    keep : indices of the parameters kept
    rest : indices of the parameters fitted beside them (none: ``G_kk`` itself)

    Returns
    -------
    array (len(keep), len(keep)) in the units of ``information``.
    """
    g = np.asarray(information, float)
    d = np.sqrt(np.clip(np.diag(g), 1e-300, None))
    gs = g / np.outer(d, d)
    k, r = list(keep), list(rest)
    m = gs[np.ix_(k, k)]
    if r:
        m = m - gs[np.ix_(k, r)] @ np.linalg.pinv(gs[np.ix_(r, r)], rcond=1e-13) @ gs[np.ix_(r, k)]
    return m * np.outer(d[k], d[k])


def replacement_rss(information: NDArray, signal: Sequence[int], coefficients: NDArray,
                    basis: Sequence[int]) -> float:
    """The noise-free residual sum of squares left when a contribution is replaced by other columns, from the
    information (Gram) matrix alone.

    With ``information = X^T X`` of stacked columns X (any columns: the library's, or a candidate effect's), the
    contribution ``X[:, signal] @ coefficients`` projected on the span of ``X[:, basis]`` leaves
    ``c^T (G_ss - G_sb G_bb^+ G_bs) c`` (:func:`schur_complement`).  Divided by
    the noise variance it is the square of the alias z (module docstring): the alias z of a whole set of columns
    against another set, with the remaining terms refitted.  Gram matrices of runs add, so the alias z of any
    selection of runs follows from their summed matrices.

    Parameters
    ----------
    information : array (P, P)
        ``X^T X`` [column units^2].
    signal : indices of the replaced columns
    coefficients : array (len(signal),)
        Their true coefficients (SI).
    basis : indices of the columns that stand in (may include none of ``signal``; including all of them gives 0)

    Returns
    -------
    float
        The residual sum of squares [target units^2], >= 0.
    """
    c = np.asarray(coefficients, float)
    return max(float(c @ schur_complement(information, signal, basis) @ c), 0.0)


def covariance_diagonal(info: NDArray) -> NDArray[np.float64]:
    """diag(info^-1) with column scaling (the SI columns span many decades)."""
    d = np.sqrt(np.clip(np.diag(info), 1e-300, None))
    return np.clip(np.diag(np.linalg.pinv(info / np.outer(d, d))), 0.0, None) / d**2


def oracle_standard_errors(model: PolynomialModel, runs: Sequence[OracleRun], noise: NoiseLevels,
                           periods: float = 0.75, information: Mapping[str, dict] | None = None) -> OracleResult:
    """Oracle standard errors and z of every term of ``model`` on ``runs`` (module docstring).

    Parameters
    ----------
    model : PolynomialModel
    runs : sequence of OracleRun
        The data set's runs (initial states, lengths, frame intervals).
    noise : NoiseLevels
        White tracking noise of y [m] and theta [-].
    periods : float
        Window length in periods of each coordinate's dominant frequency.
    information : optional
        Precomputed :func:`oracle_information` of the same model and runs (then the aliases are not
        computed: ``alias`` None, ``alias_z`` NaN).

    Returns
    -------
    OracleResult
    """
    traj = None
    if information is None:
        traj = oracle_trajectories(model, runs)
        information = oracle_information(model, runs, periods, traj)
    aliases = oracle_aliases(model, runs, noise, periods, traj) if traj is not None else {}
    n_blown = 0 if traj is None else sum(int(s.shape[0] < r.n_frames) for s, r in zip(traj, runs))
    terms, window_s, n_used = {}, {}, 0
    for q, eq in enumerate(EQUATION_NAMES):
        d = information[eq]
        names = d["terms"]
        coef = model.coef[q, [TERMS.index(t) for t in names]]
        if names and d["used"].any():
            se = noise.of(eq) * np.sqrt(covariance_diagonal(d["information"].sum(axis=0)))
        else:
            se = np.full(len(names), np.inf)
        al = aliases.get(eq, {})
        terms[eq] = {t: OracleTerm(float(c), float(e), *al.get(t, (None, float("nan"))))
                     for t, c, e in zip(names, coef, se)}
        window_s[eq] = float(np.nanmedian(d["window_s"])) if d["used"].any() else float("nan")
        n_used = max(n_used, int(d["used"].sum()))
    return OracleResult(terms, noise, n_used, n_blown, window_s)
