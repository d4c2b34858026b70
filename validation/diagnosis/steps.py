"""A data set's diagnosis from end to end: :func:`diagnose_dataset` (its files: :func:`validation.report.write_diagnosis`).

The steps, each in its folder: calibrate (:mod:`.calibrate.calibration_step`), identify
(:mod:`.identify.identification_step`), discover (:mod:`.discover.discovery_step`) and summarise
(:mod:`.summarise.summary_step`); :func:`diagnose` runs them in order.

Output, ``diagnosis.json`` (docs/formats.md, extended)::

    {"identified": [...], "calibration": {...}, "gap_before": g0, "gap_after": g1, "gap_definition": "...",
     "gap_components": [...], "gap_component_forms": {...}, "gap_per_run": {...}, "noise_floor": ...,
     "effects": [every candidate, ranked], "localization": {"before": ..., "after": ...},
     "long_time": {...}, "remaining_gap": {...}, "identification_rounds": [...], "skipped_files": [...],
     "settings": {...}}
"""
from __future__ import annotations

import logging
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Sequence

from acousim.models import ModelSpec
from cubedimer.config_checks import check_choices, check_fraction, check_positive, check_whole

if TYPE_CHECKING:
    from cubedimer.dataset import Dataset, LoadConfig
    from fitting.derivatives.preparation import PreparedDataset
    from fitting.derivatives.savitzky_golay import SmoothingConfig

from .calibrate.calibration_step import calibration_step
from .calibrate.drift import DriftSettings
from .discover.discovery_step import AIR_DAMPINGS, discovery_step
from .identify.folded import leave_out_folded_runs
from .identify.identification import PracticalThresholds
from .identify.identification_step import identification_step
from .identify.statistics import runs_needed
from .prepare.candidate_effects import CANDIDATE_EFFECTS, default_candidates
from .summarise.result import Diagnosis, DiagnosisInternals
from .summarise.summary_step import EXPLAINED_GAP, summary_step

__all__ = ["DiagnoseConfig", "DiagnosisInternals", "Diagnosis", "DiagnosisStart", "diagnose", "diagnose_dataset",
           "start_diagnosis", "load_for_diagnosis", "EXPLAINED_GAP", "MIN_RUNS", "check_enough_runs"]

logger = logging.getLogger(__name__)

#: Re-exported from the steps that use them (``AIR_DAMPINGS``: the candidate dampings, judged together against
#: discovered terms; ``EXPLAINED_GAP``: the gap below which the data count as explained within the noise).
__all__ += ["AIR_DAMPINGS"]


