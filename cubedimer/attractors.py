"""The attractor class of a run: how the hinge moves relative to y once transients have decayed.

One classifier for measured, fitted and simulated runs.  It reads the second half of a run
(``start_fraction``) and combines two views of the y-theta relation:

* spectral features (:func:`cubedimer.spectra.spectral_features`): dominant frequencies of y and
  theta, robust amplitudes, and the phase of theta relative to y from the cross spectrum at f_y;
* the section phase (:func:`section_phase`): at every crossing of the Poincare section
  (y = 0, ydot < 0) the phase of theta's y-frequency motion, whose circular mean gives the phase and
  whose length (the *coherence*, 1 for a perfect lock) tells a lock from a slow drift that a
  frequency comparison alone cannot resolve.

Classes (:data:`ATTRACTOR_CLASSES`):

* ``theta-at-rest``: theta amplitude below ``theta_rest`` (default 0.02);
* ``locked-in-phase`` / ``locked-anti-phase`` / ``locked-quadrature``: theta's dominant
  frequency within ``lock_tol`` (5 %) of y's and a coherent section phase (coherence >=
  ``coherence_min``, 0.95), the phase within ``phase_tol`` (60 degrees) of 0, of 180 degrees, or in between;
* ``locked-p:q``: a lock of another ratio: p periods of y for q of the hinge (f_theta / f_y = q / p, p and q coprime,
  each at most ``max_lock_order``, not 1:1), theta's dominant frequency within ``lock_tol`` of q / p f_y and the
  motion repeating every p periods of y (:func:`lock_coherence` >= ``coherence_min``); the ratio is
  :attr:`AttractorClass.lock_ratio`, e.g. ``"3:2"`` for a hinge at 2/3 f_y;
* ``independent``: theta not locked to y (its own frequency, e.g. the hinge mode, or a drifting phase).

The amplitude relation is reported as ``amp_theta / amp_y * L`` with ``L`` = 100 um so that
runs can also be grouped by the relative size of the hinge motion.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from numpy.typing import NDArray

from .config_checks import check_fraction, check_non_negative, check_positive, check_that, check_whole
from .poincare import poincare_section
from .spectra import spectral_features

__all__ = ["ClassifyConfig", "AttractorClass", "classify_trajectory", "classify_signal", "section_phase",
           "lock_coherence", "lock_ratios", "ATTRACTOR_CLASSES", "CLASS_COLORS", "LOCKED_AT_FY"]

ATTRACTOR_CLASSES = ("theta-at-rest", "locked-in-phase", "locked-anti-phase", "locked-quadrature",
                     "locked-p:q", "independent")
#: The classes of a hinge locked at f_y (1:1); ``locked-p:q`` is locked at another ratio.
LOCKED_AT_FY = ("locked-in-phase", "locked-anti-phase", "locked-quadrature")

#: One matplotlib colour per class, for every figure that colours runs by class.
CLASS_COLORS = {"locked-in-phase": "tab:blue", "locked-anti-phase": "tab:red", "locked-quadrature": "tab:purple",
                "locked-p:q": "tab:green", "theta-at-rest": "tab:gray", "independent": "tab:orange"}


@dataclass(frozen=True)
class ClassifyConfig:
    """Thresholds: ``theta_rest`` [-], ``lock_tol`` (relative frequency), ``phase_tol`` [rad],
    ``coherence_min`` (of the section phase, in [0, 1]) and ``max_lock_order`` (the largest p or q of a p:q lock;
    1 reads only 1:1 locks)."""

    theta_rest: float = 0.02
    lock_tol: float = 0.05
    phase_tol: float = np.pi / 3
    coherence_min: float = 0.95
    max_lock_order: int = 3

    def __post_init__(self) -> None:
        check_non_negative(self, "theta_rest")
        check_positive(self, "lock_tol")
        check_positive(self, "phase_tol")
        check_that(self, self.phase_tol <= np.pi / 2, f"phase_tol must be at most pi/2, got {self.phase_tol!r}")
        check_fraction(self, "coherence_min", closed=True)
        check_whole(self, "max_lock_order")
        check_that(self, self.max_lock_order <= 8, f"max_lock_order must be at most 8, got {self.max_lock_order!r}")


@dataclass(frozen=True)
class AttractorClass:
    """The class label and the features it was derived from.

    Attributes
    ----------
    label : str
        One of :data:`ATTRACTOR_CLASSES`.
    f_y, f_theta : float
        Dominant frequencies [Hz].
    amp_y, amp_theta : float
        Half the 1-99 % quantile range of y [m] and theta [-].
    phase : float
        Phase of theta relative to y at f_y from the cross spectrum [rad] (0: in phase).
    amplitude_ratio : float
        amp_theta / amp_y x 100 um [-].
    section_phase : float
        Circular-mean phase of theta's y-frequency motion at the section crossings [rad] (NaN with
        fewer than 3 crossings).
    coherence : float
        Length of that circular mean (1: perfectly locked; NaN with fewer than 3 crossings).
    lock_ratio : str
        ``"p:q"`` of a lock (p periods of y for q of the hinge; ``"1:1"`` for the classes locked at f_y), ``""``
        for ``independent`` and ``theta-at-rest``.
    lock_coherence : float
        :func:`lock_coherence` at the nearest ratio q / p (NaN when theta's frequency is near none).
    """

    label: str
    f_y: float
    f_theta: float
    amp_y: float
    amp_theta: float
    phase: float
    amplitude_ratio: float
    section_phase: float = float("nan")
    coherence: float = float("nan")
    lock_ratio: str = ""
    lock_coherence: float = float("nan")

    def to_dict(self) -> dict:
        return asdict(self)


def section_phase(t: NDArray, state: NDArray) -> tuple[float, float]:
    """(phase [rad], coherence) of theta relative to y at the Poincare section y = 0, ydot < 0.

    With y ~ A cos(w t) the section is w t = pi/2; for theta ~ m + B cos(w t + p) there
    theta - m = -B sin p and thetadot = -B w cos p, so p = atan2(-(theta - m), -thetadot / w), with
    m the mean of theta and w from the crossing times.  Returns the circular mean of p over the
    crossings and its length; (NaN, NaN) with fewer than 3 crossings.

    Parameters
    ----------
    t : ndarray (n,) [s]
    state : ndarray (n, 4)
        [y, ydot, theta, thetadot].
    """
    t, state = np.asarray(t, float), np.asarray(state, float)
    sec = poincare_section(t, state)
    if len(sec) < 3:
        return float("nan"), float("nan")
    w = 2 * np.pi * (len(sec) - 1) / (sec.times[-1] - sec.times[0])
    theta = state[:, 2]
    mean = float(np.mean(theta[np.isfinite(theta)]))
    z = np.mean(np.exp(1j * np.arctan2(-(sec.theta - mean), -sec.thetadot / w)))
    return float(np.angle(z)), float(abs(z))


def lock_ratios(max_order: int) -> list[tuple[int, int]]:
    """Every (p, q), coprime, 1 <= p, q <= ``max_order``, other than (1, 1): the p:q locks, f_theta = q / p f_y."""
    return [(p, q) for p in range(1, max_order + 1) for q in range(1, max_order + 1)
            if (p, q) != (1, 1) and np.gcd(p, q) == 1]


def lock_coherence(t: NDArray, state: NDArray, p: int, f_theta: float) -> float:
    """How exactly the hinge repeats every ``p`` periods of y: 1 for a p:q lock, small for a drift.

    At the k-th crossing of the section y = 0, ydot < 0 the hinge's phase is
    psi_k = atan2(-thetadot / w, theta - m) (w = 2 pi ``f_theta``, m the mean of theta).  On a p:q lock the state
    at crossing k + p is the state at crossing k, so psi_k depends only on k mod p, however anharmonic the motion;
    the coherence is the mean over the p residues of the length of the circular mean of their psi_k.  For p = 1
    it is the coherence of :func:`section_phase`.  NaN with fewer than 3 crossings per residue.

    Parameters
    ----------
    t : ndarray (n,) [s]
    state : ndarray (n, 4)
        [y, ydot, theta, thetadot].
    p : int
        Periods of y per period of the locked motion.
    f_theta : float
        Theta's dominant frequency [Hz] (normalises thetadot).
    """
    sec = poincare_section(np.asarray(t, float), np.asarray(state, float))
    if len(sec) < 3 * p or not f_theta > 0:
        return float("nan")
    theta = np.asarray(state, float)[:, 2]
    mean = float(np.mean(theta[np.isfinite(theta)]))
    psi = np.arctan2(-sec.thetadot / (2 * np.pi * f_theta), sec.theta - mean)
    return float(np.mean([abs(np.mean(np.exp(1j * psi[r::p]))) for r in range(p)]))


def _nearest_ratio(f_y: float, f_theta: float, config: ClassifyConfig) -> tuple[int, int] | None:
    """The (p, q) with q / p nearest f_theta / f_y (relative), if within ``lock_tol``; 1:1 included."""
    if not (f_y > 0 and f_theta > 0):
        return None
    r = f_theta / f_y
    best = min([(1, 1)] + lock_ratios(config.max_lock_order), key=lambda pq: abs(r * pq[0] / pq[1] - 1.0))
    return best if abs(r * best[0] / best[1] - 1.0) < config.lock_tol else None


def _label(f_y: float, f_theta: float, amp_theta: float, phase: float, coherence: float,
           config: ClassifyConfig, ratio: tuple[int, int] | None = None, ratio_coherence: float = float("nan")) -> str:
    if amp_theta < config.theta_rest:
        return "theta-at-rest"
    if ratio is not None and ratio != (1, 1):
        return "locked-p:q" if ratio_coherence >= config.coherence_min else "independent"  # NaN: not locked
    locked = f_y > 0 and abs(f_theta / f_y - 1.0) < config.lock_tol
    if locked and np.isfinite(coherence):
        locked = coherence >= config.coherence_min
    if not locked:
        return "independent"
    ph = abs(phase)
    return ("locked-in-phase" if ph < config.phase_tol else
            "locked-anti-phase" if ph > np.pi - config.phase_tol else "locked-quadrature")


def classify_trajectory(t: NDArray, state: NDArray, config: ClassifyConfig = ClassifyConfig(),
                        start_fraction: float = 0.5) -> AttractorClass:
    """Attractor class of a uniformly sampled trajectory, from ``start_fraction`` of it on.

    Parameters
    ----------
    t : ndarray (n,)
        Uniform times [s].
    state : ndarray (n, 4)
        [y, ydot, theta, thetadot] (exact, or smoothed from data).
    config : ClassifyConfig
    start_fraction : float
        Fraction of the run skipped so that transients decay (default: its first half).
    """
    t, state = np.asarray(t, float), np.asarray(state, float)
    h = int(len(t) * start_fraction)
    t, state = t[h:], state[h:]
    dt = float(t[1] - t[0])
    feats = spectral_features(state[:, 0], state[:, 2], dt)
    sp, coh = section_phase(t, state)
    # the section phase is exact at the crossings; the spectral one is the fallback
    phase = sp if np.isfinite(sp) else feats.phase
    pq = _nearest_ratio(feats.f_y, feats.f_theta, config)
    pq_coh = (coh if pq == (1, 1) else lock_coherence(t, state, pq[0], feats.f_theta)) if pq else float("nan")
    label = _label(feats.f_y, feats.f_theta, feats.amp_theta, phase, coh, config, pq, pq_coh)
    ratio = feats.amp_theta / feats.amp_y * 1e-4 if feats.amp_y > 0 else float("inf")
    lock = f"{pq[0]}:{pq[1]}" if label.startswith("locked-") and pq else ""
    return AttractorClass(label=label, f_y=feats.f_y, f_theta=feats.f_theta, amp_y=feats.amp_y,
                          amp_theta=feats.amp_theta, phase=feats.phase, amplitude_ratio=float(ratio),
                          section_phase=sp, coherence=coh, lock_ratio=lock, lock_coherence=float(pq_coh))


def classify_signal(y: NDArray, theta: NDArray, dt: float, config: ClassifyConfig = ClassifyConfig()) -> AttractorClass:
    """:func:`classify_trajectory` of positions y [m], theta [-] sampled every ``dt`` [s]; the
    velocities are their central differences (pass smoothed positions for noisy data)."""
    y, theta = np.asarray(y, float), np.asarray(theta, float)
    state = np.column_stack([y, np.gradient(y, dt), theta, np.gradient(theta, dt)])
    return classify_trajectory(np.arange(len(y)) * dt, state, config)
