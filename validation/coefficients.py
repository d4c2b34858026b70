"""Fitted model coefficients against the static coefficients of the simulated sweep.

Every velocity-free library term (monomials of y and theta) has a static prediction: the least-
squares coefficient of the swept accelerations (:func:`acousim.statics.sweep.fit_static_coefficients`).
Velocity terms have none ("dynamic only").

The y origin.  The simulation measures y from Z_eq, where gravity and the acoustic force on the
straight dimer balance.  Data measure y from a levitation plane chosen by the experimenter (e.g.
the mean position).  If the data's origin lies ``delta`` above Z_eq, i.e. ``y_sim = y_data + delta``,
a term ``c y_sim^a theta^b`` contributes ``c C(a, j) delta^(a-j)`` to the coefficient of
``y_data^j theta^b`` for every j < a: shifting the origin moves the lower-order coefficients (to first
order, ``d c[y^j theta^b] / d delta = (j + 1) c[y^(j+1) theta^b]``), and leaves the highest-order ones
unchanged.  :func:`compare_coefficients` re-expresses the simulated coefficients at the data's
origin, taking ``delta`` from the fitted model's own equilibrium by default (the root of the fitted
yddot at theta = 0 and zero velocity, which sits at y_data = -delta).

Two fitted estimates.  The ensemble statistics of the runs' refined models (mean and spread across
runs) and, when model.json carries it (key ``integral_form``, written by ``fitting fit``), the pooled
integral-form estimate with its standard error (:mod:`fitting.derivatives.integral_form`: coefficients shared by
all runs, fitted in position space where the tracking noise is white).  A term in the integral form's
selected support is judged on that estimate (combined uncertainty sqrt(SE^2 + static std^2)); the
others on the ensemble statistics.  The per-run fits are at an information limit for weak hinge terms
(theta*y^2 on a soft Gor'kov hinge scatters by ~4e9 across runs against a static ~1.4e8), which the
pooled estimate is not.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass
from math import comb

import numpy as np

from cubedimer.terms import is_velocity_free, library_terms, parse_term, term_name

__all__ = [
    "static_comparison",
    "STATIC_GRID_POINTS",
    "TermComparison",
    "CoefficientComparison",
    "shift_origin",
    "origin_sensitivity",
    "fitted_equilibrium_offset",
    "ensemble_statistics",
    "compare_coefficients",
    "LEAD_TERM",
]

#: The coupling the source paper is about: thetaddot ~ theta * y^2.
LEAD_TERM = ("thetaddot", "y^2*theta")


def shift_origin(coefficients: dict[str, float], delta: float) -> dict[str, float]:
    """Re-express a polynomial in y (and other variables) after ``y_old = y_new + delta``.

    Parameters
    ----------
    coefficients : dict term -> value
        Coefficients in the old variable (SI).
    delta : float
        Offset [m] of the new origin above the old one.

    Returns
    -------
    dict term -> value in the new variable (same terms, plus any lower-order ones created).
    """
    out: dict[str, float] = {}
    for name, c in coefficients.items():
        e = parse_term(name)
        a = int(e[0])
        for j in range(a + 1):
            ej = e.copy()
            ej[0] = j
            key = term_name(ej)
            out[key] = out.get(key, 0.0) + c * comb(a, j) * delta ** (a - j)
    return out


def origin_sensitivity(coefficients: dict[str, float]) -> dict[str, float]:
    """First-order change of each coefficient per metre of origin shift: (j+1) c[y^(j+1) ...] [SI/m]."""
    out = {}
    for name in coefficients:
        e = parse_term(name)
        up = e.copy()
        up[0] += 1
        out[name] = (e[0] + 1) * coefficients.get(term_name(up), 0.0)
    return out


def fitted_equilibrium_offset(yddot: dict[str, float], search: float = 5e-4) -> float:
    """delta [m] such that the fitted yddot(y, theta=0, velocities=0) vanishes at y_data = -delta.

    Returns the root closest to 0 within +-``search``; 0 if the fitted yddot has no root there
    (then the origins are taken to coincide, which the comparison states).
    """
    poly = np.zeros(4)
    for name, c in yddot.items():
        e = parse_term(name)
        if e[1] == 0 and e[2] == 0 and e[3] == 0 and e[0] <= 3:
            poly[e[0]] += c
    roots = np.roots(poly[::-1][np.argmax(poly[::-1] != 0):]) if np.any(poly[1:] != 0) else np.array([])
    real = roots[np.abs(roots.imag) < 1e-12].real if roots.size else np.array([])
    real = real[np.abs(real) <= search]
    if real.size == 0:
        return 0.0
    return float(-real[np.argmin(np.abs(real))])


def ensemble_statistics(model: dict) -> dict[str, dict[str, dict[str, float]]]:
    """Mean, std and z-score across runs of each term's coefficient (zeros where a run omits a term).

    Uses ``model["per_run"]``; without per-run fits the minimal model's coefficient is the mean and
    the std is NaN.
    """
    per_run = model.get("per_run") or []
    stats: dict[str, dict[str, dict[str, float]]] = {}
    for eq in ("yddot", "thetaddot"):
        terms = set(model.get("equations", {}).get(eq, {}))
        for r in per_run:
            terms |= set(r.get("equations", {}).get(eq, {}))
        stats[eq] = {}
        for t in terms:
            vals = np.array([r.get("equations", {}).get(eq, {}).get(t, 0.0) for r in per_run], float)
            if vals.size >= 2:
                mean, std = float(vals.mean()), float(vals.std(ddof=1))
            else:
                mean, std = float(model["equations"][eq].get(t, 0.0)), float("nan")
            z = model.get("zscores", {}).get(eq, {}).get(t)
            if z is None:
                z = mean / std if std and np.isfinite(std) and std > 0 else float("nan")
            stats[eq][t] = {"mean": mean, "std": std, "z": float(z), "n_runs": int(vals.size),
                            "inclusion": float(np.mean(vals != 0)) if vals.size else float("nan")}
    return stats


@dataclass(frozen=True)
class TermComparison:
    """One term of one equation, fitted against simulated (SI units)."""

    equation: str
    term: str
    kind: str  # "static" or "dynamic only: no static prediction"
    in_minimal_model: bool
    fitted: float  # the minimal model's coefficient (0 if not selected)
    fitted_mean: float  # ensemble mean across runs
    fitted_std: float  # ensemble std across runs
    fitted_z: float
    simulated: float  # static coefficient at the data's origin (NaN for dynamic terms)
    simulated_std: float
    ratio: float  # fitted / simulated
    signs_agree: bool | None
    within_uncertainty: bool | None  # |fitted - simulated| <= n_sigma * sqrt(std_fit^2 + std_sim^2)
    origin_shift_per_um: float  # change of the simulated coefficient per micrometre of origin shift
    integral: float = float("nan")  # pooled integral-form estimate (NaN where that selection dropped the term)
    integral_std_error: float = float("nan")  # its standard error
    #: which estimate ``signs_agree``, ``within_uncertainty`` and ``ratio`` use: "integral form" (the term is in
    #: the integral form's selected support), "ensemble" (ensemble mean and across-run std) or "none" (no verdict)
    verdict_from: str = "ensemble"
    #: |estimate - simulated| in combined standard deviations (what ``within_uncertainty`` compares with n_sigma;
    #: NaN without a verdict)
    deviation_sigma: float = float("nan")


@dataclass(frozen=True)
class CoefficientComparison:
    rows: list[TermComparison]
    delta_m: float
    origin: str
    n_sigma: float
    static_box: dict

    def to_dict(self) -> dict:
        return {
            "origin": self.origin,
            "origin_offset_m": self.delta_m,
            "n_sigma": self.n_sigma,
            "static_fit_box": self.static_box,
            "lead_term": {"equation": LEAD_TERM[0], "term": LEAD_TERM[1]},
            "terms": [asdict(r) for r in self.rows],
            "units": "SI",
        }

    def table(self) -> str:
        """Markdown table, the theta*y^2 term first; the verdict columns use the estimate named in "verdict from"."""
        head = ("| equation | term | fitted (minimal) | ensemble mean +- std | z | integral form +- SE | simulated +- std | "
                f"verdict from | ratio | signs agree | within {self.n_sigma:g} sigma | d(sim)/d(origin) per um |")
        lines = [head, "|" + "---|" * 12]
        for r in self.rows:
            ig = "not selected" if not np.isfinite(r.integral) else f"{r.integral:.4g} +- {r.integral_std_error:.2g}"
            common = (f"| {r.equation} | {r.term} | {r.fitted:.4g} | {r.fitted_mean:.4g} +- {r.fitted_std:.2g} | "
                      f"{r.fitted_z:.3g} | {ig} | ")
            if r.kind != "static":
                lines.append(common + "dynamic only: no static prediction | | | | | |")
                continue
            yes = lambda b: "-" if b is None else ("yes" if b else "**no**")  # noqa: E731
            lines.append(
                common + f"{r.simulated:.4g} +- {r.simulated_std:.2g} | {r.verdict_from} | {r.ratio:.3g} | "
                f"{yes(r.signs_agree)} | {yes(r.within_uncertainty)} | {r.origin_shift_per_um:.3g} |"
            )
        return "\n".join(lines)


def compare_coefficients(
    model: dict,
    static_coefficients: dict[str, dict[str, float]],
    static_std: dict[str, dict[str, float]],
    origin_offset: float | str = "fitted-equilibrium",
    n_sigma: float = 2.0,
    static_box: dict | None = None,
    origin_source: str = "user-given",
) -> CoefficientComparison:
    """Compare a fitted model (model.json contents) with static coefficients of a sweep.

    Parameters
    ----------
    model : dict
        The fitted model per docs/formats.md (``equations``, ``zscores``, ``per_run``).
    static_coefficients, static_std : dict equation -> term -> value
        Static least-squares coefficients and their standard errors (SI, y from Z_eq).
    origin_offset : float or "fitted-equilibrium"
        delta [m] with ``y_sim = y_data + delta``; by default from the fitted yddot's root.
    origin_source : str
        Where a numeric ``origin_offset`` comes from, for the stated origin (``"user-given"`` on the command line,
        ``"calibrated"`` when the diagnosis's calibration gives it).
    n_sigma : float
        Agreement criterion: |fitted - simulated| <= n_sigma x combined std.  For a term in the
        selected support of the pooled integral form (``model["integral_form"]``), fitted is that
        estimate and the combined std sqrt(SE^2 + std_static^2); otherwise fitted is the ensemble
        mean and the combined std sqrt(std_across_runs^2 + std_static^2) (the across-run spread, not
        the standard error of the mean: a conservative choice, since runs differ physically as well
        as by noise).  ``TermComparison.verdict_from`` names the estimate used.
    """
    if origin_offset == "fitted-equilibrium":
        delta = fitted_equilibrium_offset(model["equations"].get("yddot", {}))
        origin = (f"data origin placed at the fitted model's equilibrium: y_sim = y_data + delta, delta = {delta * 1e6:.2f} um "
                  "(simulated coefficients re-expanded about it)")
    else:
        delta = float(origin_offset)
        origin = f"{origin_source} origin offset: y_sim = y_data + delta, delta = {delta * 1e6:.2f} um"
    stats = ensemble_statistics(model)
    integral = model.get("integral_form") or {}
    per_run_given = len(model.get("per_run") or []) >= 2
    rows: list[TermComparison] = []
    all_terms = library_terms()
    for eq in ("yddot", "thetaddot"):
        sim = shift_origin(static_coefficients[eq], delta)
        sens = origin_sensitivity(static_coefficients[eq])
        # standard errors move with the origin too: variances add with squared binomial weights
        # (covariances between the static coefficients neglected)
        var = {}
        for name, sd in static_std[eq].items():
            e = parse_term(name)
            for j in range(int(e[0]) + 1):
                ej = e.copy()
                ej[0] = j
                key = term_name(ej)
                var[key] = var.get(key, 0.0) + (sd * comb(int(e[0]), j) * delta ** (int(e[0]) - j)) ** 2
        sim_std = {t: float(np.sqrt(v)) for t, v in var.items()}
        fitted_terms = set(model["equations"].get(eq, {})) | set(stats[eq])
        ig_terms = (integral.get(eq) or {}).get("terms", {})
        for t in all_terms:
            static = is_velocity_free(t)
            if not static and t not in fitted_terms:
                continue
            if static and t not in sim:
                continue
            # a term no run selected: every run's coefficient is 0
            st = stats[eq].get(t, {"mean": 0.0, "std": 0.0 if per_run_given else float("nan"), "z": float("nan")})
            fitted = float(model["equations"].get(eq, {}).get(t, 0.0))
            ig = ig_terms.get(t) or {}
            ig_val, ig_se = float(ig.get("value", np.nan)), float(ig.get("std_error", np.nan))
            if static:
                s, s_std = float(sim[t]), float(sim_std.get(t, 0.0))
                if np.isfinite(ig_val) and np.isfinite(ig_se) and ig_se > 0:
                    basis, est, est_std = "integral form", ig_val, ig_se
                else:
                    basis = "ensemble"
                    est = st["mean"] if np.isfinite(st["std"]) else fitted
                    est_std = st["std"] if np.isfinite(st["std"]) else 0.0
                comb_std = np.sqrt(est_std**2 + s_std**2)
                ratio = est / s if s != 0 else float("nan")
                signs = None if (s == 0 or est == 0) else bool(np.sign(est) == np.sign(s))
                within = bool(abs(est - s) <= n_sigma * comb_std) if comb_std > 0 else None
                dev = float(abs(est - s) / comb_std) if comb_std > 0 else float("nan")
                rows.append(TermComparison(eq, t, "static", t in model["equations"].get(eq, {}), fitted, st["mean"], st["std"],
                                           st["z"], s, s_std, ratio, signs, within, sens.get(t, 0.0) * 1e-6,
                                           ig_val, ig_se, basis, dev))
            else:
                rows.append(TermComparison(eq, t, "dynamic only: no static prediction", t in model["equations"].get(eq, {}),
                                           fitted, st["mean"], st["std"], st["z"], float("nan"), float("nan"), float("nan"),
                                           None, None, float("nan"), ig_val, ig_se, "none"))

    def order(r: TermComparison):
        lead = (r.equation, r.term) == LEAD_TERM
        return (not lead, r.kind != "static", not r.in_minimal_model, r.equation != "thetaddot", all_terms.index(r.term))

    rows.sort(key=order)
    return CoefficientComparison(rows, delta, origin, n_sigma, static_box or {})


#: Grid points per axis of the sweep a static comparison fits (over the box, endpoints included).
STATIC_GRID_POINTS = 41


def static_comparison(model: dict, simulation, theta_max: float, y_max: float,
                      origin_offset: float | str = "fitted-equilibrium", n_sigma: float = 2.0,
                      origin_source: str = "user-given"):
    """The static coefficients of a simulation over a box and their comparison with a fitted model: what
    ``python -m validation compare`` and the report's section 5 both do.

    Parameters
    ----------
    model : dict
        The fitted model (model.json's content).
    simulation : StaticModel or acousim.statics.sweep.SweepResult
        A simulation, swept on a :data:`STATIC_GRID_POINTS`-square grid over the box, or a sweep already made
        (``compare --sweep``), fitted over the part of it inside the box.
    theta_max, y_max : float
        The box of the static fit: |theta| <= theta_max [-], |y| <= y_max [m] (y from the simulation's Z_eq).  The
        compare command takes model.json's ``data_range`` (theta at most 0.9) unless told otherwise; the report takes
        the 98 % quantiles of the fitted runs' |theta| (at most 0.9) and |y| measured from the calibrated Z_eq.
    origin_offset, n_sigma, origin_source
        As :func:`compare_coefficients`.

    Returns
    -------
    (acousim.statics.sweep.StaticCoefficients, CoefficientComparison)
    """
    from acousim.statics.sweep import SweepResult, fit_static_coefficients, static_sweep

    sweep = simulation if isinstance(simulation, SweepResult) else static_sweep(
        simulation, np.linspace(-theta_max, theta_max, STATIC_GRID_POINTS), np.linspace(-y_max, y_max, STATIC_GRID_POINTS))
    static = fit_static_coefficients(sweep, theta_max=theta_max, y_max=y_max)
    return static, compare_coefficients(model, static.coefficients, static.std_errors, origin_offset=origin_offset,
                                        n_sigma=n_sigma, static_box=static.box, origin_source=origin_source)
