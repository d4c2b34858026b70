"""Settings of the digital twin: the field-drop protocol, the camera, a data set's configuration and presets.

:class:`DropProtocol` (how each run is started), :class:`Camera` (frame rate, tracking noise, missing
frames), :class:`TwinConfig` (every setting of a synthetic data set) and :class:`TwinPreset` with
:data:`PAPER_LIKE`, the effect set and protocol documented in ``docs/twin.md`` that reproduces what it
can of the source paper's dynamics.  Every configuration object validates itself and raises
:class:`TwinError` with a one-line message.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from cubedimer.config_checks import (check_in_range, check_non_negative, check_positive, check_that, check_whole, named,
                                    raising)
from cubedimer.meta import DEFAULT_TRACKING_NOISE

from ..dynamics.integrator import DEFAULT_MAX_STEP
from ..dynamics.resonator import DEFAULT_CAVITY_AREA, CavityMode
from ..dynamics.effects import EffectSet, LinearDamping, MirrorAsymmetry, PairScattering
from ..fullwave.statics import MODEL_NAME as FULLWAVE
from ..models import ExperimentConditions, ModelSpec, force_model_names, model_options

__all__ = ["TwinError", "DropProtocol", "Camera", "TwinConfig", "TwinPreset", "PAPER_LIKE", "PAPER", "WINDOW_RESONATOR",
           "PRESETS"]


class TwinError(ValueError):
    """A twin setting or run that cannot be simulated; ``str(err)`` is one line."""


def _range(name: str, r: Sequence[float], low: float | None = None, high: float | None = None,
           strict_low: bool = False) -> tuple[float, float]:
    try:
        a, b = (float(v) for v in r)
    except (TypeError, ValueError):
        raise TwinError(f"{name} must be a (min, max) pair of numbers, got {r!r}") from None
    if not (np.isfinite(a) and np.isfinite(b)) or a > b:
        raise TwinError(f"{name} must be finite with min <= max, got ({a:g}, {b:g})")
    if low is not None and (a < low or (strict_low and a <= low)):
        raise TwinError(f"{name} must be {'>' if strict_low else '>='} {low:g}, got ({a:g}, {b:g})")
    if high is not None and b > high:
        raise TwinError(f"{name} must be <= {high:g}, got ({a:g}, {b:g})")
    return a, b


@dataclass(frozen=True)
class DropProtocol:
    """The field-drop protocol; every quantity is drawn uniformly from its (min, max) range per run.

    Parameters
    ----------
    t_off : (float, float)
        Time the field is off [s].  The dimer falls g t_off^2 / 2 and starts at g t_off downwards;
        at the defaults a drop longer than ~6 ms throws it out of the trap.
    theta_drop : (float, float)
        Hinge angle when the field drops [-].
    thetadot_drop : (float, float)
        Hinge rate when the field drops [1/s].
    """

    t_off: tuple[float, float] = (2.0e-3, 4.0e-3)
    theta_drop: tuple[float, float] = (-0.3, 0.3)
    thetadot_drop: tuple[float, float] = (-3.0, 3.0)

    def __post_init__(self) -> None:
        object.__setattr__(self, "t_off", _range("t_off", self.t_off, low=0.0))
        object.__setattr__(self, "theta_drop", _range("theta_drop", self.theta_drop, low=-0.99, high=0.99))
        object.__setattr__(self, "thetadot_drop", _range("thetadot_drop", self.thetadot_drop))

    def draw(self, rng: np.random.Generator) -> dict[str, float]:
        """One run's drop: ``{"t_off_s", "theta_drop", "thetadot_drop"}``."""
        return {
            "t_off_s": float(rng.uniform(*self.t_off)),
            "theta_drop": float(rng.uniform(*self.theta_drop)),
            "thetadot_drop": float(rng.uniform(*self.thetadot_drop)),
        }


