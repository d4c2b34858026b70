"""The fit's first step: the runs' smoothed states and derivatives, before any method sees them.

* :mod:`~fitting.derivatives.decimation`: block averaging of runs filmed at many frames per period;
* :mod:`~fitting.derivatives.savitzky_golay`: smoothing and differentiation (Savitzky-Golay), :class:`SmoothingConfig`,
  :class:`Derivatives`;
* :mod:`~fitting.derivatives.integral_form`: the integral (position-space) form of the equations of motion, the data
  of the discovery and of the oracle, with its hinge-smoothed column states;
* :mod:`~fitting.derivatives.frequencies`: the runs' oscillation frequencies, one rule (:func:`oscillation_frequencies`);
* :mod:`~fitting.derivatives.preparation`: all of the above done once per data set
  (:func:`~fitting.derivatives.preparation.prepare_dataset`, a
  :class:`~fitting.derivatives.preparation.PreparedDataset`, re-exported by :mod:`fitting`), read by the fit and by
  the diagnosis.

The names of :mod:`~fitting.derivatives.savitzky_golay` and :func:`oscillation_frequencies` are re-exported here.
"""
from .decimation import block_average, decimation_factor
from .frequencies import oscillation_frequencies
from .savitzky_golay import (LONG_WINDOW, Derivatives, SmoothingConfig, SmoothingFailure, acceleration_kernel,
                             apply_acceleration_kernel, differentiate, noise_gain, run_derivatives, savgol_weights,
                             savgol_window, smooth_long_window)

__all__ = ["SmoothingConfig", "Derivatives", "savgol_window", "savgol_weights", "differentiate", "smooth_long_window",
           "noise_gain", "run_derivatives", "acceleration_kernel", "apply_acceleration_kernel", "LONG_WINDOW",
           "SmoothingFailure", "block_average", "decimation_factor", "oscillation_frequencies"]