@dataclass(frozen=True)
class DiagnoseConfig:
    """Settings of a diagnosis.

    Parameters
    ----------
    candidates : names of the candidate effects (default: all of docs/conventions.md section 5; the cavity's lag,
        ``cavity_lag``, only when named here)
    alpha : significance level of the one-sided sign-flip permutation test of the held-out improvement
    min_relative_improvement : practical significance, as a fraction of the current gap
    min_absolute_improvement : practical significance, as a fraction of the variance (beyond noise)
    max_frames_per_run : runs are thinned to at most this many frames for the fits (speed)
    max_vertical_gap : no cause is named when the vertical (calibration) equation stays unexplained beyond
        this fraction of its variance (the calibration is then distorted by something else)
    long_time : also compute the long-time (shape, Poincare, frequency) gaps
    long_time_duration : seconds of each run simulated for them [s]; None: the whole run
    drift : settings of the test for a pressure drifting within runs (:mod:`validation.diagnosis.calibrate.drift`);
        None: the pressure is taken as constant without testing
    discover : regress what remains after the candidates on the cubic library (:mod:`validation.diagnosis.discover.library_terms`)
    discovery_min_improvement : a discovered term's median held-out improvement, as a fraction of the variance
    check_orientation : test whether y points down (:mod:`validation.diagnosis.calibrate.orientation`); if so, warn
        (``data_warnings``, code ``y_inverted``) and diagnose the data with y -> -y
    trajectory_test : judge the velocity coupling, where the held-out rounds did not choose it beside linear damping,
        on the runs' whole trajectories (:mod:`validation.diagnosis.identify.output_error`; on by default).  False:
        the held-out rounds alone, which miss about half the couplings drawn beside the air's damping
        (docs/diagnosis.md)
    """

    candidates: tuple[str, ...] = field(default_factory=default_candidates)
    alpha: float = 0.01
    min_relative_improvement: float = 0.05
    min_absolute_improvement: float = 5e-6
    max_frames_per_run: int = 1500
    max_vertical_gap: float = 0.05
    long_time: bool = True
    long_time_duration: float | None = 2.0
    drift: DriftSettings | None = DriftSettings()
    discover: bool = True
    discovery_min_improvement: float = 1e-3
    check_orientation: bool = True
    trajectory_test: bool = True

    def __post_init__(self) -> None:
        check_choices(self, "candidates", CANDIDATE_EFFECTS, what="effect(s)")
        check_fraction(self, "alpha")
        check_whole(self, "max_frames_per_run", minimum=10)
        check_positive(self, "long_time_duration", optional=True)
        self.thresholds  # validates the practical thresholds

    @property
    def thresholds(self) -> PracticalThresholds:
        """The practical-significance settings of the identification."""
        return PracticalThresholds(self.min_relative_improvement, self.min_absolute_improvement, self.max_vertical_gap)


def load_for_diagnosis(data_dir: str | Path, strict: bool = False, progress: bool = True,
                       load: "LoadConfig | None" = None) -> "Dataset":
    """Load ``data_dir`` as :func:`diagnose` reads it: the physics bounds of any levitated dimer, and with a meta.json
    also the Gor'kov estimate of the trap frequency at its nominal pressure
    (:func:`acousim.analytic.nominal_trap_frequency`); skipped files are warned about (``progress``) or logged at
    DEBUG level; runs whose hinge ended folded are left out as skipped files
    (:func:`~validation.diagnosis.identify.folded.leave_out_folded_runs`).  Load the data set once and pass the :class:`~cubedimer.dataset.Dataset` to the fit and the
    diagnosis, so that both see the same runs.  ``load``: the loading rules (default :class:`LoadConfig`'s; the
    report passes the fit's glitch masking and shortest run, ``--no-glitch-mask`` and ``--min-periods``), to which the
    trap-frequency check is added."""
    from acousim.analytic import nominal_trap_frequency
    from cubedimer.dataset import LoadConfig, load_dataset

    skip = logger.warning if progress else logger.debug
    config = replace(load if load is not None else LoadConfig(), trap_frequency=nominal_trap_frequency)
    loaded = load_dataset(data_dir, strict=strict, config=config, report=lambda m: skip("skipping %s", m))
    dataset = leave_out_folded_runs(loaded)
    for s in dataset.skipped[len(loaded.skipped):]:
        skip("skipping %s", s)
    return dataset


def diagnose_dataset(data_dir: str | Path, config: DiagnoseConfig = DiagnoseConfig(), strict: bool = False,
                     progress: bool = True, spec: ModelSpec = ModelSpec()) -> Diagnosis:
    """Load the data set ``data_dir`` (:func:`load_for_diagnosis`) and diagnose it (:func:`diagnose`)."""
    dataset = load_for_diagnosis(data_dir, strict=strict, progress=progress)
    return diagnose(dataset, config, progress=progress, spec=spec)


@dataclass(frozen=True, eq=False)
class DiagnosisStart:
    """A data set ready to be diagnosed (:func:`start_diagnosis`): checked, prepared once, and the simulation model at
    its starting parameters."""

    prepared: "PreparedDataset"  #: the runs' one preparation (fitting.derivatives.preparation), folded runs left out
    spec: ModelSpec
    conditions: object  #: the experiment conditions of meta.json with the spec's options
    model: object  #: the spec's static model, parameters to be calibrated at their starting values
    #: what was left out of the start of every run for the cavity's ring-up [s] (0: nothing; :func:`start_diagnosis`)
    ring_up_left_out: float = 0.0


