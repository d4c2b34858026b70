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
* ``independent``: theta not locked to y (its own frequency, e.g. the hinge mode, or a drifting phase).

The amplitude relation is reported as ``amp_theta / amp_y * L`` with ``L`` = 100 um so that
runs can also be grouped by the relative size of the hinge motion.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from numpy.typing import NDArray

from .poincare import poincare_section
from .spectra import spectral_features

__all__ = ["ClassifyConfig", "AttractorClass", "classify_trajectory", "classify_signal", "section_phase",
           "ATTRACTOR_CLASSES", "CLASS_COLORS"]

ATTRACTOR_CLASSES = ("theta-at-rest", "locked-in-phase", "locked-anti-phase", "locked-quadrature",
                     "independent")

#: One matplotlib colour per class, for every figure that colours runs by class.
CLASS_COLORS = {"locked-in-phase": "tab:blue", "locked-anti-phase": "tab:red", "locked-quadrature": "tab:purple",
                "theta-at-rest": "tab:gray", "independent": "tab:orange"}


@dataclass(frozen=True)
class ClassifyConfig:
    """Thresholds: ``theta_rest`` [-], ``lock_tol`` (relative frequency), ``phase_tol`` [rad],
    ``coherence_min`` (of the section phase, in [0, 1])."""

    theta_rest: float = 0.02
    lock_tol: float = 0.05
    phase_tol: float = np.pi / 3
    coherence_min: float = 0.95

    def __post_init__(self) -> None:
        if not (self.theta_rest >= 0 and self.lock_tol > 0 and 0 < self.phase_tol <= np.pi / 2
                and 0 <= self.coherence_min <= 1):
            raise ValueError(f"bad classification thresholds: {self!r}")


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


def _label(f_y: float, f_theta: float, amp_theta: float, phase: float, coherence: float,
           config: ClassifyConfig) -> str:
    if amp_theta < config.theta_rest:
        return "theta-at-rest"
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
    label = _label(feats.f_y, feats.f_theta, feats.amp_theta, phase, coh, config)
    ratio = feats.amp_theta / feats.amp_y * 1e-4 if feats.amp_y > 0 else float("inf")
    return AttractorClass(label=label, f_y=feats.f_y, f_theta=feats.f_theta, amp_y=feats.amp_y,
                          amp_theta=feats.amp_theta, phase=feats.phase, amplitude_ratio=float(ratio),
                          section_phase=sp, coherence=coh)


def classify_signal(y: NDArray, theta: NDArray, dt: float, config: ClassifyConfig = ClassifyConfig()) -> AttractorClass:
    """:func:`classify_trajectory` of positions y [m], theta [-] sampled every ``dt`` [s]; the
    velocities are their central differences (pass smoothed positions for noisy data)."""
    y, theta = np.asarray(y, float), np.asarray(theta, float)
    state = np.column_stack([y, np.gradient(y, dt), theta, np.gradient(theta, dt)])
    return classify_trajectory(np.arange(len(y)) * dt, state, config)
