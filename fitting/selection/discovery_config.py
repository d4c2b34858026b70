"""The settings of the discovery's selection, :class:`DiscoveryConfig`, and the names its results carry.

The method itself, and why each setting has its value, is :mod:`fitting.selection.integral_discovery` and
docs/fitting.md.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from cubedimer.config_checks import check_bounds, check_fraction, check_non_negative, check_positive, check_that, check_whole
from ..refinement.model_states import SegmentConfig
from ..refinement.output_error import OutputErrorConfig

__all__ = ["DiscoveryConfig", "METHOD", "KNEE_TOLERANCE", "MODEL_ERROR_MODE", "FEW_RUNS_MODE"]

#: ``DiscoveryResult.selection_modes`` of an equation selected by held-out prediction (model error)
MODEL_ERROR_MODE = "held-out (model error)"

#: ``DiscoveryResult.selection_modes`` of an equation under model error whose held-out selection was overruled because
#: the few runs disagreed (``DiscoveryConfig.few_runs``): the significance rule's support is kept
FEW_RUNS_MODE = "significance (model error, runs disagree)"

#: Held-out tolerance of the Pareto knee that model.json and the report name (``DiscoveryResult.knee``; the same
#: number as ``fit --heldout-tolerance 0.002``): on the paper-like twin it gives the Gor'kov-form model.
KNEE_TOLERANCE = 0.002

#: One-line description of the method (written next to the result).
METHOD = ("pooled integral form (windows of 0.75 of the coordinate's dominant period, within 0.55-11 periods of the first coordinate, in the model passes "
          "at most 0.875 periods of the equation's natural frequency; Numerov-corrected double integrals); per "
          "equation backward elimination from the 35-term library until Holm's rule at family-wise alpha declares "
          "every remaining term significant, stepwise additions, swaps and two-for-one merges that keep every term "
          "significant, then the support with the smallest held-out error (K-fold over runs) on the continued "
          "elimination path; damping terms always kept; repeated with the columns at the raw positions and the "
          "velocities of the selected model's trajectories fitted segment by segment to the data until the support "
          "and coefficients converge; under model error, the coefficients refined by the output error over segments "
          "of 5 slow periods")


@dataclass(frozen=True)
class DiscoveryConfig:
    """Settings of :func:`discover_model`.

    Parameters
    ----------
    alpha : float
        Family-wise significance level of Holm's rule (per equation).
    window_periods : float
        Integral-form window in periods of the coordinate's dominant frequency
        (:func:`fitting.derivatives.integral_form.integral_window`).
    window_bounds_periods : (float, float)
        Its minimum and maximum in periods of the run's first coordinate (y) at its dominant frequency, so that the
        windows are the same whatever unit of time the data are written in.  The raw positions' noise in the
        columns, double integrated over a window W, grows like (omega W)^2 times the coordinate's stiffness, while
        shorter windows lose information.  Measured on a 35-Hz hinge beside a 22-Hz y (1500 fps, 12 runs): with
        a minimum of 1.05 hinge periods its damping came out 4 oracle standard errors off; at 0.75 hinge periods
        (21 ms) the standard errors of the hinge terms were 1.3-1.7 times the oracle's; at 0.55 y periods (25 ms,
        0.875 hinge periods) every coefficient was within 2.4 oracle standard errors on 5 data sets.  The maximum,
        11 y periods (0.5 s at 22 Hz), bounds the windows of a hinge much slower than y.
    segments : SegmentConfig
        The model-based state estimate.
    max_iterations : int
        Passes with model-based states after the first pass.
    tolerance : float
        Convergence of an equation selected by significance: every coefficient changed by less than ``tolerance``
        standard errors (and the support unchanged).
    heldout_convergence : float
        Convergence of an equation under model error, where standard errors mean nothing: the support unchanged and
        the held-out RMS error of its selection (K-fold over runs) changed by less than this fraction.  0.005: a
        sixth of ``model_error_tolerance``'s 3 % (what the held-out rule itself counts as the same error).
    velocity_first : bool
        Drop velocity terms first while one is below the Bonferroni level.
    keep_damping : bool
        Always keep ydot in yddot and thetadot in thetaddot.
    selection_passes : int
        Passes that may change the support; after them (or when the support returns to an earlier one) it is
        frozen and only the coefficients and states iterate.
    heldout_prune : bool
        After Holm's rule, continue the elimination and keep the support with the smallest held-out error.
    heldout_tolerance : float
        Keep the smallest support whose held-out RMS error is at most ``1 + heldout_tolerance`` times the smallest
        on that path (0: the minimum itself); under model error it widens the held-out rule and is the output
        error's ``misfit_tolerance`` (docs/fitting.md, "The practical threshold under model error").
    n_folds : int
        Folds over runs of the held-out error (at most the number of runs).
    raw_positions : bool
        Model-state passes evaluate the columns at the raw positions and the model's velocities (True) or at
        the model's positions and velocities (False; measured to drift: module docstring).
    stepwise : bool
        Stepwise additions, swaps and merges after the backward elimination.
    velocity_price : float or None
        Residual variances by which a velocity term must lower the residual sum of squares to replace a
        velocity-free term in a swap (None: z_alpha^2 at ``alpha``).
    natural_periods : float or None
        From the second pass on, an equation's windows are at most this many periods of its natural frequency
        (``sqrt(-stiffness) / 2 pi``: the y coefficient of yddot, the theta coefficient of thetaddot, of the first
        pass), also below the lower bound of ``window_bounds_s``; None: the dominant frequency alone.  The raw
        positions' white noise averages out in the double integral only over windows below about one period of the
        equation's stiffness.  A strongly damped hinge near f_theta = 2 f_y, driven by y, moves at f_y: 0.75 of its
        dominant period is 1.5 natural periods, and even the 0.55-y-period floor is 1.07 periods of a 43-Hz hinge.  There
        the theta residual came out 3.6 % above the tracking noise and up to 5 spurious thetaddot terms per data set
        were selected at z 3.8-5.8 (a constant, theta^3, y^2, y*thetadot, ...).  0.875 is the floor's own share of
        the 35-Hz hinge it was chosen on (docs/fitting.md, "Near parametric resonance").
    model_error_factor : float or None
        When an equation's residual standard deviation (at the significance rule's support) exceeds this many times
        the white tracking noise of its coordinate (:func:`cubedimer.noise.white_noise_std`), the residual is model
        error (a truth that is not sparse in the library), under which the standard errors and Holm's rule have no
        meaning: that equation is selected by held-out prediction over runs instead
        (:func:`fitting.selection.support_search.select_heldout`: the smallest support on the elimination path from the full
        library whose held-out error is the smallest one's within ``model_error_se`` paired standard errors or
        ``model_error_tolerance``).  None: never.
        1.05: on sparse truths the ratio is at most 1.0005 (37 data sets of ten truths, fresh seeds), while a
        levitated dimer's full-wave twin with air damping reaches 1.06-1.13 in y (docs/fitting.md, "Model error").
    model_error_se : float
        The standard errors of that rule (1: the one-standard-error rule).
    model_error_tolerance : float
        The relative excess of held-out error, as a share of its model-error part, that counts as the same held-out
        error however small its standard error (the one-standard-error rule alone keeps spare terms that generalise
        by a fraction of a per cent).  0.03: docs/fitting.md, "Model error".
    model_error_inflation : float or None
        The second sign of model error, one that the library's spare terms cannot hide: the held-out misfit
        (K-fold over runs) at the significance rule's support exceeds the in-sample residual by more than white noise
        explains.  The statistic (:func:`fitting.selection.support_search.heldout_inflation`) is
        ``(heldout^2 / residual^2 - 1) * dof / terms``, of order 1 under white noise.  Above this value the equation
        is selected by held-out prediction, as above.  None: never.  20: -0.55 to 7.0 on sparse truths, 11-1,120 on
        non-sparse ones whose residual stayed within 1.05 of the noise (docs/fitting.md, "Why 20").
    output_error : OutputErrorConfig or None
        Under model error in either equation, the coefficients are refined by the output error over segments of
        several periods and the support pruned and grown by it (:func:`fitting.refinement.output_error.refine_output_error`).
    few_runs, few_runs_excess : int, float or None
        Under model error with fewer than ``few_runs`` runs, a held-out selection that drops terms of the significance
        rule's support while some held-out run's misfit (integral form, K-fold over runs) rises by more than
        ``few_runs_excess`` (relative) without them is overruled and the significance support kept; with more runs
        it is logged.  With 4 runs the one-standard-error rule rests on 4 per-run differences that disagree (one run
        100-280 % worse, the others 60-90 % better): at 12 % truncation it dropped 2-4 Taylor terms of an equation on 3
        of 6 data sets (docs/fitting.md, "Few runs").  6: a standard error of 5 values or fewer;  0.1: above the 3-7 %
        excess of the held-out selections that kept every Taylor term.  None: never.
    estimate_choice : bool or None
        Under model error, the coefficients of the output error's support are the least squares of short-window
        accelerations (the weighting a prediction from a run's largest amplitude needs) unless the integral form or the
        output error predicts the runs better from their first states (a lower median over the held-out runs, K-fold
        over runs) (:mod:`fitting.selection.estimate_choice`).  None (default): only with a cap
        (``max_terms``), where a support of at most the cap's size carries the model error in few coefficients; the
        selection's own larger supports, whose added odd terms carry the truth's fifth order, are predicted better by
        the output error's coefficients (docs/fitting.md, "The estimate that predicts from the first state").  False:
        the output error's; True: always.
    acceleration_window_periods : float
        The Savitzky-Golay window of that least squares of accelerations, in periods of each run's faster dominant
        frequency (0.25: the window of the pysindy baselines in ``benchmarks/bench_model_error.py``).
    max_terms : int or None
        At most this many terms per equation (``fit --max-terms``): below the selection's size the front's point at
        that cap (ordered by the held-out long-time error, :meth:`fitting.selection.front.Front.supports_at`; without
        a front each equation whose selection is larger takes the largest support on its elimination path within the
        cap, :func:`fitting.selection.front.capped_support`), refitted on all runs.  None: the selection itself.
    """

    alpha: float = 0.01
    window_periods: float = 0.75
    window_bounds_periods: tuple[float, float] = (0.55, 11.0)
    segments: SegmentConfig = field(default_factory=SegmentConfig)
    max_iterations: int = 6
    tolerance: float = 0.5
    heldout_convergence: float = 0.005
    velocity_first: bool = True
    keep_damping: bool = True
    selection_passes: int = 3
    heldout_prune: bool = True
    heldout_tolerance: float = 0.0
    n_folds: int = 5
    raw_positions: bool = True
    stepwise: bool = True
    velocity_price: float | None = None
    natural_periods: float | None = 0.875
    model_error_factor: float | None = 1.05
    model_error_se: float = 1.0
    model_error_tolerance: float = 0.03
    model_error_inflation: float | None = 20.0
    output_error: OutputErrorConfig | None = field(default_factory=OutputErrorConfig)
    few_runs: int = 6
    few_runs_excess: float | None = 0.1
    estimate_choice: bool | None = None
    acceleration_window_periods: float = 0.25
    max_terms: int | None = None

    def __post_init__(self) -> None:
        check_fraction(self, "alpha")
        check_positive(self, "window_periods")
        check_bounds(self, "window_bounds_periods")
        check_whole(self, "max_iterations", minimum=0)
        check_whole(self, "n_folds", minimum=2)
        check_whole(self, "selection_passes")
        check_positive(self, "tolerance")
        check_positive(self, "acceleration_window_periods")
        check_positive(self, "heldout_convergence")
        check_whole(self, "few_runs", minimum=2)
        check_positive(self, "few_runs_excess", optional=True)
        check_fraction(self, "heldout_tolerance", zero=True)
        check_positive(self, "natural_periods", optional=True)
        check_positive(self, "model_error_inflation", optional=True)
        check_that(self, self.model_error_factor is None or self.model_error_factor > 1,
                   f"model_error_factor must exceed 1 (or be None), got {self.model_error_factor!r}")
        check_non_negative(self, "model_error_se")
        check_fraction(self, "model_error_tolerance", zero=True)
        check_that(self, self.max_terms is None or (isinstance(self.max_terms, int) and self.max_terms >= 1),
                   f"max_terms must be a whole number >= 1 (or None), got {self.max_terms!r}")
