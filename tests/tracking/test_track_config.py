"""TrackConfig refuses a bad setting where it is made, with a one-line TrackingError (a ValueError, exit 2 from the
command) naming the option."""
from __future__ import annotations

import math

import pytest

from tracking.recording import TrackingError
from tracking.track_config import TrackConfig


def test_the_defaults_and_the_optional_settings_are_accepted():
    TrackConfig()
    TrackConfig(fps=2000.0, pixel_size=1e-5, origin_row=12.5, edge_window=6, roi=(0, 10, 0, 20), polarity="dark")


@pytest.mark.parametrize("field, value, fragment", [
    ("fps", 0.0, "--fps must be a positive finite number"),
    ("pixel_size", -1e-5, "--pixel-size must be a positive finite number"),
    ("pixel_size", 1.0, "pixel size 1.0 m is implausible"),
    ("origin_frames", 0, "--origin-frames must be a whole number >= 1"),
    ("origin_row", math.nan, "--origin-row must be finite"),
    ("polarity", "grey", "--polarity: unknown 'grey' (use one of auto, dark, bright)"),
    ("up", "left", "--up: unknown 'left'"),
    ("edge_window", 60, "--edge-window must be a whole number in [2, 50] px"),
    ("roi", (10, 5, 0, 20), "region of interest 10:5,0:20 is empty or inverted"),
    ("area_tolerance", 0.0, "--area-tolerance must be a positive finite number"),
    ("max_edge_rms_factor", math.inf, "TrackConfig.max_edge_rms_factor must be a positive finite number"),
    ("max_hinge_gap", -0.1, "--max-hinge-gap must be"),
])
def test_a_bad_value_names_the_option(field, value, fragment):
    with pytest.raises(TrackingError) as info:
        TrackConfig(**{field: value})
    assert isinstance(info.value, ValueError) and fragment in str(info.value) and "\n" not in str(info.value)