@dataclass(frozen=True)
class Camera:
    """The tracking camera.

    Parameters
    ----------
    fps : float
        Frame rate [1/s].
    noise_y : float
        Standard deviation of the Gaussian tracking noise on y [m].
    noise_theta : float
        Standard deviation of the Gaussian tracking noise on theta [-].
    missing_frames : int
        Frames per run lost by the tracker (both y and theta written as ``nan``), at random
        interior positions, never two adjacent.
    """

    fps: float = 2000.0
    noise_y: float = DEFAULT_TRACKING_NOISE["noise_y_m"]
    noise_theta: float = DEFAULT_TRACKING_NOISE["noise_theta"]
    missing_frames: int = 3

    def __post_init__(self) -> None:
        with raising(TwinError):
            check_positive(self, "fps")
            check_non_negative(self, "noise_y")
            check_non_negative(self, "noise_theta")
            check_whole(self, "missing_frames", minimum=0)

    def record(self, state: NDArray[np.float64], rng: np.random.Generator) -> tuple[NDArray, NDArray, NDArray]:
        """Observed (y [m], theta [-]) of exact states (n, 4), and the indices of the missing frames.

        Observed theta is clipped to +-0.999 (a tracker never reports an angle past face contact).
        """
        n = state.shape[0]
        y = state[:, 0] + self.noise_y * rng.standard_normal(n)
        th = np.clip(state[:, 2] + self.noise_theta * rng.standard_normal(n), -0.999, 0.999)
        k = int(self.missing_frames)
        if k:
            interior = n - 2
            if interior < 2 * k:
                raise TwinError(f"a run of {n} frames cannot have {k} missing frames")
            # k non-adjacent positions in 1..n-2: choose from n-2-(k-1) slots and spread them
            slots = np.sort(rng.choice(interior - (k - 1), size=k, replace=False))
            idx = 1 + slots + np.arange(k)
        else:
            idx = np.zeros(0, int)
        y[idx] = np.nan
        th[idx] = np.nan
        return y, th, idx


@dataclass(frozen=True)
class TwinPreset:
    """A named set of effects, protocol, experiment and model (e.g. :data:`PAPER_LIKE`, :data:`PAPER`).

    ``experiment`` is the experiment's conditions (side, frequency, nominal pressure amplitude...) and ``model_spec``
    the force model with its own options (the full-wave hinge gap), as :class:`TwinConfig` holds them.
    ``air_damping`` adds the air's computed drag (:func:`acousim.dynamics.effects.air_damping_for`), as every twin does by
    default; a preset whose ``effects`` hold a tuned *total* damping (a ``linear_damping`` standing for all of the
    air's drag) sets it False, so that the air is not counted twice.
    """

    name: str
    effects: EffectSet
    experiment: ExperimentConditions = field(default_factory=ExperimentConditions)
    protocol: DropProtocol = field(default_factory=DropProtocol)
    description: str = ""
    model_spec: ModelSpec = field(default_factory=ModelSpec)
    air_damping: bool = True
    transducer_q: float | None = None
    cavity_detuning: float | None = None
    cavity_area: float | None = None

    def dimer_settings(self) -> dict:
        """The preset's :class:`TwinConfig` fields beyond effects and protocol: ``experiment``, ``model_spec``,
        ``air_damping`` and the resonator's settings it sets."""
        out = {k: getattr(self, k) for k in ("transducer_q", "cavity_detuning", "cavity_area")
               if getattr(self, k) is not None}
        return {"experiment": self.experiment, "model_spec": self.model_spec, **out, "air_damping": bool(self.air_damping)}


