"""Full-wave (boundary-element) scattering model of the cube dimer (docs/conventions.md section 7).

* :func:`solve_scattering` (bempp-cl, Burton-Miller, P1) on any set of closed :class:`Body` surfaces, with
  :class:`HeightStructure` giving every force and torque as ``A + B cos(2kZ) + C sin(2kZ)``;
* :func:`dimer_bodies` and :class:`DimerMeshSpec`: the posed, gapped, hinge-graded cube meshes;
* :class:`FullwaveSurrogate`, :func:`build_fullwave_surrogate`, :func:`cached_fullwave_surrogate`,
  :func:`default_fullwave_surrogate`: the Chebyshev-in-theta force surrogate (same interface as
  :class:`acousim.gorkov.energy_surrogate.ForceSurrogate`, without a potential);
* ``python -m acousim force`` (:mod:`acousim.cli.force_command`) and the convergence study
  (``python -m acousim convergence``).

bempp-cl is imported lazily, at the first solve.
"""
from .geometry import (COARSE_SPEC, DEFAULT_SPEC, DimerMeshSpec, MeshError, check_closed_oriented,
                       dimer_bodies, hinge_refined_spec, mesh_family, split_bodies, volume_centroid)
from .mesh_rules import TABLE_SPEC, edge_graded_mesh_spec
from .flux import (ExteriorField, FluxSurface, double_layer_potential, enclosing_sphere_surface, flux_height_structure,
                   mirror_half_surface)
from .solver import Body, HeightStructure, ScatteringSolution, solve_scattering
from .force_surrogate import (FullwaveSurrogate, build_fullwave_surrogate, cached_fullwave_surrogate,
                              coarse_fullwave_surrogate, default_fullwave_surrogate, dimer_generalized_coefficients)

__all__ = [
    "Body", "HeightStructure", "ScatteringSolution", "solve_scattering",
    "ExteriorField", "FluxSurface", "double_layer_potential", "enclosing_sphere_surface", "mirror_half_surface",
    "flux_height_structure",
    "DimerMeshSpec", "DEFAULT_SPEC", "TABLE_SPEC", "COARSE_SPEC", "mesh_family", "hinge_refined_spec", "edge_graded_mesh_spec",
    "dimer_bodies",
    "split_bodies",
    "check_closed_oriented", "volume_centroid", "MeshError",
    "FullwaveSurrogate", "build_fullwave_surrogate", "cached_fullwave_surrogate", "default_fullwave_surrogate",
    "coarse_fullwave_surrogate", "dimer_generalized_coefficients",
]
