"""The full-wave table family: every lab dimer from tables over the dimensionless parameters (ks, g/s).

Scaling.  Rigid, immobile cubes in an inviscid medium (docs/conventions.md section 7) scatter a field that depends on
the geometry only through ``ks`` (wavenumber times side), ``g/s`` (hinge gap over side) and ``r_e/s`` (edge
radius over side).  With the incident field ``p0 sin(kZ)`` and lengths measured in units of s, the
surface pressure is ``p0 * P(x/s; ks, g/s)`` and the particle velocity ``p0/(rho0 c0) * V(x/s; ...)``, so the
radiation-stress bracket ``|p|^2/(4 rho0 c0^2) - rho0 |v|^2/4`` is ``p0^2/(rho0 c0^2)`` times a dimensionless
function; integrated over areas (``s^2``) and lever arms (``s``)::

    F_Z     = p0^2 s^2 / (rho0 c0^2) * f(theta, k Z_com; ks, g/s)          [N]
    Q_theta = p0^2 s^3 / (rho0 c0^2) * q(theta, k Z_com; ks, g/s)          [N m]

exactly, for any side, frequency, sound speed, air density and pressure.  The height structure
``A + B cos(2kZ) + C sin(2kZ)`` carries over, with 2k = 2 ks / s.  Mass, hinge inertia and gravity do not
enter the scattering: they are applied afterwards (``M = 2 rho_p s^3``, the hinge arm ``d + g/2``), and the
equilibrium height is solved anew.  :func:`dimensionless_coefficients` and :func:`scaled_surrogate` are this
map and its inverse; a test checks it against direct solves at two different (s, f) with the same ks.

Family.  Node tables (:class:`~acousim.fullwave.force_surrogate.FullwaveSurrogate`, Chebyshev in theta) are built
on a tensor grid in ``ks`` and in ``log(g/s)`` (:data:`FAMILY_KS`, :data:`FAMILY_GAP_RATIOS`), all on one mesh
rule of :mod:`acousim.fullwave.family_grid` (the hinge-graded :func:`family_mesh_spec`, or the edge-graded mesh at
each gap's level).  Between nodes the dimensionless Chebyshev coefficients are
interpolated by the tensor-product Lagrange polynomial through the nodes, after dividing F_Z's by ks: the
vertical force is a gradient of the field's energy (the Rayleigh limit F ~ ks in these units), while the hinge's
Q_theta comes from the near field between the cubes, whose kinetic energy p0^2/(rho0 c0^2) at the node does not
depend on k (measured: Q_theta in these units changes by 1 % from ks = 0.3 to 0.65, F_Z / ks by 5 %).  Outside the covered rectangle nothing is extrapolated: :class:`FamilyRangeError` names the range
and the command that builds a table for the condition.

Build.  ``python -m acousim family build`` builds the missing nodes through the executor seam
(:func:`cubedimer.executor.map_ordered`), each node written atomically as it finishes, so an interrupted
build resumes from the nodes it has and a dask cluster spreads the nodes over its workers.
"""
from __future__ import annotations

import json
import logging
import os
import time
from dataclasses import replace
from functools import cached_property, lru_cache
from pathlib import Path
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from cubedimer.executor import ExecutorConfig, map_ordered
from cubedimer.meta import DEFAULT_PARTICLE_DENSITY, DEFAULT_PRESSURE_AMPLITUDE_PA

from ..medium import GRAVITY, Medium
from .family_grid import (BUILD_HINT, FAMILY_BUILD, FAMILY_DIR, FAMILY_GAP_RATIOS, FAMILY_KS,
                          MESH_CONVERGENCE_FILE, REFERENCE, FamilyNode, FamilyRangeError, FamilyTableError,
                          family_mesh_spec, family_nodes, node_path)
from .geometry import DimerMeshSpec, hinge_arm, rounded_cube_volume
from .force_surrogate import build_fullwave_surrogate, build_settings_of
from .table import _COMPONENTS, FullwaveSurrogate, _equilibrium_height, _tup

