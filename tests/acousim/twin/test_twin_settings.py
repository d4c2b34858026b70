"""TwinConfig refuses a bad setting where it is made, with a one-line TwinError (a ValueError, exit 2 from
``acousim simulate``) naming the field or its option."""
from __future__ import annotations

import math

import pytest

from acousim.models import ExperimentConditions
from acousim.twin import Camera, TwinConfig, TwinError


@pytest.mark.parametrize("kwargs, fragment", [
    (dict(runs=0), "TwinConfig.runs must be a whole number >= 1, got 0"),
    (dict(runs=2.5), "TwinConfig.runs must be a whole number"),
    (dict(duration=-1.0), "TwinConfig.duration must be a positive finite number"),
    (dict(seed=-1), "TwinConfig.seed must be a whole number >= 0"),
    (dict(pressure_error=0.5), "pressure error (--pressure-error) must lie in [0, 0.5)"),
    (dict(transducer_q=math.nan), "transducer quality factor (--transducer-q) must lie in [0, 100000]"),
    (dict(max_step=0.0), "TwinConfig.max_step must be a positive finite number"),
    (dict(experiment=ExperimentConditions(side_length_m=3e-3)), "TwinConfig.side must lie in [5e-05, 0.002] m"),
    (dict(model_spec="fullwave"), "experiment and model_spec must be an ExperimentConditions and a ModelSpec"),
    (dict(experiment=ExperimentConditions(gap_m=1e-5)), "gap_m is the model's own option"),
    (dict(duration=1e-3), "0.001 s at 2000 fps gives only 2 frames"),
    (dict(cavity_detuning=1.0), "needs the cavity's quality factor: give --transducer-q > 0"),
    (dict(cavity_detuning=1.0, transducer_q=250.0, cavity_area=-1.0), "--cavity-area: the cavity area must lie in"),
])
def test_a_bad_setting_is_a_one_line_error_naming_it(kwargs, fragment):
    with pytest.raises(TwinError) as info:
        TwinConfig(**kwargs)
    assert isinstance(info.value, ValueError) and fragment in str(info.value) and "\n" not in str(info.value)


def test_the_defaults_are_accepted():
    assert TwinConfig().runs == 10 and TwinConfig(cavity_detuning=1.0, transducer_q=250.0).cavity_mode is not None


@pytest.mark.parametrize("field, value, fragment", [
    ("fps", 0.0, "Camera.fps must be a positive finite number"),
    ("noise_y", -1e-6, "Camera.noise_y must be a finite number >= 0"),
    ("noise_theta", math.nan, "Camera.noise_theta must be a finite number >= 0"),
    ("missing_frames", -1, "Camera.missing_frames must be a whole number >= 0"),
])
def test_a_bad_camera_is_a_one_line_error_naming_it(field, value, fragment):
    with pytest.raises(TwinError) as info:
        Camera(**{field: value})
    assert fragment in str(info.value) and "\n" not in str(info.value)
