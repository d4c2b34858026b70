"""Step 1, calibrate: the simulation fitted to the data (pressure, origin, the model's own parameters).

* :mod:`~validation.diagnosis.calibrate.calibration`: pressure and origin from the vertical equation;
* :mod:`~validation.diagnosis.calibrate.gap_model`: the calibrated simulation plus effects, fitted, and its residuals;
* :mod:`~validation.diagnosis.calibrate.metrics`: the gap components and the scalar gap;
* :mod:`~validation.diagnosis.calibrate.orientation`: whether y points down, told by the trap's asymmetry;
* :mod:`~validation.diagnosis.calibrate.model_parameters`: the model's own calibratable parameters (the hinge gap);
* :mod:`~validation.diagnosis.calibrate.drift`: the pressure per time window within runs, and the test of its drift.
"""