@dataclass(frozen=True)
class TwinConfig:
    """Every setting of a synthetic data set.

    Parameters
    ----------
    runs : int
        Number of runs (one CSV each).
    duration : float
        Recorded time per run [s] (from the moment the field is back on).
    seed : int
        Master seed: every random choice derives from it.
    experiment : ExperimentConditions
        The experiment (:class:`acousim.models.ExperimentConditions` without the model's own options): cube side
        [m] (50 um to 2 mm), material, drive frequency [Hz] (with the side it sets ks), air and the nominal pressure
        amplitude p0 [Pa] written to meta.json; default: docs/conventions.md's.
    model_spec : ModelSpec
        The acoustic force model and its own options (:class:`acousim.models.ModelSpec`: ``"gorkov"``, the Gor'kov
        surrogate, with its ``mesh_size_m``; ``"fullwave"``, the full-wave table of the dimer from the table family,
        with its hinge ``gap_m`` and ``edge_radius_m``, None: 0.01 side and sharp edges); default: the registry's
        first model.
    pressure_error : float
        The true p0 is drawn uniformly in nominal x [1 - e, 1 + e] (0: true = nominal); docs/formats.md
        allows real data to be off by up to 10 %.
    effects : EffectSet
    protocol : DropProtocol
    camera : Camera
    max_step : float
        Longest internal RK4 step [s].
    preset : str, optional
        Name of the preset these settings came from (bookkeeping only).
    air_damping : bool
        Add the air's drag computed from the dimer's geometry and the air (the effect ``air_damping``,
        docs/damping.md) to ``effects``, unless they hold one already.  On by default: a twin of an experiment
        in air has it, and ``effects`` then add what the air's drag misses.  False gives the inviscid dimer with
        no damping beyond ``effects`` (what a study that draws its damping itself, or a tuned total damping such
        as :data:`PAPER_LIKE`'s, needs).
    transducer_q : float
        The transducer's quality factor Q: the field rings down when the drive stops and rings up when it is back,
        with the amplitude's ring time tau = Q / (pi ``frequency``), and the acoustic forces follow p(t)^2 / p0^2
        (:mod:`acousim.dynamics.switching`).  0 (the default) switches the field instantly;
        :data:`acousim.dynamics.switching.DEFAULT_TRANSDUCER_Q` (250, tau = 1.74 ms at 45.65 kHz) is the value stated for
        a Langevin transducer of a levitator (Q 150-400).  With ``cavity_detuning`` it is the cavity mode's Q.
    cavity_detuning : float, optional
        The levitator as a resonator (:mod:`acousim.dynamics.resonator`, docs/twin.md): the cavity's resonance minus
        the drive's frequency with the dimer at rest, in half-widths f / (2 ``transducer_q``) (> 0: the drive below
        the resonance, which damps y; < 0: above it, which feeds y).  The mode's amplitude is then a state of every
        run, detuned by the dimer at its present (y, theta), and needs ``transducer_q`` > 0.  None (the default):
        the field does not respond to the dimer (every output as without a resonator).
    cavity_area : float
        The cavity's effective cross-section A_cav [m^2] (the transducer's area; the mode's volume is
        A_cav lambda / 2), used with ``cavity_detuning``; default :data:`acousim.dynamics.resonator.DEFAULT_CAVITY_AREA`
        (a 20 mm transducer, 3.14e-4 m^2), within :data:`acousim.dynamics.resonator.CAVITY_AREA_RANGE`.
    """

    runs: int = 10
    duration: float = 4.0
    seed: int = 0
    experiment: ExperimentConditions = field(default_factory=ExperimentConditions)
    model_spec: ModelSpec = field(default_factory=ModelSpec)
    pressure_error: float = field(default=0.0, metadata=named("pressure error (--pressure-error)"))
    effects: EffectSet = field(default_factory=EffectSet)
    protocol: DropProtocol = field(default_factory=DropProtocol)
    camera: Camera = field(default_factory=Camera)
    max_step: float = DEFAULT_MAX_STEP
    preset: str | None = None
    air_damping: bool = True
    transducer_q: float = field(default=0.0, metadata=named("transducer quality factor (--transducer-q)"))
    cavity_detuning: float | None = None
    cavity_area: float = DEFAULT_CAVITY_AREA

    def __post_init__(self) -> None:
        with raising(TwinError):
            check_in_range(self, "transducer_q", 0.0, 1e5)  # 0: instant switching
            self.cavity_mode  # noqa: B018 (checks the resonator's settings)
            check_whole(self, "runs")
            check_positive(self, "duration")
            check_whole(self, "seed", minimum=0)
            check_that(self, isinstance(self.experiment, ExperimentConditions) and isinstance(self.model_spec, ModelSpec),
                       f"experiment and model_spec must be an ExperimentConditions and a ModelSpec, got "
                       f"{type(self.experiment).__name__} and {type(self.model_spec).__name__}")
            own = [name for name in model_options() if self.experiment.option(name) is not None]
            check_that(self, not own, f"{', '.join(own)} is the model's own option: give it in model_spec, not in "
                                      "experiment")
            check_in_range(self, "side", 50e-6, 2e-3, unit="m")
            check_in_range(self, "pressure_error", 0.0, 0.5, high_open=True)
            check_positive(self, "max_step")
            self.conditions  # noqa: B018 (checks the model's options at this experiment)
            check_that(self, self.n_frames >= 16,
                       f"{self.duration:g} s at {self.camera.fps:g} fps gives only {self.n_frames} frames")

    @classmethod
    def from_preset(cls, preset: TwinPreset, **overrides) -> "TwinConfig":
        """Settings of a preset (effects, experiment, model, protocol), with any field overridden."""
        base = dict(effects=preset.effects, protocol=preset.protocol, preset=preset.name, **preset.dimer_settings())
        base.update(overrides)
        return cls(**base)

    @property
    def conditions(self) -> ExperimentConditions:
        """The experiment with the model's own options (:meth:`acousim.models.ModelSpec.conditions`): what the force
        model is built for, at the nominal pressure amplitude."""
        try:
            return self.experiment.with_options(**self.model_spec.option_values)
        except ValueError as exc:
            raise TwinError(str(exc)) from None

    @property
    def side(self) -> float:
        """Cube side [m] (``experiment.side_length_m``)."""
        return self.experiment.side_length_m

    @property
    def frequency(self) -> float:
        """Drive frequency [Hz] (``experiment.frequency_hz``)."""
        return self.experiment.frequency_hz

    @property
    def pressure_amplitude_pa(self) -> float:
        """Nominal pressure amplitude p0 [Pa] (``experiment.pressure_amplitude_pa``)."""
        return self.experiment.pressure_amplitude_pa

    @property
    def force_model(self) -> str:
        """The force model's registered name (``model_spec.name``)."""
        return self.model_spec.name

    @property
    def cavity_mode(self) -> CavityMode | None:
        """The levitator's cavity mode (:class:`acousim.dynamics.resonator.CavityMode`), None without a resonator."""
        if self.cavity_detuning is None:
            return None
        if not self.transducer_q > 0:
            raise TwinError("the resonator (--detuning) needs the cavity's quality factor: give --transducer-q > 0 "
                            "(e.g. 250)")
        try:
            return CavityMode(float(self.transducer_q), self.cavity_detuning, self.cavity_area)
        except (TypeError, ValueError) as exc:
            option = "--detuning" if "detuning" in str(exc) else "--cavity-area" if "area" in str(exc) else "--transducer-q"
            raise TwinError(f"{option}: {exc}") from None

    @property
    def n_frames(self) -> int:
        """Frames per run."""
        return int(round(self.duration * self.camera.fps))

    def to_dict(self) -> dict:
        """JSON-ready settings (SI units); ``force_model`` is listed when it is not the Gor'kov default, ``air_damping``
        always (true or false)."""
        options = self.model_spec.option_values
        out = {
            "runs": int(self.runs),
            "duration_s": float(self.duration),
            "seed": int(self.seed),
            "side_length_m": float(self.side),
            "nominal_pressure_amplitude_pa": float(self.pressure_amplitude_pa),
            "pressure_error": float(self.pressure_error),
            "effects": self.effects.to_dict(),
            "protocol": {k: list(v) for k, v in asdict(self.protocol).items()},
            "camera": {"fps": float(self.camera.fps), "noise_y_m": float(self.camera.noise_y),
                       "noise_theta": float(self.camera.noise_theta),
                       "missing_frames": int(self.camera.missing_frames)},
            "mesh_size_m": options.get("mesh_size_m"),  # listed always (null: the model's default)
            "max_step_s": float(self.max_step),
            "preset": self.preset,
        }
        if self.force_model != force_model_names()[0]:  # listed when it is not the default model
            out["force_model"] = self.force_model
        for name in model_options():  # every other option of the model that is set, under its name
            if name != "mesh_size_m" and name in options:
                out[name] = float(options[name])
        if self.frequency != ExperimentConditions.frequency_hz:
            out["frequency_hz"] = float(self.frequency)
        out["air_damping"] = bool(self.air_damping)
        out["field_switching"] = {"transducer_q": float(self.transducer_q),
                                  "ring_time_s": float(self.transducer_q) / (np.pi * float(self.frequency)),
                                  "model": "instant" if self.transducer_q == 0 else
                                  "p(t)/p0 = exp(-t/tau) with the drive off, 1 - (1 - p_on/p0) exp(-t/tau) once it "
                                  "is back; forces scale as (p/p0)^2"}
        if self.cavity_mode is not None:  # listed only with the resonator: every other output as without it
            out["resonator"] = self.cavity_mode.to_dict(self.frequency)
        return out