__all__ = [
    "FAMILY_KS", "FAMILY_GAP_RATIOS", "FAMILY_DIR", "FAMILY_BUILD", "REFERENCE",
    "family_mesh_spec", "FamilyNode", "node_path", "family_nodes", "load_node", "force_scale", "build_family_node", "build_family",
    "dimensionless_coefficients", "scaled_surrogate", "FullwaveFamily", "FamilyRangeError", "FamilyTableError",
    "BUILD_HINT", "interpolation_errors", "family_accuracy", "fullwave_surrogate", "shipped_family", "FAMILY_ENV", "DEFAULT_GAP_RATIO",
]

log = logging.getLogger(__name__)


def _matches(sur: FullwaveSurrogate, node: FamilyNode) -> bool:
    exp = node.expected_settings()
    got = build_settings_of(sur)
    for k in exp.keys() | got.keys():  # both ways: a setting keyed only when not its default (flux_disc_points)
        v, g = exp.get(k), got.get(k)
        if isinstance(v, float):
            if g is None or not np.isclose(float(g), v, rtol=1e-9, atol=0.0):
                return False
        elif g != v:
            return False
    return True


def load_node(path: str | os.PathLike, node: FamilyNode | None = None) -> FullwaveSurrogate:
    """Read one node table, refusing a corrupt file or one built with other settings (:class:`FamilyTableError`)."""
    path = Path(path)
    try:
        with open(path) as fh:
            sur = FullwaveSurrogate.from_dict(json.load(fh))
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise FamilyTableError(f"{path}: not a readable full-wave table ({type(exc).__name__}: {exc})") from None
    for comp in _COMPONENTS:
        arr = np.asarray(sur.coefficients.get(comp, ()), dtype=object)
        if arr.size == 0 or not all(np.all(np.isfinite(np.asarray(c, float))) for c in sur.coefficients[comp]):
            raise FamilyTableError(f"{path}: the table's {comp} coefficients are missing or not finite")
    if node is not None and not _matches(sur, node):
        raise FamilyTableError(f"{path}: built with other settings than the family node {node.name} "
                               f"(mesh, medium or theta series differ); rebuild it with {BUILD_HINT}")
    return sur


def build_family_node(node: FamilyNode, directory: str | os.PathLike) -> dict:
    """Build one node's table into ``directory`` unless a matching one is there; returns a summary.

    The table is written atomically when it is complete, so that an interrupted build leaves either the whole
    table or nothing.  Module-level and picklable: the executor seam runs it in worker processes.
    """
    path = node_path(directory, node)
    if path.exists():
        try:
            sur = load_node(path, node)
            return {"node": node.name, "built": False, "wall_s": float(sur.build_accuracy.get("wall_s", 0.0)),
                    "dofs": int(sur.build_accuracy.get("dofs", 0))}
        except FamilyTableError as exc:
            log.warning("%s; rebuilding", exc)
    for name in ("bempp", "numba"):
        logging.getLogger(name).setLevel(logging.WARNING)
    t0 = time.perf_counter()
    sur = build_fullwave_surrogate(node.spec, node.medium, REFERENCE["particle_density_kg_m3"],
                                   REFERENCE["pressure_amplitude_pa"], GRAVITY, node.n_half, node.theta_max,
                                   flux_disc_points=node.flux_disc_points)
    sur.build_accuracy.update(ks=node.ks, gap_ratio=node.gap_ratio, family_node=node.name, mesh_level=node.mesh_level,
                              command=f"{BUILD_HINT} (node {node.name})")
    sur.save(path)
    wall = time.perf_counter() - t0
    log.info("family node %s: %d DOFs, %.0f s", node.name, sur.build_accuracy["dofs"], wall)
    return {"node": node.name, "built": True, "wall_s": wall, "dofs": int(sur.build_accuracy["dofs"])}


