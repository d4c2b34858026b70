"""The long-time loss: attractor shape, Poincare convergence and oscillation frequency.

All three terms compare a simulated trajectory with one run's smoothed data, in coordinates
normalised per component by the data's max|x_i| (``x_hat = x / max|x|``), and each is divided by
its value for the *rest model* (the trajectory that sits at the origin, i.e. the model "as bad as
the zero model"), so that 0 is perfect and ~1 is as bad as predicting no motion at all.

Definitions (D = data points x_hat_j, j = 1..N; S = simulated points s_i, i = 1..M; both over the
same time span starting from the data's initial state):

* shape  L_S = [ 1/2 mean_i min_j |s_i - x_j|^2 + 1/2 mean_j min_i |x_j - s_i|^2 ] / mean_j |x_j|^2.
  The first half is the paper's "distance from each simulated point to the nearest data point";
  the second half (symmetrisation) penalises a simulation that covers only part of the
  attractor (e.g. collapses to a fixed point inside it), which the first half alone rewards.
  Rest model: ~1/2 (exactly (min_j|x_j|^2 + mean_j|x_j|^2) / (2 mean_j|x_j|^2)).
* Poincare  L_P = mean_k d_k / mean_k (|p_k|^2 + 1) over the data's K crossings of y = 0 with
  ydot < 0, where p_k = (ydot, theta, thetadot)_hat at the data's k-th crossing (time t_k) and
  d_k = |q_k - p_k|^2 + min(((s_k - t_k) / T)^2, 1) with q_k, s_k the simulation's k-th
  crossing and T = 1 / f_y of the data, or d_k = |p_k|^2 + 1 if the simulation has fewer
  than k crossings.  Crossing by crossing, so a phase drift between y and theta or a wrong decay
  rate is penalised even when the attractor's shape is right.  ydot is included because on
  y = 0 the section of the 4-D flow is 3-D and ydot at the crossing measures the y amplitude.
  The crossing-time term is needed because the section points alone are invariant under a
  uniform rescaling of time (all frequencies and decay rates multiplied by the same factor
  leave the stroboscopic map and the normalised shape unchanged): without it a model 1 % too
  fast scored L_P ~ 5e-5 (measured).  Rest model: exactly 1.
* frequency  L_F = 1/2 [min(r_y^2, 1) + min(r_theta^2, 1)], r = (f_sim - f_data) / f_data of the
  dominant y and theta frequencies (Hann-windowed spectra, parabolic peak interpolation).
  Rest model: 1 (no peak, r = -1).

Total ``L = w_S L_S + w_P L_P + w_F L_F`` with default weights 1, 1, 1: after the
normalisation every term is O(1) for a useless model and 0 for a perfect one, so equal weights
give each feature the same say.  The frequency term is nearly redundant with the Poincare term
near the optimum but, unlike it, is smooth far from it (it does not depend on the phase), which
helps the optimiser out of basins where the simulated crossings are out of step.

Blow-up: integration stops when any normalised component exceeds ``bound`` (default 5, i.e.
five times the data's max|x|) or becomes non-finite; the loss is then
``penalty * (2 - n_valid / n)`` (default penalty 1e3), finite and decreasing the later the
blow-up happens, and every non-diverged loss is capped below ``penalty``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from cubedimer.config_checks import check_non_negative, check_positive, check_that
from cubedimer.poincare import poincare_section
from cubedimer.spectra import dominant_frequency

from .nearest import PointGrid

__all__ = ["LossWeights", "LossTerms", "Reference", "make_reference", "loss_terms", "attractor_shape_loss",
           "rest_model_terms"]


@dataclass(frozen=True)
class LossWeights:
    """Weights of the loss terms and the blow-up handling.

    Parameters
    ----------
    shape, poincare, frequency : float
        Weights of L_S, L_P, L_F.
    bound : float
        Blow-up bound in normalised coordinates (multiples of the data's max|x_i|).
    penalty : float
        Loss scale of a diverged simulation.
    """

    shape: float = 1.0
    poincare: float = 1.0
    frequency: float = 1.0
    bound: float = 5.0
    penalty: float = 1e3

    def __post_init__(self) -> None:
        for name in ("shape", "poincare", "frequency"):
            check_non_negative(self, name)
        check_that(self, self.shape + self.poincare + self.frequency > 0,
                   "at least one of shape, poincare, frequency must be positive")
        check_positive(self, "bound")
        check_positive(self, "penalty")


@dataclass(frozen=True)
class LossTerms:
    """Values of the loss terms of one simulation (dimensionless)."""

    shape: float
    poincare: float
    frequency: float
    total: float
    blown_up: bool = False

    def to_dict(self) -> dict:
        return {"shape": self.shape, "poincare": self.poincare, "frequency": self.frequency,
                "total": self.total, "blown_up": self.blown_up}


@dataclass(frozen=True, eq=False)
class Reference:
    """Precomputed features of one run's data (time and states in any consistent units).

    Attributes
    ----------
    t : ndarray (n,)
    state : ndarray (n, 4)
    norm : ndarray (4,)
        max|x_i| of the data.
    x0 : ndarray (4,)
        Initial state (first row of ``state``).
    points : PointGrid
        The normalised data points, prepared for exact nearest-point queries.
    s0 : float
        mean_j |x_hat_j|^2.
    section : ndarray (K, 3)
        Normalised Poincare points (ydot, theta, thetadot).
    section_times : ndarray (K,)
        Crossing times, relative to ``t[0]``, in units of the data's y period.
    p0 : float
        mean_k |p_k|^2 + 1.
    f_y, f_theta : float
        Dominant frequencies (1 / time unit).
    sub : int
        Stride of the data points used for the data-to-simulation half of L_S.
    """

    t: NDArray[np.float64]
    state: NDArray[np.float64]
    norm: NDArray[np.float64]
    points: PointGrid
    s0: float
    section: NDArray[np.float64]
    section_times: NDArray[np.float64]
    p0: float
    f_y: float
    f_theta: float
    sub: int = 3

    @property
    def x0(self) -> NDArray[np.float64]:
        return self.state[0]

    @property
    def dt(self) -> float:
        return float(self.t[1] - self.t[0])

    @property
    def n(self) -> int:
        return self.t.size


def make_reference(t: NDArray, state: NDArray, sub: int = 3) -> Reference:
    """Build the :class:`Reference` of a smoothed trajectory ``state`` (n, 4) at uniform ``t``."""
    t = np.asarray(t, float)
    state = np.asarray(state, float)
    norm = np.max(np.abs(state), axis=0)
    norm = np.where(norm > 0, norm, 1.0)
    xn = state / norm
    sec = poincare_section(t, state)
    pts = sec.points / norm[1:]
    dt = float(t[1] - t[0])
    f_y = dominant_frequency(state[:, 0], dt)
    return Reference(t=t, state=state, norm=norm, points=PointGrid.of(xn), s0=float(np.mean(np.sum(xn**2, 1))),
                     section=pts, section_times=(sec.times - t[0]) * f_y,
                     p0=float(np.mean(np.sum(pts**2, 1)) + 1.0) if len(pts) else 1.0,
                     f_y=f_y, f_theta=dominant_frequency(state[:, 2], dt), sub=sub)


def attractor_shape_loss(sim: NDArray, ref: Reference) -> float:
    """The shape term of :func:`loss_terms`: the mean squared distance from each normalised simulated point to the
    nearest data point and from every ``ref.sub``-th data point to the nearest simulated point, averaged and
    divided by ``ref.s0``.  ``sim`` (n, 4) is sampled at ``ref.t``."""
    sn = sim / ref.norm
    d1 = ref.points.nearest_squared(sn)  # each simulated point's same-time data point is its first guess
    every = np.arange(0, ref.n, ref.sub)
    d2 = PointGrid.of(sn).nearest_squared(ref.points.points[every], guess=every)
    return float(0.5 * (np.mean(d1) + np.mean(d2)) / ref.s0)


def loss_terms(sim: NDArray, n_valid: int, ref: Reference, weights: LossWeights = LossWeights()) -> LossTerms:
    """Loss of a simulated trajectory ``sim`` (n, 4), sampled at ``ref.t``, against ``ref``.

    ``n_valid < ref.n`` marks a blow-up (see the module docstring); never raises, never NaN.
    """
    n = ref.n
    if n_valid < n:
        pen = weights.penalty * (2.0 - n_valid / n)
        return LossTerms(pen, pen, pen, pen, True)
    shape = attractor_shape_loss(sim, ref)
    sec = poincare_section(ref.t, sim)
    q = sec.points / ref.norm[1:]
    K = ref.section.shape[0]
    if K:
        k = min(K, q.shape[0])
        d = np.empty(K)
        dtk = (sec.times[:k] - ref.t[0]) * ref.f_y - ref.section_times[:k]
        d[:k] = np.sum((q[:k] - ref.section[:k]) ** 2, axis=1) + np.minimum(dtk**2, 1.0)
        d[k:] = np.sum(ref.section[k:] ** 2, axis=1) + 1.0
        poinc = float(np.mean(d) / ref.p0)
    else:
        poinc = 0.0 if q.shape[0] == 0 else 1.0
    fy = dominant_frequency(sim[:, 0], ref.dt)
    ft = dominant_frequency(sim[:, 2], ref.dt)
    ry = (fy - ref.f_y) / ref.f_y if ref.f_y > 0 else 0.0
    rt = (ft - ref.f_theta) / ref.f_theta if ref.f_theta > 0 else 0.0
    freq = 0.5 * (min(ry * ry, 1.0) + min(rt * rt, 1.0))
    total = weights.shape * shape + weights.poincare * poinc + weights.frequency * freq
    total = float(min(total, 0.999 * weights.penalty))
    return LossTerms(float(shape), poinc, float(freq), total, False)


def rest_model_terms(ref: Reference, weights: LossWeights = LossWeights()) -> LossTerms:
    """Loss of the rest model (a trajectory sitting at the origin): the normalisation check."""
    return loss_terms(np.zeros_like(ref.state), ref.n, ref, weights)