# ---------------------------------------------------------------------- presets
#: The "paper-like" twin of docs/twin.md: *tuned* Gor'kov dynamics.  pair_scattering tunes the hinge to just below the y
#: frequency (f_theta = 21.0 Hz vs f_y = 21.3-21.8 Hz), mirror_asymmetry's beta1 y term drives the
#: hinge at f_y, y is weakly damped (amplitude decay time 20 s) and the hinge transient dies in
#: ~1-2 s.  Over 200 drops: ~45 % lock anti-phase with a small hinge amplitude (~0.15), ~40 % lock
#: in-phase with a large one (~0.65), ~15 % have not settled after 4 s; never a failed run.  Its linear_damping is
#: the tuned *total* damping, so the air's computed drag is off (``air_damping=False``): counted twice otherwise.
PAPER_LIKE = TwinPreset(
    name="paper-like",
    effects=EffectSet((
        LinearDamping(gamma_y=0.1, gamma_theta=1.5),
        PairScattering(kappa=19500.0),
        MirrorAsymmetry(beta0=0.0, beta1=1.0e6),
    )),
    experiment=ExperimentConditions(pressure_amplitude_pa=3000.0),
    protocol=DropProtocol(t_off=(2.0e-3, 4.0e-3), theta_drop=(-0.3, 0.3), thetadot_drop=(-3.0, 3.0)),
    description="tuned Gor'kov dynamics: hinge tuned just below the y frequency by pair scattering and driven at "
    "f_y by a mirror asymmetry; weak damping: bistable in-phase (large) and anti-phase (small) locking, see docs/twin.md; "
    "its tuned linear damping is the total damping, so the air's computed drag is off",
    air_damping=False,
)

