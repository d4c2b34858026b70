"""Contrast factors, the Gor'kov potential density and its analytic gradient."""
import numpy as np
import pytest

from acousim.field import StandingWave, gorkov_potential_density, gorkov_potential_gradient
from acousim.medium import Medium, ParticleMaterial, contrast_factors


def test_contrast_factors_nacl_in_air():
    f1, f2 = contrast_factors(Medium(), ParticleMaterial())
    # f1 = 1 - rho0 c0^2 / K_p = 1 - 1.204 * 343^2 / 24.9e9; f2 = 2 (2160 - 1.204) / (4320 + 1.204)
    np.testing.assert_allclose(f1, 1 - 1.204 * 343**2 / 24.9e9, rtol=1e-14)
    np.testing.assert_allclose(f2, 2 * (2160 - 1.204) / (2 * 2160 + 1.204), rtol=1e-14)


def test_potential_density_limits(default_wave):
    w = default_wave
    f1, f2 = w.contrast_factors
    e = w.acoustic_energy_density
    # at the node sin = 0: u = -3/2 f2 E; at the antinode (k Z = pi/2): u = f1 E
    np.testing.assert_allclose(gorkov_potential_density(0.0, w), -1.5 * f2 * e, rtol=1e-14)
    np.testing.assert_allclose(gorkov_potential_density(np.pi / 2 / w.wavenumber, w), f1 * e, rtol=1e-12)


@pytest.mark.parametrize("z", [-2e-3, -4.3e-4, 0.0, 1e-4, 1.5e-3])
def test_gradient_matches_finite_difference(default_wave, z):
    h = 1e-8  # m; central difference error ~ h^2 u''' / 6 ~ 1e-10 relative
    fd = (gorkov_potential_density(z + h, default_wave) - gorkov_potential_density(z - h, default_wave)) / (2 * h)
    scale = default_wave.wavenumber * default_wave.acoustic_energy_density
    np.testing.assert_allclose(gorkov_potential_gradient(z, default_wave), fd, atol=1e-7 * scale)


def test_energy_density_scales_with_pressure_squared(default_wave):
    w2 = default_wave.with_pressure(2 * default_wave.pressure_amplitude_pa)
    np.testing.assert_allclose(w2.acoustic_energy_density, 4 * default_wave.acoustic_energy_density, rtol=1e-14)


@pytest.mark.parametrize("bad", [0.0, -1.0, np.nan])
def test_bad_pressure_rejected(bad):
    with pytest.raises(ValueError):
        StandingWave(bad)


@pytest.mark.parametrize("make, field", [
    (Medium, "frequency_hz"), (Medium, "sound_speed_m_s"), (Medium, "density_kg_m3"),
    (ParticleMaterial, "density_kg_m3"), (ParticleMaterial, "bulk_modulus_pa"),
])
@pytest.mark.parametrize("value", [0.0, -1.0, float("nan"), float("inf")])
def test_the_medium_and_the_material_refuse_a_non_positive_value(make, field, value):
    with pytest.raises(ValueError, match=rf"^{make.__name__}\.{field} must be a positive finite number, got "):
        make(**{field: value})