def start_diagnosis(data: "Dataset | PreparedDataset", spec: ModelSpec = ModelSpec(), alpha: float = 0.01,
                    smoothing: "SmoothingConfig | None" = None, candidates: Sequence[str] = ()) -> DiagnosisStart:
    """Check a data set for a diagnosis, once, before anything long: refuse a model that does not fit the experiment
    (a generic two-coordinate set, a dimer outside the full-wave family) and too few runs (:func:`check_enough_runs`
    at ``alpha``); then the runs are prepared once (:func:`fitting.derivatives.preparation.prepare_dataset` with
    ``smoothing``, default :class:`~fitting.derivatives.savitzky_golay.SmoothingConfig`'s, or a prepared ``data``'s
    own), unless ``data`` is prepared already and nothing is left out of it.  Runs whose hinge ended folded are left
    out; with ``cavity_lag`` among the ``candidates`` the diagnosis will try, so is the first
    :data:`~validation.diagnosis.prepare.cavity_lag.RING_UP_S` of every run (the cavity's ring-up after the field drop,
    :func:`~validation.diagnosis.prepare.cavity_lag.leave_out_ring_up`), before the preparation: whatever reads the
    start (the diagnosis, and the report's fit) sees the same runs."""
    from cubedimer.system import require_levitated_dimer
    from fitting.derivatives.preparation import PreparedDataset, prepare_dataset
    from fitting.derivatives.savitzky_golay import SmoothingConfig

    from ..simulation import conditions_from_meta
    from .prepare.cavity_lag import RING_UP_S, leave_out_ring_up

    prepared = data if isinstance(data, PreparedDataset) else None
    dataset = leave_out_folded_runs(data.dataset if prepared is not None else data)  # a no-op after load_for_diagnosis
    ring_up = RING_UP_S if "cavity_lag" in candidates else 0.0
    if ring_up:
        dataset = leave_out_ring_up(dataset, ring_up)
        if prepared is not None:  # prepared again on the shortened runs, with its own smoothing
            smoothing, prepared = (smoothing if smoothing is not None else prepared.smoothing), None
    require_levitated_dimer(dataset.meta, "validation")
    conditions = conditions_from_meta(dataset.meta, spec)
    # a parameter to be calibrated starts at the value the model takes by default
    start = {n: d for n, (_, _, d) in spec.type.calibration_ranges(conditions).items() if getattr(conditions, n) is None}
    model = spec.static(replace(conditions, **start))
    check_enough_runs(dataset.path, len(dataset.runs), len(dataset.skipped_files()), alpha)
    if prepared is None:
        prepared = prepare_dataset(dataset, smoothing if smoothing is not None else SmoothingConfig())
    elif dataset is not prepared.dataset:
        prepared = prepared.restricted_to(dataset)
    return DiagnosisStart(prepared, spec, conditions, model, ring_up)