#: The source paper's protocol on the physics, no tuned parameter (docs/twin.md, "The paper's protocol"): the
#: full-wave model of a family dimer, the air's computed drag as the only damping, and the paper's 13 ms field
#: drop of a dimer at rest.  The dimer is the family's 700 um, g = 0.05 s one at 45.65 kHz (ks 0.585), at
#: 6 kPa: the family dimer and pressure in docs/twin.md's scan at which a 13 ms free fall neither throws the
#: dimer out of the trap (it does below 5 kPa at every side) nor folds its hinge (500 um dimers fold: their
#: hinge frequency is within 10 % of the vertical one, where the fall's 1.2 mm oscillation pumps the hinge
#: parametrically).  The hinge starts at rest within +-0.02 of its static equilibrium (theta* = 0.017 at 6 kPa):
#: the asymmetry of real cubes and traps.
PAPER = TwinPreset(
    name="paper",
    effects=EffectSet(),
    experiment=ExperimentConditions(side_length_m=700e-6, pressure_amplitude_pa=6000.0),
    protocol=DropProtocol(t_off=(13.0e-3, 13.0e-3), theta_drop=(-0.003, 0.037), thetadot_drop=(0.0, 0.0)),
    description="the paper's 13 ms field drop on the full-wave model of a 700 um dimer (g = 0.05 s) with the air's "
    "computed damping and no tuned parameter, see docs/twin.md",
    model_spec=ModelSpec(FULLWAVE, {"gap_m": 35e-6}),
    air_damping=True,
)

#: The levitator as a resonator near its threshold (docs/twin.md, "The levitator as a resonator"): the full-wave
#: 500 um, g/s 0.02 dimer at 3 kPa (inside the held-y window, f_theta / f_y = 1.195) with the air's computed damping,
#: its cavity mode at Q = 250 driven 2.2 half-widths above the resonance with a 20 mm transducer, where the lagged
#: force nearly cancels the air's damping of y (net growth rate +0.016 1/s), and drive-off times of 3-5 ms.  The
#: detuning and the drop were chosen by a scan (docs/twin.md) as those where both phase classes appear: tuned, within
#: a tenth of a half-width of the threshold, not derived.
WINDOW_RESONATOR = TwinPreset(
    name="window-resonator",
    effects=EffectSet(),
    experiment=ExperimentConditions(side_length_m=500e-6, pressure_amplitude_pa=3000.0),
    protocol=DropProtocol(t_off=(3.0e-3, 5.0e-3), theta_drop=(-0.4, 0.4), thetadot_drop=(-30.0, 30.0)),
    description="the full-wave 500 um, g/s 0.02 dimer at 3 kPa with the air's computed damping and the levitator as a "
    "resonator (Q 250, drive 2.2 half-widths above the resonance, 20 mm transducer), 3-5 ms drops; see docs/twin.md",
    model_spec=ModelSpec(FULLWAVE, {"gap_m": 10e-6}),
    air_damping=True,
    transducer_q=250.0,
    cavity_detuning=-2.2,
    cavity_area=DEFAULT_CAVITY_AREA,
)

#: Presets by name (the ``--preset`` values of ``python -m acousim simulate``).
PRESETS: dict[str, TwinPreset] = {PAPER_LIKE.name: PAPER_LIKE, PAPER.name: PAPER, WINDOW_RESONATOR.name: WINDOW_RESONATOR}