def _build_task(item: tuple) -> dict:
    node, directory = item
    return build_family_node(node, directory)


def build_family(directory: str | os.PathLike = FAMILY_DIR, nodes: Sequence[FamilyNode] | None = None,
                 config: ExecutorConfig | None = None, progress: bool = True) -> list[dict]:
    """Build every missing node table of ``nodes`` (default: the whole edge-graded family) into ``directory``.

    Resumable: nodes whose table exists with the right settings are skipped; each finished node is on disk at
    once.  Parallel over nodes through :func:`cubedimer.executor.map_ordered` (local processes or dask); local
    processes are spawned, not forked (``ExecutorConfig.start_method``): a process that has already assembled a
    boundary-element matrix runs GNU OpenMP threads, and forking it kills the pool.
    """
    config = config or ExecutorConfig()
    if config.start_method is None:
        config = replace(config, start_method="spawn")
    nodes = list(nodes if nodes is not None else family_nodes())
    Path(directory).mkdir(parents=True, exist_ok=True)
    done = [n for n in nodes if node_path(directory, n).exists()]
    log.info("family build: %d node(s), %d already on disk in %s", len(nodes), len(done), directory)
    return map_ordered(_build_task, [(n, str(directory)) for n in nodes], config, desc="family nodes",
                       progress=progress)


# ---------------------------------------------------------------------------------------------- scaling
def force_scale(side: float, medium: Medium, pressure_amplitude_pa: float) -> float:
    """p0^2 s^2 / (rho0 c0^2) [N]: the unit of every radiation force of a dimer of side s."""
    return pressure_amplitude_pa**2 * side**2 / (medium.density_kg_m3 * medium.sound_speed_m_s**2)


def dimensionless_coefficients(sur: FullwaveSurrogate) -> dict[str, NDArray[np.float64]]:
    """The table's Chebyshev-in-theta coefficients of (A, B, C) in units of the radiation-force scale.

    ``fz`` in units of p0^2 s^2/(rho0 c0^2), ``qt`` in units of p0^2 s^3/(rho0 c0^2); arrays of shape (3, n).
    """
    s = float(sur.settings["side_m"])
    unit = force_scale(s, sur.medium, sur.pressure_amplitude_pa)
    return {"fz": np.array([np.asarray(c, float) for c in sur.coefficients["fz"]]) / unit,
            "qt": np.array([np.asarray(c, float) for c in sur.coefficients["qt"]]) / (unit * s)}


def scaled_surrogate(coefficients: dict[str, NDArray], theta_max: float, side: float, gap: float,
                     medium: Medium, particle_density: float = DEFAULT_PARTICLE_DENSITY,
                     pressure_amplitude_pa: float = DEFAULT_PRESSURE_AMPLITUDE_PA,
                     gravity: float = GRAVITY, edge_radius: float = 0.0, settings: dict | None = None,
                     build_accuracy: dict | None = None) -> FullwaveSurrogate:
    """The physical surrogate of a dimer of side ``side`` [m] and gap ``gap`` [m] from dimensionless coefficients.

    Inverse of :func:`dimensionless_coefficients` (forces times p0^2 s^2/(rho0 c0^2), torques times one more s),
    with the mass, hinge inertia and equilibrium height of this dimer.  ``medium`` gives k, c0 and rho0.
    """
    unit = force_scale(side, medium, pressure_amplitude_pa)
    coefs = {"fz": tuple(_tup(unit * np.asarray(c)) for c in coefficients["fz"]),
             "qt": tuple(_tup(unit * side * np.asarray(c)) for c in coefficients["qt"])}
    spec_arm = DimerMeshSpec(side=side, gap=gap, edge_radius=edge_radius)
    m = particle_density * rounded_cube_volume(side, edge_radius)
    arm = hinge_arm(spec_arm)
    st = {"side_m": float(side), "gap_m": float(gap), "edge_radius_m": float(edge_radius),
          "frequency_hz": medium.frequency_hz, "sound_speed_m_s": medium.sound_speed_m_s,
          "air_density_kg_m3": medium.density_kg_m3, "particle_density_kg_m3": float(particle_density),
          "theta_max": float(theta_max), "pressure_amplitude_pa": float(pressure_amplitude_pa),
          "gravity_m_s2": float(gravity), "model": "fullwave", "forces": "flux",
          "ks": medium.wavenumber * side, "gap_over_side": gap / side, **(settings or {})}
    sur = FullwaveSurrogate(
        coefficients=coefs, theta_max=float(theta_max), two_k=2 * medium.wavenumber, wavenumber=medium.wavenumber,
        z_eq=-np.pi / (4 * medium.wavenumber), mass=2 * m, gravity=float(gravity),
        inertia_const=(np.pi / 4) ** 2 * 2 * m * side**2 / 6, inertia_sin2=(np.pi / 4) ** 2 * 2 * m * arm**2,
        pressure_amplitude_pa=float(pressure_amplitude_pa), settings=st, build_accuracy=dict(build_accuracy or {}))
    z_eq = _equilibrium_height(sur)
    return replace(sur, z_eq=z_eq, settings=dict(st, equilibrium_height_m=z_eq))


