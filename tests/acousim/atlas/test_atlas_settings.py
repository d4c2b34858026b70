"""The atlases' settings refuse a bad value where they are made, with a one-line AtlasError (a ValueError, which the
commands turn into exit 2) that names the command's option and the valid range."""
from __future__ import annotations

import math

import pytest

from acousim.atlas.field_drops import AtlasConfig, AtlasDimer, AtlasError
from acousim.atlas.free_y import FreeYConfig
from acousim.atlas.held_y import HeldYConfig
from acousim.atlas.resonator_map import ResonatorMapConfig

DIMERS = (AtlasDimer(500e-6, 0.02),)
GOOD = {
    AtlasConfig: dict(dimers=DIMERS, t_off=(5e-3,), theta_drop=(0.0,)),
    FreeYConfig: dict(dimers=DIMERS),
    HeldYConfig: dict(dimers=DIMERS, pressures_pa=(3000.0,), amplitudes_m=(50e-6,)),
    ResonatorMapConfig: {},
}


@pytest.mark.parametrize("config", list(GOOD))
def test_the_defaults_are_accepted(config):
    config(**GOOD[config])


@pytest.mark.parametrize("config, field, value, fragment", [
    (AtlasConfig, "dimers", (), "--dimers: give at least one"),
    (AtlasConfig, "t_off", (0.05,), "--t-off: every value must lie in [0, 0.03] s"),
    (AtlasConfig, "t_off", (), "--t-off: every value"),
    (AtlasConfig, "theta_drop", (0.99,), "--theta-drop: every value must lie in (-0.99, 0.99)"),
    (AtlasConfig, "pressure_amplitude_pa", 0.0, "--pressure must lie in (0, 100000] Pa"),
    (AtlasConfig, "frequency_hz", math.nan, "--frequency must lie in [1000, 1e+06] Hz"),
    (AtlasConfig, "duration", 0.5, "--duration must lie in [1, 120] s"),
    (AtlasConfig, "sample_rate", 100.0, "--sample-rate must lie in [200, 20000] 1/s"),
    (AtlasConfig, "transducer_q", -1.0, "--transducer-q must lie in [0, 100000]"),
    (FreeYConfig, "dimers", (), "--dimers: give at least one"),
    (FreeYConfig, "quality_factors", (-1.0,), "--qualities/--detunings/--area: the cavity's quality factor"),
    (FreeYConfig, "detunings", (), "--detunings: give at least one detuning"),
    (FreeYConfig, "area_m2", 1.0, "--qualities/--detunings/--area: the cavity area"),
    (FreeYConfig, "pressure_pa", 2e5, "--pressure must lie in (0, 100000] Pa"),
    (FreeYConfig, "amplitudes_m", (2e-3,), "--amplitudes: every value must lie in (0, 0.001] m"),
    (FreeYConfig, "theta_starts", (1.2,), "--theta-starts: every value"),
    (FreeYConfig, "settle_time", 0.5, "--settle-time must lie in [1, 600] s"),
    (FreeYConfig, "samples_per_period", 40.5, "--samples-per-period must be a whole number in [16, 1000]"),
    (FreeYConfig, "max_step", 0.0, "--max-step must lie in (0, 0.001] s"),
    (FreeYConfig, "frequency_hz", 10.0, "--frequency must lie in"),
    (HeldYConfig, "pressures_pa", (0.0,), "--pressures: every value must lie in (0, 100000] Pa"),
    (HeldYConfig, "amplitudes_m", (), "--amplitudes: every value"),
    (HeldYConfig, "theta_starts", (-1.0,), "--theta-starts: every value"),
    (HeldYConfig, "thetadot_starts", (2e3,), "--thetadot-starts: every value must lie in [-1000, 1000] 1/s"),
    (HeldYConfig, "analysed_periods", 4, "--analysed-periods must be a whole number in [8, 100000]"),
    (HeldYConfig, "settle_periods", 1.5, "--settle-periods must be a whole number in [0, 100000]"),
    (HeldYConfig, "max_step", 1.0, "--max-step must lie in (0, 0.001] s"),
    (ResonatorMapConfig, "dimers", ("bem:1",), "--dimers 'bem:1': expected"),
    (ResonatorMapConfig, "areas_m2", (1.0,), "--qualities/--areas/--detunings: the cavity area"),
    (ResonatorMapConfig, "start_amplitude", 1e-7, "the amplitudes must satisfy 0 < small < start"),
    (ResonatorMapConfig, "window", 30.0, "the times must satisfy"),
])
def test_a_bad_value_names_the_option(config, field, value, fragment):
    with pytest.raises(AtlasError) as info:
        config(**{**GOOD[config], field: value})
    message = str(info.value)
    assert isinstance(info.value, ValueError) and fragment in message and "\n" not in message


@pytest.mark.parametrize("side, gap_ratio, fragment", [
    (100e-6 / 4, 0.03, "--dimers: the side must lie in [5e-05, 0.002] m"),
    (500e-6, 0.0, "--dimers: the gap ratio must lie in (0, 0.5]"), (500e-6, 0.9, "--dimers: the gap ratio"),
])
def test_a_bad_dimer_names_the_option(side, gap_ratio, fragment):
    with pytest.raises(AtlasError, match="^--dimers: ") as info:
        AtlasDimer(side, gap_ratio)
    assert fragment in str(info.value)
