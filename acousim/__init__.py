"""acousim: the physics of a levitated, hinged cube dimer: the Gor'kov model, the full-wave model and the twin.

Physics follows ``docs/conventions.md``; see the README for a tour.  Public API:

* configuration: :class:`Medium`, :class:`ParticleMaterial`, :class:`StandingWave`, :class:`CubeDimer`
* potential: :func:`gorkov_potential_density`, :func:`gorkov_potential_gradient`, :func:`contrast_factors`
* meshes and quadrature: :func:`tetrahedralize_cube`, :func:`tetrahedral_quadrature`
* the model: :class:`GorkovDimer` (forces, torques, Q_y, Q_theta, Z_eq, stiffness)
* sweeps: :func:`static_sweep`, :func:`fit_static_coefficients`, :func:`taylor_coefficients`
* closed-form references: :mod:`acousim.analytic`
* force models: the :class:`ForceModel` protocol and its :class:`ForceCoefficients`; the Gor'kov
  :class:`ForceSurrogate` (:func:`build_surrogate`); the registry of force models (:mod:`acousim.models`:
  :class:`ExperimentConditions`, :func:`static_model`, :func:`dynamic_model`, :func:`register_force_model`), with
  the full-wave model of any lab dimer from the table family (:mod:`acousim.fullwave.family`)
* equations of motion: :func:`accelerations` (force model plus effects), :class:`DimerDynamics`
  (integration), the effects of docs/conventions.md section 5 (:class:`EffectSet` and one class per effect)
* the digital twin (:mod:`acousim.twin`): :class:`TwinConfig`, :class:`Camera`, :class:`DropProtocol`,
  :func:`simulate_run`, :func:`simulate_dataset`, the ``PAPER_LIKE`` preset and :class:`TwinError`
"""
from .dimer import CubeDimer, bend_angle
from .field import StandingWave, gorkov_potential_density, gorkov_potential_gradient
from .forces import GorkovDimer, StaticForces, acoustic_force, acoustic_potential_energy, acoustic_torque
from .medium import GRAVITY, Medium, ParticleMaterial, contrast_factors
from .mesh import tetrahedralize_cube
from .quadrature import tetrahedral_quadrature, tetrahedron_rule
from .sweep import SweepResult, fit_static_coefficients, read_sweep_csv, static_sweep, taylor_coefficients
from .force_model import ForceCoefficients, ForceModel
from .surrogate import ForceSurrogate, SurrogateBox, build_surrogate, cached_surrogate
from .effects import (EFFECT_TYPES, AirDamping, EffectSet, LinearDamping, MirrorAsymmetry, PairScattering,
                      QuadraticDrag, VelocityCoupling, parse_effect)
from .air_damping import AirDampingRates, air_damping_for, air_damping_rates
from .equations import accelerations
from .dynamics import DimerDynamics, Trajectory
from .twin import PAPER, PAPER_LIKE, Camera, DropProtocol, TwinConfig, TwinError, simulate_dataset, simulate_run
from .models import (ExperimentConditions, ForceModelType, StaticModel, dynamic_model, force_model_names,
                     register_force_model, static_model)

__all__ = [
    "CubeDimer",
    "bend_angle",
    "StandingWave",
    "gorkov_potential_density",
    "gorkov_potential_gradient",
    "GorkovDimer",
    "StaticForces",
    "acoustic_force",
    "acoustic_potential_energy",
    "acoustic_torque",
    "GRAVITY",
    "Medium",
    "ParticleMaterial",
    "contrast_factors",
    "tetrahedralize_cube",
    "tetrahedral_quadrature",
    "tetrahedron_rule",
    "SweepResult",
    "fit_static_coefficients",
    "read_sweep_csv",
    "static_sweep",
    "taylor_coefficients",
    "ForceModel",
    "ForceCoefficients",
    "ForceSurrogate",
    "SurrogateBox",
    "build_surrogate",
    "cached_surrogate",
    "accelerations",
    "DimerDynamics",
    "Trajectory",
    "EFFECT_TYPES",
    "EffectSet",
    "LinearDamping",
    "QuadraticDrag",
    "PairScattering",
    "MirrorAsymmetry",
    "VelocityCoupling",
    "AirDamping",
    "AirDampingRates",
    "air_damping_rates",
    "air_damping_for",
    "parse_effect",
    "PAPER_LIKE",
    "PAPER",
    "Camera",
    "DropProtocol",
    "TwinConfig",
    "simulate_dataset",
    "simulate_run",
    "TwinError",
    "ExperimentConditions",
    "StaticModel",
    "ForceModelType",
    "register_force_model",
    "force_model_names",
    "static_model",
    "dynamic_model",
]