# ---------------------------------------------------------------------------------------------- interpolation
#: What each component is divided by before it is interpolated in ks (see the module docstring).
_KS_POWER = {"fz": lambda ks: ks, "qt": lambda ks: 1.0}

def _lagrange_weights(nodes: NDArray, x: float) -> NDArray[np.float64]:
    """Weights w_i with sum_i w_i f(x_i) the interpolating polynomial through (nodes, f) at x."""
    nodes = np.asarray(nodes, float)
    w = np.ones(nodes.size)
    for i in range(nodes.size):
        for j in range(nodes.size):
            if i != j:
                w[i] *= (x - nodes[j]) / (nodes[i] - nodes[j])
    return w


class FullwaveFamily:
    """The node tables of a directory, interpolated in (ks, log g/s).

    Parameters
    ----------
    directory : path-like
        Holds node tables named by :func:`node_path` (default: the shipped family) and optionally
        ``accuracy.json``, the measured interpolation errors against direct solves between the nodes
        (written by ``python -m acousim family check``).

    The covered region is the largest rectangle of complete rows of the grid: every ks node at a contiguous
    run of gap nodes (a partially built family covers the gaps it has).
    """

    def __init__(self, directory: str | os.PathLike = FAMILY_DIR):
        self.directory = Path(directory)
        tables, quadratures, rules = {}, set(), set()
        for path in sorted(self.directory.glob("ks*_g*.json")):
            sur = load_node(path)
            ba = sur.build_accuracy
            if "ks" not in ba or "gap_ratio" not in ba:
                raise FamilyTableError(f"{path}: not a family node (no ks / gap_ratio in its build record)")
            node = FamilyNode.from_table(sur)
            if path.name != node_path(self.directory, node).name or not _matches(sur, node):
                raise FamilyTableError(f"{path}: its settings do not match its node {node.name} (file renamed or "
                                       f"built with another mesh rule); rebuild it with {BUILD_HINT}")
            tables[(node.ks, node.gap_ratio)] = sur
            quadratures.add(node.flux_disc_points)
            rules.add(node.mesh_level is not None)
        self.tables = tables
        #: True when the nodes are on the edge-graded mesh rule, False on the hinge-graded one (None: no nodes).
        self.edge_graded: bool | None = next(iter(rules)) if len(rules) == 1 else None
        ks = sorted({k for k, _ in tables})
        gaps = sorted({g for _, g in tables})
        complete = [g for g in gaps if all((k, g) in tables for k in ks)]
        # the longest contiguous run of complete gap rows (in the order of the full grid)
        best: list[float] = []
        run: list[float] = []
        for g in gaps:
            if g in complete:
                run.append(g)
                best = max(best, run, key=len)
            else:
                run = []
        self.ks_nodes = tuple(ks) if best else ()
        self.gap_nodes = tuple(best) if self.ks_nodes else ()
        if self.ks_nodes:
            first = tables[(self.ks_nodes[0], self.gap_nodes[0])]
            self.theta_max = float(first.theta_max)
            lengths = {len(np.asarray(t.coefficients["qt"][0])) for t in tables.values()}
            if len(lengths) != 1 or any(t.theta_max != self.theta_max for t in tables.values()):
                raise FamilyTableError(f"{self.directory}: node tables with different theta series")
            if len(rules) != 1:
                raise FamilyTableError(f"{self.directory}: node tables on hinge-graded and on edge-graded meshes mixed; "
                                       f"a family is built on one mesh rule ({BUILD_HINT} --out NEW_DIR)")
            if len(quadratures) != 1:
                raise FamilyTableError(f"{self.directory}: node tables built with different flux quadratures "
                                       f"({sorted(quadratures)} disc points per panel); rebuild them with {BUILD_HINT}")
        acc = self.directory / "accuracy.json"
        try:
            self.accuracy = json.loads(acc.read_text()) if acc.exists() else {}
        except (OSError, ValueError) as exc:
            raise FamilyTableError(f"{acc}: not readable ({type(exc).__name__}: {exc}); rerun python -m acousim "
                                   f"family check") from None
        mesh = self.directory / MESH_CONVERGENCE_FILE
        try:
            rows = json.loads(mesh.read_text())["gap_rows"] if mesh.exists() else []
            self.mesh_errors: dict[float, float] = {float(r["gap_over_side"]): float(r["stated_error"]) for r in rows}
        except (OSError, ValueError, KeyError, TypeError) as exc:
            raise FamilyTableError(f"{mesh}: not readable ({type(exc).__name__}: {exc})") from None

    # -------------------------------------------------------------------------------- coverage
    @property
    def empty(self) -> bool:
        return not self.ks_nodes

    def ranges(self) -> tuple[tuple[float, float], tuple[float, float]] | None:
        """((ks_min, ks_max), (g/s min, g/s max)) covered, or None."""
        if self.empty:
            return None
        return (self.ks_nodes[0], self.ks_nodes[-1]), (self.gap_nodes[0], self.gap_nodes[-1])

    def describe_range(self) -> str:
        r = self.ranges()
        if r is None:
            return "no complete row of nodes is built"
        (k0, k1), (g0, g1) = r
        if g0 == g1:
            return f"ks {k0:.3g}-{k1:.3g} at g/s = {g0:.3g}"
        return f"ks {k0:.3g}-{k1:.3g} and g/s {g0:.3g}-{g1:.3g}"

    def check_covers(self, ks: float, gap_ratio: float) -> None:
        """Raise :class:`FamilyRangeError` (one line, naming the range and the build command) when (ks, g/s)
        lies outside the covered rectangle.  Never extrapolates."""
        r = self.ranges()
        tol = 1e-6
        inside = r is not None and (r[0][0] * (1 - tol) <= ks <= r[0][1] * (1 + tol)) and (
            r[1][0] * (1 - tol) <= gap_ratio <= r[1][1] * (1 + tol))
        if not inside:
            raise FamilyRangeError(
                f"ks = {ks:.4g}, g/s = {gap_ratio:.4g} lies outside the full-wave family ({self.describe_range()}); "
                f"build a table for it with {BUILD_HINT} --ks {ks:.4g} --gap-ratio {gap_ratio:.4g} --out DIR and set "
                f"CUBEDIMER_FULLWAVE_FAMILY=DIR")

    # -------------------------------------------------------------------------------- evaluation
    @cached_property
    def _reduced(self) -> dict[str, NDArray[np.float64]]:
        """The interpolated quantities: dimensionless coefficients (F_Z's over ks), shape (n_ks, n_gap, 3, n_terms)."""
        return {comp: np.array([[dimensionless_coefficients(self.tables[(k, g)])[comp] / _KS_POWER[comp](k)
                                 for g in self.gap_nodes] for k in self.ks_nodes]) for comp in _COMPONENTS}

    def dimensionless(self, ks: float, gap_ratio: float) -> dict[str, NDArray[np.float64]]:
        """Interpolated dimensionless coefficients (as :func:`dimensionless_coefficients`) at (ks, g/s)."""
        self.check_covers(ks, gap_ratio)
        wk = _lagrange_weights(np.array(self.ks_nodes), ks)
        wg = _lagrange_weights(np.log(np.array(self.gap_nodes)), np.log(gap_ratio)) if len(self.gap_nodes) > 1 \
            else np.ones(1)
        return {c: _KS_POWER[c](ks) * np.einsum("i,j,ijkl->kl", wk, wg, self._reduced[c]) for c in _COMPONENTS}

    def mesh_error(self, gap_ratio: float) -> float | None:
        """The stated mesh error of the hinge stiffness at ``gap_ratio`` (fraction): the larger of the two gap rows
        around it (``mesh_convergence.json``, docs/fullwave.md); None when a row has no study."""
        g = np.array(self.gap_nodes)
        around = g[(g >= gap_ratio * (1 - 1e-9)) & (g <= gap_ratio * (1 + 1e-9))]
        if around.size == 0:
            i = int(np.clip(np.searchsorted(g, gap_ratio), 1, g.size - 1))
            around = g[i - 1:i + 1]
        errors = [next((e for r, e in self.mesh_errors.items() if np.isclose(r, v, rtol=1e-4)), None) for v in around]
        return None if not errors or any(e is None for e in errors) else max(errors)

    def surrogate(self, side: float, gap: float, medium: Medium = Medium(),
                  particle_density: float = DEFAULT_PARTICLE_DENSITY,
                  pressure_amplitude_pa: float = DEFAULT_PRESSURE_AMPLITUDE_PA, gravity: float = GRAVITY) -> FullwaveSurrogate:
        """The full-wave surrogate of a dimer of side ``side`` [m] with hinge gap ``gap`` [m] in ``medium``.

        Raises :class:`FamilyRangeError` outside the family.  The result's ``build_accuracy`` states the family's
        measured interpolation accuracy (``accuracy.json``) and the node tables used.
        """
        ks = medium.wavenumber * side
        ratio = gap / side
        coefs = self.dimensionless(ks, ratio)
        on_node = any(np.isclose(ks, k, rtol=1e-9) and np.isclose(ratio, g, rtol=1e-9) for k, g in self.tables)
        acc = {"source": "family node" if on_node else "family interpolation", "family": str(self.directory),
               "family_range": self.describe_range(), "nodes_ks": list(self.ks_nodes),
               "nodes_gap_over_side": list(self.gap_nodes)}
        summary = self.accuracy.get("summary", {})
        if summary:
            acc["interpolation_error"] = summary
        stated = {"table_source": acc["source"], "family_range": acc["family_range"],
                  "interpolation_error_q_y": summary.get("q_y"), "interpolation_error_q_theta": summary.get("q_theta"),
                  "interpolation_error_hinge_stiffness": summary.get("stiffness"),
                  "mesh_error_hinge_stiffness": self.mesh_error(ratio)}
        return scaled_surrogate(coefs, self.theta_max, side, gap, medium, particle_density, pressure_amplitude_pa,
                                gravity, settings={"n_half": len(coefs["qt"][0]) // 2, "family": True, **stated},
                                build_accuracy=acc)


# ---------------------------------------------------------------------------------------------- the model of a lab
#: Environment variable naming another family directory (e.g. one built with ``python -m acousim family build``).
FAMILY_ENV = "CUBEDIMER_FULLWAVE_FAMILY"
#: The default hinge gap as a fraction of the side (docs/conventions.md).
DEFAULT_GAP_RATIO = 0.01


@lru_cache(maxsize=4)
def _family(directory: str) -> FullwaveFamily:
    return FullwaveFamily(directory)


def shipped_family() -> FullwaveFamily:
    """The family of ``$CUBEDIMER_FULLWAVE_FAMILY`` if set, else the shipped one (read once per process)."""
    return _family(os.environ.get(FAMILY_ENV) or str(FAMILY_DIR))


@lru_cache(maxsize=1)
def _default_table_settings() -> dict:
    from .force_surrogate import DEFAULT_TABLE

    with open(DEFAULT_TABLE) as fh:
        return json.load(fh)["settings"]


def _is_default_dimer(side: float, gap: float, medium: Medium, density: float, gravity: float) -> bool:
    st = _default_table_settings()
    pairs = ((side, st["side_m"]), (gap, st["gap_m"]), (medium.frequency_hz, st["frequency_hz"]),
             (medium.sound_speed_m_s, st["sound_speed_m_s"]), (medium.density_kg_m3, st["air_density_kg_m3"]),
             (density, st["particle_density_kg_m3"]), (gravity, st["gravity_m_s2"]))
    return all(np.isclose(a, b, rtol=1e-6, atol=0.0) for a, b in pairs)


def fullwave_surrogate(conditions) -> FullwaveSurrogate:
    """The full-wave surrogate of an experiment (:class:`acousim.models.ExperimentConditions`).

    The default dimer (500 um, 45.65 kHz, g = 0.01 s, the default air) is its own direct-solve table
    (``acousim/data/fullwave_default.json``, 7 solves); every other dimer is scaled from the family
    (:class:`FullwaveFamily`, interpolated between its nodes with the accuracy it states).

    Raises
    ------
    FamilyRangeError
        Rounded edges (no tables), or (ks, g/s) outside the family: one line naming the range and the build command.
    """
    from .force_surrogate import default_fullwave_surrogate

    c = conditions
    side = float(c.side_length_m)
    gap = float(c.gap_m) if c.gap_m is not None else DEFAULT_GAP_RATIO * side
    if c.edge_radius_m:
        raise FamilyRangeError(f"--edge-radius = {c.edge_radius_m:g} m: only sharp-edged tables are shipped; build "
                               f"one with python -m acousim table --edge-radius R --side S --gap G --out FILE")
    medium = c.medium
    density, gravity, p0 = float(c.particle_density_kg_m3), float(c.gravity_m_s2), float(c.pressure_amplitude_pa)
    if _is_default_dimer(side, gap, medium, density, gravity):
        sur = default_fullwave_surrogate(p0)
        source = "direct-solve table of the default dimer"
        # built on the shipped family's mesh at g = 0.01 s: that row's error, whatever family the environment names
        mesh_error = _family(str(FAMILY_DIR)).mesh_error(DEFAULT_GAP_RATIO)
        return replace(sur, build_accuracy={**sur.build_accuracy, "source": source},
                       settings={**sur.settings, "table_source": source, "mesh_error_hinge_stiffness": mesh_error})
    return shipped_family().surrogate(side, gap, medium, density, p0, gravity)


# ---------------------------------------------------------------------------------------------- accuracy
def interpolation_errors(family: FullwaveFamily, check: FullwaveSurrogate, n_theta: int = 37,
                         y: NDArray | None = None) -> dict:
    """The family against a direct-solve table ``check`` built between its nodes (or any table it covers).

    Both are evaluated at the check's own dimer (side, gap, medium, density, pressure) on ``n_theta`` bends over
    |theta| <= theta_max and heights ``y`` [m] above the check's Z_eq (default -1.0 to +0.8 mm, the box of the
    surrogate study).

    Returns
    -------
    dict
        ``ks``, ``gap_over_side``; ``q_y`` and ``q_theta``: the largest error relative to max |Q| over the box;
        ``q_theta_inner``: the same for Q_theta over the inner 80 % of the theta range; ``f_y`` and ``f_theta``:
        relative errors of the small-oscillation frequencies; ``stiffness``: relative
        error of dQ_theta/dtheta at the equilibrium.
    """
    st = check.settings
    side, gap = float(st["side_m"]), float(st["gap_m"])
    fam = family.surrogate(side, gap, check.medium, float(st.get("particle_density_kg_m3", DEFAULT_PARTICLE_DENSITY)),
                           check.pressure_amplitude_pa, check.gravity)
    y = np.linspace(-1.0e-3, 0.8e-3, 19) if y is None else np.asarray(y, float)
    tm = min(check.theta_max, family.theta_max)
    tt, yy = np.meshgrid(np.linspace(-tm, tm, n_theta), y, indexing="ij")
    z = yy + check.z_eq
    (qy_c, qt_c), (qy_f, qt_f) = check.generalized_forces(tt, z - check.z_eq), fam.generalized_forces(tt, z - fam.z_eq)
    fc, ff = check.linear_frequencies(), fam.linear_frequencies()
    th_c, y_c = check.equilibrium()
    th_f, y_f = fam.equilibrium()
    k_c, k_f = check._jacobian(th_c, y_c)[1, 0], fam._jacobian(th_f, y_f)[1, 0]
    inner = np.abs(tt[:, 0]) <= 0.8 * tm + 1e-12  # away from the interval's ends (the folding barrier)
    return {"ks": check.wavenumber * side, "gap_over_side": gap / side,
            "q_y": float(np.max(np.abs(qy_f - qy_c)) / np.max(np.abs(qy_c))),
            "q_theta": float(np.max(np.abs(qt_f - qt_c)) / np.max(np.abs(qt_c))),
            "q_theta_inner": float(np.max(np.abs(qt_f - qt_c)[inner]) / np.max(np.abs(qt_c))),
            "f_y": float(ff[0] / fc[0] - 1), "f_theta": float(ff[1] / fc[1] - 1), "stiffness": float(k_f / k_c - 1),
            "check_solves": int(st.get("n_half", 0))}


def family_accuracy(family: FullwaveFamily, checks: Sequence[FullwaveSurrogate]) -> dict:
    """:func:`interpolation_errors` of every check the family covers, and their maxima (``summary``).

    A check on the other mesh rule than the family's (hinge-graded against edge-graded) is skipped with a warning:
    it would measure the mesh difference (3-11 % in the hinge torque), not the interpolation."""
    rule = {True: "edge-graded", False: "hinge-graded"}
    rows = []
    for c in checks:
        ks, g = c.wavenumber * float(c.settings["side_m"]), float(c.settings["gap_m"]) / float(c.settings["side_m"])
        edge_graded = c.settings.get("h_edge") is not None  # keyed only on the edge-graded rule
        if family.edge_graded is not None and edge_graded != family.edge_graded:
            log.warning("check table at ks %.4f, g/s %.4f skipped: built on the %s mesh rule, the family on the %s one",
                        ks, g, rule[edge_graded], rule[family.edge_graded])
            continue
        try:
            family.check_covers(ks, g)
        except FamilyRangeError:
            continue
        rows.append(interpolation_errors(family, c))
    summary = {"q_y": max((r["q_y"] for r in rows), default=None),
               "q_theta": max((r["q_theta"] for r in rows), default=None),
               "q_theta_inner": max((r["q_theta_inner"] for r in rows), default=None),
               "f_theta": max((abs(r["f_theta"]) for r in rows), default=None),
               "stiffness": max((abs(r["stiffness"]) for r in rows), default=None), "n_checks": len(rows),
               "family_range": family.describe_range(),
               "note": "the largest errors of the family's interpolation against direct-solve tables between its "
                       "nodes, relative to max |Q| over |theta| <= 0.9 and y -1.0..+0.8 mm (docs/fullwave.md)"}
    return {"checks": rows, "summary": summary}
