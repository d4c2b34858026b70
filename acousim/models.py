"""The force models: one interface, one registry.

Every command that simulates the dimer (``acousim sweep``, ``acousim simulate``, ``validation diagnose``,
``validation report``) gets its model here, by name, from the experiment's conditions
(:class:`ExperimentConditions`: the options or meta.json).  A model type (:class:`ForceModelType`) gives two
views of the same physics:

* the **static model** (:class:`acousim.static_model.StaticModel`): forces at absolute heights above the node, what the static
  sweep and the sim-to-real diagnosis evaluate at every frame (:class:`acousim.GorkovDimer`,
  :class:`acousim.fullwave.FullwaveDimer`);
* the **force model** (:class:`acousim.ForceModel`): the height structure ``A + B cos 2kZ + C sin 2kZ`` with
  Chebyshev-in-theta coefficients that the equations of motion and the twin integrate.

A new force model is one module defining its two builders and one :func:`register_force_model` call (see
docs/architecture.md); the commands' ``--model`` choices are :func:`force_model_names`, and no module outside
this one branches on a model's name.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, fields, replace
from typing import Callable, ClassVar, Mapping
from cubedimer.meta import (DEFAULT_AIR_DENSITY_KG_M3, DEFAULT_BULK_MODULUS_PA, DEFAULT_FREQUENCY_HZ,
                            DEFAULT_PARTICLE_DENSITY, DEFAULT_PRESSURE_AMPLITUDE_PA, DEFAULT_SIDE_LENGTH_M,
                            DEFAULT_SOUND_SPEED_M_S)

from .force_model import ForceModel
from .medium import GRAVITY, Medium, ParticleMaterial
from .static_model import StaticModel

__all__ = ["ExperimentConditions", "ForceModelType", "FORCE_MODEL_TYPES", "register_force_model",
           "force_model_type", "force_model_names", "static_model", "dynamic_model", "ConditionError", "ModelSpec",
           "ModelOption", "REGISTERED_MODEL_OPTIONS", "register_model_option", "model_options"]


class ConditionError(ValueError):
    """An experimental condition the chosen model cannot take (a gap with the Gor'kov model, a dimer outside the
    full-wave family...); one line naming the condition."""


#: How each condition is named on the command line (for one-line errors).
OPTION_NAMES = {"side_length_m": "--side", "frequency_hz": "--frequency", "gap_m": "--gap",
                "edge_radius_m": "--edge-radius", "mesh_size_m": "--mesh-size", "side_b_m": "--side-b",
                "pressure_amplitude_pa": "--pressure", "particle_density_kg_m3": "--density",
                "quadrature_degree": "--quadrature-degree"}
#: The built-in model-specific conditions, fields of :class:`ExperimentConditions` (each model type takes some of
#: them, :attr:`ForceModelType.options`); :func:`model_options` adds the registered ones.
MODEL_OPTIONS = ("gap_m", "edge_radius_m", "mesh_size_m", "side_b_m", "quadrature_degree")


@dataclass(frozen=True)
class ModelOption:
    """A model option registered beyond the built-in fields (:func:`register_model_option`).

    Parameters
    ----------
    name : str
        The key (with its SI unit, e.g. ``"gap_m"``): in :class:`ModelSpec` options, in
        :meth:`ExperimentConditions.option`, in a model type's ``options`` and in truth.json.
    flag : str
        Its command-line option (``"--gap"``), offered by every command with ``--model``
        (:func:`acousim.cli.model_options.add_model_arguments`).
    help : str
        The option's help line (what it is, its unit, its default).
    metavar : str
        The value's name in the help.
    """

    name: str
    flag: str
    help: str
    metavar: str = "VALUE"


#: Registered model options by name, in registration order (:func:`register_model_option`).
REGISTERED_MODEL_OPTIONS: dict[str, ModelOption] = {}


def register_model_option(option: ModelOption) -> ModelOption:
    """Add a model option: every command with ``--model`` offers ``option.flag``, every :class:`ModelSpec` carries it
    to the conditions its model is built for (:meth:`ExperimentConditions.option`), a model type takes it by listing
    ``option.name`` in its ``options``, and the twin records it in truth.json.  A finite value > 0."""
    if option.name in MODEL_OPTIONS or option.name in {f.name for f in fields(ExperimentConditions)}:
        raise ValueError(f"{option.name!r} is a field of ExperimentConditions already")
    REGISTERED_MODEL_OPTIONS[option.name] = option
    OPTION_NAMES[option.name] = option.flag
    return option


def model_options() -> tuple[str, ...]:
    """Every model-specific condition: the built-in :data:`MODEL_OPTIONS` and the registered ones."""
    return MODEL_OPTIONS + tuple(REGISTERED_MODEL_OPTIONS)


@dataclass(frozen=True)
class ExperimentConditions:
    """The experiment a model is built for (SI units; defaults of the README's conventions, docs/conventions.md).

    ``gap_m`` and ``edge_radius_m`` describe the hinge of the full-wave model (None: its default, 0.01 s and
    sharp edges); ``mesh_size_m`` and ``side_b_m`` belong to the Gor'kov volume model (None: its defaults).
    ``extra_options`` holds the registered model options that are set (:func:`register_model_option`; read them with
    :meth:`option`).  A model refuses conditions it does not take (:attr:`ForceModelType.options`).
    """

    side_length_m: float = DEFAULT_SIDE_LENGTH_M
    particle_density_kg_m3: float = DEFAULT_PARTICLE_DENSITY
    bulk_modulus_pa: float = DEFAULT_BULK_MODULUS_PA
    frequency_hz: float = DEFAULT_FREQUENCY_HZ
    sound_speed_m_s: float = DEFAULT_SOUND_SPEED_M_S
    air_density_kg_m3: float = DEFAULT_AIR_DENSITY_KG_M3
    pressure_amplitude_pa: float = DEFAULT_PRESSURE_AMPLITUDE_PA
    gravity_m_s2: float = GRAVITY
    gap_m: float | None = None
    edge_radius_m: float | None = None
    mesh_size_m: float | None = None
    side_b_m: float | None = None
    quadrature_degree: int | None = None
    #: the registered model options that are set (:func:`register_model_option`), ``((name, value), ...)``
    extra_options: tuple = ()

    def __post_init__(self) -> None:
        extra = tuple(sorted((str(k), v) for k, v in dict(self.extra_options).items() if v is not None))
        object.__setattr__(self, "extra_options", extra)
        unknown = [name for name, _ in extra if name not in REGISTERED_MODEL_OPTIONS]
        if unknown:
            raise ConditionError(f"{', '.join(map(repr, unknown))} is not a condition or a registered model option "
                                 "(acousim.models.register_model_option)")
        for name, value in (*((k, v) for k, v in asdict(self).items() if k != "extra_options"), *extra):
            if value is None:
                continue
            if not math.isfinite(float(value)):
                raise ConditionError(f"{OPTION_NAMES.get(name, name)} = {value!r} is not finite")
            if name == "quadrature_degree":
                if int(value) != value or value < 2:
                    raise ConditionError(f"--quadrature-degree must be an integer of at least 2, got {value!r}")
            elif name == "edge_radius_m":
                if value < 0:
                    raise ConditionError(f"--edge-radius = {value!r} m must be >= 0")
            elif value <= 0:
                raise ConditionError(f"{OPTION_NAMES.get(name, name)} = {value!r} must be positive")
        if self.gap_m is not None and self.gap_m > 0.5 * self.side_length_m:
            raise ConditionError(f"--gap = {self.gap_m:g} m is more than half the side ({self.side_length_m:g} m)")

    #: The meta.json keys (docs/formats.md) that map one to one onto fields.
    META_FIELDS: ClassVar[tuple[str, ...]] = ("side_length_m", "particle_density_kg_m3", "bulk_modulus_pa",
                                              "frequency_hz", "sound_speed_m_s", "air_density_kg_m3",
                                              "pressure_amplitude_pa")

    @classmethod
    def from_meta(cls, meta: dict | None = None, **overrides) -> "ExperimentConditions":
        """Conditions of a data set's meta.json (missing keys: defaults), with ``overrides`` (None values ignored;
        registered model options among them go to :attr:`extra_options`)."""
        values = {k: float(v) for k, v in (meta or {}).items() if k in cls.META_FIELDS and v is not None}
        values.update({k: v for k, v in overrides.items() if v is not None})
        return cls().with_options(**values)

    def with_options(self, **values) -> "ExperimentConditions":
        """These conditions with ``values`` set: fields by name, registered model options (:func:`register_model_option`)
        into :attr:`extra_options` (None values ignored)."""
        own = {f.name for f in fields(self)} - {"extra_options"}
        extra = {k: v for k, v in values.items() if k not in own and v is not None}
        return replace(self, **{k: v for k, v in values.items() if k in own and v is not None},
                       extra_options=tuple({**dict(self.extra_options), **extra}.items()))

    def option(self, name: str):
        """The value of the model option ``name`` (a field, or a registered option; None when unset)."""
        return getattr(self, name) if name in MODEL_OPTIONS else dict(self.extra_options).get(name)

    @property
    def medium(self) -> Medium:
        return Medium(frequency_hz=self.frequency_hz, sound_speed_m_s=self.sound_speed_m_s,
                      density_kg_m3=self.air_density_kg_m3)

    @property
    def material(self) -> ParticleMaterial:
        return ParticleMaterial(density_kg_m3=self.particle_density_kg_m3, bulk_modulus_pa=self.bulk_modulus_pa)

    @property
    def ks(self) -> float:
        """Wavenumber times side (dimensionless)."""
        return self.medium.wavenumber * self.side_length_m

    def with_pressure(self, pressure_amplitude_pa: float) -> "ExperimentConditions":
        return replace(self, pressure_amplitude_pa=float(pressure_amplitude_pa))


@dataclass(frozen=True)
class ForceModelType:
    """One registered force model.

    Parameters
    ----------
    name : str
        The ``--model`` value.
    summary : str
        One line for ``--help``.
    label : str
        The model's name in tables and prose (e.g. ``"Gor'kov"``).
    static : callable
        ``static(conditions) -> StaticModel``.
    dynamic : callable
        ``dynamic(conditions) -> ForceModel`` (for the equations of motion and the twin).
    options : frozenset of str
        The model-specific :class:`ExperimentConditions` fields it takes (others must be None).
    capabilities : frozenset of str
        What else it offers: ``"render"`` (a volume mesh to draw), ``"potential"`` (forces from a potential).
    calibratable : callable, optional
        ``calibratable(conditions) -> {field: (lo, hi, default)}``: model parameters (fields of
        :class:`ExperimentConditions`) that the data may determine, with the range the model covers and the value
        it takes when they do not (the full-wave hinge gap); the diagnosis profiles each one the user left unset.
    parameter_model_error : callable, optional
        ``parameter_model_error(conditions) -> {field: fraction}``: the relative error of each calibratable
        parameter at ``conditions`` that the model's own stated error implies (a systematic error that no amount of
        data reduces: the full-wave gap inherits the family's stated hinge-stiffness error through the stiffness's
        logarithmic sensitivity to the gap); a field may map to None when the model states no error there.
    """

    name: str
    summary: str
    label: str
    static: Callable[[ExperimentConditions], StaticModel]
    dynamic: Callable[[ExperimentConditions], ForceModel]
    options: frozenset = field(default_factory=frozenset)
    capabilities: frozenset = field(default_factory=frozenset)
    calibratable: Callable[[ExperimentConditions], dict] | None = None
    parameter_model_error: Callable[[ExperimentConditions], dict] | None = None

    def calibration_ranges(self, conditions: ExperimentConditions) -> dict[str, tuple[float, float, float]]:
        """``{field: (lo, hi, default)}`` of the parameters the data may determine ({} for none)."""
        return {} if self.calibratable is None else dict(self.calibratable(conditions))

    def check(self, conditions: ExperimentConditions) -> None:
        """Refuse model-specific conditions this model does not take (one line naming the option)."""
        for name in model_options():
            if conditions.option(name) is not None and name not in self.options:
                takers = [t.name for t in FORCE_MODEL_TYPES.values() if name in t.options]
                raise ConditionError(f"{OPTION_NAMES[name]} applies to --model {' / '.join(takers) or '(none)'} only, "
                                     f"not to --model {self.name}")


#: The registry: model name -> :class:`ForceModelType`.
FORCE_MODEL_TYPES: dict[str, ForceModelType] = {}


def register_force_model(model_type: ForceModelType) -> ForceModelType:
    """Add a model type to the registry (its name becomes a ``--model`` choice everywhere)."""
    FORCE_MODEL_TYPES[model_type.name] = model_type
    return model_type


def force_model_names() -> tuple[str, ...]:
    """The registered model names, in registration order (the first is the default)."""
    return tuple(FORCE_MODEL_TYPES)


def force_model_type(name: str) -> ForceModelType:
    """The registered type called ``name`` (:class:`ConditionError` naming the choices otherwise)."""
    try:
        return FORCE_MODEL_TYPES[name]
    except KeyError:
        raise ConditionError(f"unknown force model {name!r}; choose one of {', '.join(FORCE_MODEL_TYPES)}") from None


def static_model(name: str, conditions: ExperimentConditions) -> StaticModel:
    """The static model ``name`` of ``conditions`` (checked first; :class:`ConditionError` on a misfit)."""
    t = force_model_type(name)
    t.check(conditions)
    return t.static(conditions)


def dynamic_model(name: str, conditions: ExperimentConditions) -> ForceModel:
    """The force model ``name`` of ``conditions`` for the equations of motion (checked first)."""
    t = force_model_type(name)
    t.check(conditions)
    return t.dynamic(conditions)


@dataclass(frozen=True)
class ModelSpec:
    """A chosen force model: its registry entry and its own options, checked on construction.

    The one object that carries a model choice through a command (instead of a name and loose keyword arguments):
    the experiment itself (side, material, frequency, pressure) comes from the data set's meta.json or the options
    where the model is built, :meth:`conditions`; the model's own options (the :func:`model_options` it takes,
    e.g. the full-wave hinge gap) travel here.  A new model with a new option needs no change where a spec travels.

    Parameters
    ----------
    name : str, optional
        A registered model name (default: the first registered, the Gor'kov model).
    options : mapping, optional
        ``{name: value}`` of :func:`model_options` (None values are left out); an option the model does not take
        is refused with one line naming the option.
    """

    name: str | None = None
    options: Mapping[str, float] | tuple = ()

    def __post_init__(self) -> None:
        name = self.name if self.name is not None else force_model_names()[0]
        items = self.options.items() if isinstance(self.options, Mapping) else self.options
        options = tuple(sorted((str(k), v) for k, v in items if v is not None))
        object.__setattr__(self, "name", name)
        object.__setattr__(self, "options", options)
        t = force_model_type(name)
        for k, _ in options:
            if k not in model_options():
                raise ConditionError(f"{k!r} is not a model option (one of {', '.join(model_options())})")
        t.check(ExperimentConditions().with_options(**dict(options)))

    @property
    def type(self) -> ForceModelType:
        """The registry entry."""
        return force_model_type(self.name)

    @property
    def label(self) -> str:
        """The model's name in tables and prose."""
        return self.type.label

    @property
    def option_values(self) -> dict[str, float]:
        """``{field: value}`` of the options that are set."""
        return dict(self.options)

    def conditions(self, meta: Mapping | None = None, **overrides) -> ExperimentConditions:
        """The experiment of ``meta`` (missing keys: the defaults) with this model's options and ``overrides``
        (None values ignored)."""
        return ExperimentConditions.from_meta(meta, **{**self.option_values, **overrides})

    def static(self, conditions: ExperimentConditions) -> StaticModel:
        """The static model at ``conditions`` (checked first; :class:`ConditionError` on a misfit)."""
        return static_model(self.name, conditions)

    def dynamic(self, conditions: ExperimentConditions) -> ForceModel:
        """The force model of the equations of motion at ``conditions`` (checked first)."""
        return dynamic_model(self.name, conditions)


# ---------------------------------------------------------------------------------------------- Gor'kov
def _gorkov_static(c: ExperimentConditions):
    from .dimer import CubeDimer
    from .field import StandingWave
    from .gorkov.forces import DEFAULT_QUADRATURE_DEGREE, GorkovDimer

    smallest = min(c.side_length_m, c.side_b_m or c.side_length_m)
    if c.mesh_size_m is not None and not 0.01 <= c.mesh_size_m / smallest <= 1.0:
        raise ConditionError(f"--mesh-size {c.mesh_size_m:g} m must be between 0.01 and 1 times the cube side")
    dimer = CubeDimer(c.side_length_m, c.side_b_m, c.material)
    model = GorkovDimer(dimer, StandingWave(c.pressure_amplitude_pa, c.medium, c.material), mesh_size=c.mesh_size_m,
                        quadrature_degree=c.quadrature_degree or DEFAULT_QUADRATURE_DEGREE, gravity=c.gravity_m_s2)
    model.equilibrium_height  # noqa: B018 (raises ValueError when the field cannot levitate the dimer)
    return model


def _gorkov_dynamic(c: ExperimentConditions):
    from .gorkov.energy_surrogate import build_surrogate, cached_surrogate

    if c.side_b_m is not None and c.side_b_m != c.side_length_m:
        raise ConditionError("--side-b: the equations of motion take equal cubes only")
    default_air = ExperimentConditions(side_length_m=c.side_length_m, pressure_amplitude_pa=c.pressure_amplitude_pa,
                                       mesh_size_m=c.mesh_size_m)
    if c == default_air:  # cached per process (the twin's usual case)
        return cached_surrogate(float(c.side_length_m), float(c.pressure_amplitude_pa), c.mesh_size_m)
    return build_surrogate(_gorkov_static(c))


register_force_model(ForceModelType(
    "gorkov", "the Gor'kov volume integral over tetrahedral meshes of the two cubes (small-particle limit)",
    "Gor'kov", _gorkov_static, _gorkov_dynamic, frozenset({"mesh_size_m", "side_b_m", "quadrature_degree"}),
    frozenset({"render", "potential"})))


# ---------------------------------------------------------------------------------------------- full wave
def _fullwave_dynamic(c: ExperimentConditions):
    from .fullwave.family import fullwave_surrogate

    return fullwave_surrogate(c)


def _fullwave_static(c: ExperimentConditions):
    from .fullwave.statics import FullwaveDimer

    return FullwaveDimer(_fullwave_dynamic(c))


#: Relative step in the gap of the hinge stiffness's logarithmic sensitivity d ln k / d ln g.
GAP_SENSITIVITY_STEP = 0.05


def _fullwave_gap_model_error(c: ExperimentConditions) -> dict:
    """The gap's relative error implied by the stated error e of the hinge stiffness k at the dimer's gap (the
    family's mesh error plus its interpolation error): e / |d ln k / d ln g|, the derivative by central differences
    over +-5 % in g (one-sided at an end of the family's range); None when the family states no mesh error there."""
    lo, hi, _ = _fullwave_gap_range(c)["gap_m"]
    g = float(c.gap_m)
    sur = _fullwave_dynamic(c)
    mesh, interp = sur.settings.get("mesh_error_hinge_stiffness"), sur.settings.get("interpolation_error_hinge_stiffness")
    if mesh is None:
        return {"gap_m": None}
    g_up, g_dn = min(g * (1 + GAP_SENSITIVITY_STEP), hi), max(g * (1 - GAP_SENSITIVITY_STEP), lo)
    k_up, k_dn = (abs(_fullwave_dynamic(replace(c, gap_m=v)).hinge_stiffness()) for v in (g_up, g_dn))
    slope = abs(math.log(k_up / k_dn) / math.log(g_up / g_dn))
    error = float(mesh) + float(interp or 0.0)
    return {"gap_m": error / slope if slope > 0 else float("inf")}


def _fullwave_gap_range(c: ExperimentConditions) -> dict:
    """The hinge gaps [m] the shipped family covers at this dimer's ks, and the gap the model takes when the data
    do not determine it: 0.01 s (the default dimer's direct table, or inside the family), else the covered gap
    nearest to it."""
    from .fullwave.family import DEFAULT_GAP_RATIO, _is_default_dimer, shipped_family

    fam = shipped_family()
    fam.check_covers(c.ks, fam.ranges()[1][0] if fam.ranges() else DEFAULT_GAP_RATIO)
    (_, _), (g0, g1) = fam.ranges()
    s = c.side_length_m
    default = DEFAULT_GAP_RATIO * s
    if not _is_default_dimer(s, default, c.medium, c.particle_density_kg_m3, c.gravity_m_s2):
        default = min(max(default, g0 * s), g1 * s)
    return {"gap_m": (g0 * s, g1 * s, default)}


register_force_model(ForceModelType(
    "fullwave", "the full-wave (boundary-element) scattering by both cubes, from the table family over (ks, g/s)",
    "full wave", _fullwave_static, _fullwave_dynamic, frozenset({"gap_m", "edge_radius_m"}), calibratable=_fullwave_gap_range,
    parameter_model_error=_fullwave_gap_model_error))