def diagnose(data: "Dataset | PreparedDataset | DiagnosisStart", config: DiagnoseConfig = DiagnoseConfig(),
             progress: bool = True, spec: ModelSpec | None = None) -> Diagnosis:
    """Diagnose a loaded data set.

    Parameters
    ----------
    data : the data set (:func:`load_for_diagnosis` loads it with the checks a diagnosis needs), its one preparation
        (:func:`fitting.derivatives.preparation.prepare_dataset`, the one the fit reads), or a
        :class:`DiagnosisStart` (:func:`start_diagnosis`: checked and prepared already, with its spec).  With
        ``cavity_lag`` among the candidates the first 40 ms of every run (the cavity's ring-up after the field
        drop, :func:`~validation.diagnosis.prepare.cavity_lag.leave_out_ring_up`) are left out, where the start is
        made (:func:`start_diagnosis` with the candidates): a start made without leaving them out is refused with
        such candidates, so that every entry point diagnoses the same runs
    config : DiagnoseConfig
    progress : log the steps at INFO level (else DEBUG)
    spec : the simulation model and its own options (:class:`acousim.models.ModelSpec`; default: the Gor'kov
        model, or the start's); every model is calibrated the same way (pressure amplitude and height origin), and a
        model's own parameters that the data may determine (the full-wave hinge gap) are profiled unless the spec
        sets them (:mod:`validation.diagnosis.calibrate.model_parameters`)

    Returns
    -------
    Diagnosis
        The diagnosis (``to_json()``: diagnosis.json, docs/formats.md), with :class:`DiagnosisInternals` for the
        figures in ``internals``.

    Runs with one BLAS thread (:func:`cubedimer.executor.single_blas_thread`): the same numbers wherever it
    runs (here, in an executor task, on a dask worker), and faster for its many small factorisations.
    """
    from cubedimer.executor import single_blas_thread

    if isinstance(data, DiagnosisStart):
        if spec is not None and spec != data.spec:
            raise ValueError(f"the diagnosis was started with {data.spec}, not {spec}")
        if "cavity_lag" in config.candidates and not data.ring_up_left_out:
            raise ValueError("the diagnosis tries cavity_lag, but its start kept the cavity's ring-up at the start of "
                             "every run; make the start with start_diagnosis(..., candidates=config.candidates)")
    with single_blas_thread():
        start = data if isinstance(data, DiagnosisStart) else start_diagnosis(
            data, spec if spec is not None else ModelSpec(), config.alpha, candidates=config.candidates)
        return _diagnose(start, config, progress)


#: The fewest runs a diagnosis takes: every fit is scored on runs held out of it (K-fold over runs), and the
#: calibration's and the effects' held-out comparison needs at least two runs to fit on and one to score.
MIN_RUNS = 3


def check_enough_runs(data_dir, n_runs: int, n_skipped: int, alpha: float) -> None:
    """Refuse a data set with fewer than :data:`MIN_RUNS` usable runs: one line that says how many are needed and why.

    Raises
    ------
    DatasetError
        With fewer than :data:`MIN_RUNS` runs.
    """
    from cubedimer.errors import DatasetError

    if n_runs >= MIN_RUNS:
        return
    skipped = f" ({n_skipped} file(s) skipped, each with its reason above)" if n_skipped else ""
    raise DatasetError(
        f"{data_dir}: {n_runs} usable run{'' if n_runs == 1 else 's'}{skipped}; the diagnosis needs at least {MIN_RUNS}, "
        f"because it scores every fit on runs held out of it, and at least {runs_needed(alpha)} to name an effect at "
        f"alpha {alpha:g} (the held-out sign-flip test's smallest p with n runs is 2^-n); record more runs")


def _diagnose(start: DiagnosisStart, config: DiagnoseConfig, progress: bool) -> Diagnosis:
    """The diagnosis as its named steps: calibrate, identify, discover, the joint model, summarise."""
    log = logger.info if progress else logger.debug
    spec = start.spec
    cal = calibration_step(start.prepared, start.conditions, start.model, spec, config, log)
    # the trajectory test of the velocity coupling refits the pressure and the named effects, not a calibrated model
    # parameter: a hinge gap known to its profile's resolution leaves a structured residual that a tiny coupling
    # absorbs (synthetic full-wave twin, gap 0.3 % off: Delta chi2 = 172 for c5 = 2.8 1/m with converged fits), so it
    # is not made there
    calibrated = any(pc.calibrated for pc in cal.parameters.values())
    found = identification_step(cal.problem, config, progress, log, None if calibrated else cal.conditions)
    discovery, replaced, identified, final = discovery_step(cal.problem, found, config, log)
    return summary_step(start.prepared.dataset, cal, found, discovery, replaced, identified, final, spec, config, log)
