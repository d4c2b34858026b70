"""acousim: the physics of a levitated, hinged cube dimer: the Gor'kov model, the full-wave model and the twin.

Physics follows ``docs/conventions.md``; see the README for a tour.  Public API (the building blocks, such as the
Gor'kov potential density, the tetrahedral quadrature or one class per effect, are in their modules):

* configuration: :class:`Medium`, :class:`ParticleMaterial`, :class:`StandingWave`, :class:`CubeDimer`
* the Gor'kov model: :class:`GorkovDimer` (forces, torques, Q_y, Q_theta, Z_eq, stiffness) on tetrahedral meshes
* sweeps: :func:`static_sweep`, :func:`fit_static_coefficients`, :func:`read_sweep_csv`
* force models: the :class:`ForceModel` protocol; the Gor'kov :class:`ForceSurrogate` (:func:`build_surrogate`,
  :func:`cached_surrogate`); the registry of force models (:mod:`acousim.models`: :class:`ExperimentConditions`,
  :class:`StaticModel`, :class:`ForceModelType`, :func:`static_model`, :func:`dynamic_model`,
  :func:`register_force_model`, :func:`force_model_names`), with the full-wave model of any lab dimer from the
  table family (:mod:`acousim.fullwave`)
* equations of motion: :class:`DimerDynamics` (force model plus effects, integration); the effects of
  docs/conventions.md section 5: the registry :data:`EFFECT_TYPES` (:func:`register_effect` adds one),
  :class:`EffectSet`, :func:`parse_effect`;
  the air's damping from geometry (:func:`air_damping_rates`, :func:`air_damping_for`, docs/damping.md)
* the levitator as a resonator (docs/twin.md): :class:`CavityMode`, :class:`CoupledCavity` (the mode's envelope
  equation coupled to a dimer), :func:`potential_series`, :func:`integrate_coupled`, the linear theory
  :class:`LinearCavityCoupling` and the lag's velocity couplings :func:`lag_couplings`
* the digital twin (:mod:`acousim.twin`): :class:`TwinConfig`, :class:`Camera`, :class:`DropProtocol`,
  :func:`simulate_run`, :func:`simulate_dataset`, the ``PAPER`` (physics only) and ``PAPER_LIKE`` (tuned) presets and :class:`TwinError`
* closed-form references: :mod:`acousim.analytic`
"""
import cubedimer  # noqa: F401  (first: sets up the compile cache, cubedimer.compile_cache)
from cubedimer.distribution import __version__
from .dimer import CubeDimer
from .field import StandingWave
from .gorkov.forces import GorkovDimer
from .medium import Medium, ParticleMaterial
from .statics.sweep import fit_static_coefficients, read_sweep_csv, static_sweep
from .force_model import ForceModel
from .gorkov.energy_surrogate import ForceSurrogate, build_surrogate, cached_surrogate
from .dynamics.effects import EFFECT_TYPES, EffectSet, air_damping_for, parse_effect, register_effect
from .dynamics.integrator import DimerDynamics
from .dynamics.air_damping import air_damping_rates
from .dynamics.resonator import CavityMode, CoupledCavity, integrate_coupled, potential_series, slow_response_gains
from .dynamics.cavity_stability import LinearCavityCoupling, lag_couplings
from .twin import PAPER, PAPER_LIKE, Camera, DropProtocol, TwinConfig, TwinError, simulate_dataset, simulate_run
from .static_model import StaticModel
from .models import (ExperimentConditions, ForceModelType, dynamic_model, force_model_names, register_force_model,
                     static_model)

__all__ = [
    "CubeDimer", "StandingWave", "Medium", "ParticleMaterial", "GorkovDimer",
    "static_sweep", "fit_static_coefficients", "read_sweep_csv",
    "ForceModel", "ForceSurrogate", "build_surrogate", "cached_surrogate",
    "ExperimentConditions", "StaticModel", "ForceModelType", "register_force_model", "force_model_names",
    "static_model", "dynamic_model",
    "CavityMode", "CoupledCavity", "integrate_coupled", "potential_series", "slow_response_gains", "LinearCavityCoupling",
    "lag_couplings",
    "DimerDynamics", "EFFECT_TYPES", "EffectSet", "parse_effect", "register_effect", "air_damping_rates", "air_damping_for",
    "PAPER", "PAPER_LIKE", "Camera", "DropProtocol", "TwinConfig", "simulate_dataset", "simulate_run", "TwinError",
]
