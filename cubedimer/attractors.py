"""Classification of runs into attractor classes by amplitude and y-theta phase relation.

Features come from :func:`cubedimer.spectra.spectral_features` of the smoothed run (or of a
simulation).  Classes:

* ``theta-at-rest``: theta amplitude below ``theta_rest`` (default 0.02);
* ``locked-in-phase`` / ``locked-anti-phase`` / ``locked-quadrature``: theta's dominant
  frequency within ``lock_tol`` (5 %) of y's, and the phase of theta relative to y within
  60 degrees of 0, of 180 degrees, or in between;
* ``independent``: theta oscillates at its own frequency (e.g. the hinge mode), not locked to y.

The amplitude relation is reported as ``amp_theta / amp_y * L`` with ``L`` = 100 um so that
runs can also be grouped by the relative size of the hinge motion.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from numpy.typing import NDArray

from .spectra import SpectralFeatures, spectral_features

__all__ = ["ClassifyConfig", "AttractorClass", "classify", "classify_signal", "ATTRACTOR_CLASSES"]

ATTRACTOR_CLASSES = ("theta-at-rest", "locked-in-phase", "locked-anti-phase", "locked-quadrature",
                     "independent")


@dataclass(frozen=True)
class ClassifyConfig:
    """Thresholds: ``theta_rest`` [-], ``lock_tol`` (relative frequency), ``phase_tol`` [rad]."""

    theta_rest: float = 0.02
    lock_tol: float = 0.05
    phase_tol: float = np.pi / 3


@dataclass(frozen=True)
class AttractorClass:
    """The class label and the features it was derived from (frequencies in Hz, phase in rad)."""

    label: str
    f_y: float
    f_theta: float
    amp_y: float
    amp_theta: float
    phase: float
    amplitude_ratio: float

    def to_dict(self) -> dict:
        return asdict(self)


def classify(features: SpectralFeatures, config: ClassifyConfig = ClassifyConfig()) -> AttractorClass:
    """Attractor class of a run from its spectral features."""
    if features.amp_theta < config.theta_rest:
        label = "theta-at-rest"
    elif features.f_y > 0 and abs(features.f_theta / features.f_y - 1.0) < config.lock_tol:
        ph = abs(features.phase)
        label = ("locked-in-phase" if ph < config.phase_tol else
                 "locked-anti-phase" if ph > np.pi - config.phase_tol else "locked-quadrature")
    else:
        label = "independent"
    ratio = features.amp_theta / features.amp_y * 1e-4 if features.amp_y > 0 else float("inf")
    return AttractorClass(label=label, f_y=features.f_y, f_theta=features.f_theta, amp_y=features.amp_y,
                          amp_theta=features.amp_theta, phase=features.phase, amplitude_ratio=float(ratio))


def classify_signal(y: NDArray, theta: NDArray, dt: float, config: ClassifyConfig = ClassifyConfig()) -> AttractorClass:
    """Classify a trajectory given y [m], theta [-] sampled every ``dt`` [s].

    Only the second half of the signal is used, so that transients decay (the long-time state).
    """
    h = len(y) // 2
    return classify(spectral_features(np.asarray(y)[h:], np.asarray(theta)[h:], dt), config)
