"""The loader's rules, :class:`LoadConfig`, and the command-line options that set them (:data:`LOAD_OPTIONS`).

Every command that loads a data set (``fitting fit``, ``validation report``, ``validation diagnose``) offers the
options of :data:`LOAD_OPTIONS`, declared here beside the fields they set (:class:`cubedimer.setting_options.
SettingOption`), with the defaults read from :class:`LoadConfig`.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

from .config_checks import check_fraction, check_non_negative, check_that, check_whole
from .consistency import ConsistencyConfig
from .glitches import GlitchConfig
from .setting_options import SettingOption, positive_float, positive_int

__all__ = ["LoadConfig", "DEFAULT_MAX_GAP", "LOAD_OPTIONS"]

#: The longest gap of missing frames [frames] the loader fills when neither the caller nor the data set (meta.json
#: ``tracking.max_gap_frames``) says another: 5 ms at 2,000 fps, a tenth of a 20 Hz period.
DEFAULT_MAX_GAP = 10


@dataclass(frozen=True)
class LoadConfig:
    """Rules for loading.

    Parameters
    ----------
    max_gap : int or None
        Longest run of consecutive missing frames that is filled (PCHIP through the neighbours); a run is split at
        a longer gap (:func:`load_run_parts`).  None: the limit the data set records (meta.json
        ``tracking.max_gap_frames``, written by ``tracking track --max-gap``), else :data:`DEFAULT_MAX_GAP`; a
        number given here is used whatever the set records.
    max_missing_fraction : float
        Largest allowed fraction of missing frames per run.
    uniform_tol : float
        Allowed relative deviation of any time step from the median step (docs/formats.md: 1 %).
    min_periods : float
        Minimum number of oscillation periods (of the dominant y frequency) a run must hold.
    glitches : GlitchConfig or None
        Isolated tracking glitches are found (:mod:`cubedimer.glitches`) and masked like missing
        frames; None keeps every frame.
    consistency : ConsistencyConfig or None
        Runs that do not fit the rest of the set or the physics of levitation (:mod:`cubedimer.consistency`;
        meta.json's constants or their defaults) are reported and skipped; None loads every readable run.
    trap_frequency : callable or None
        ``trap_frequency(meta) -> Hz``, a physics estimate of the vertical trap frequency at meta.json's
        nominal pressure (e.g. :func:`acousim.analytic.nominal_trap_frequency`), checked when the data set
        has a meta.json; None keeps the physics-free bound of 5-200 Hz only.
    systems : tuple of str
        The kinds of system (:data:`cubedimer.system.SYSTEM_KINDS`) accepted from meta.json; a data set declaring
        another kind is refused in one line.  The default, a levitated dimer only, is what every command but
        ``fitting fit`` needs.
    """

    max_gap: int | None = None
    max_missing_fraction: float = 0.05
    uniform_tol: float = 0.01
    min_periods: float = 5.0
    glitches: GlitchConfig | None = field(default_factory=GlitchConfig)
    consistency: ConsistencyConfig | None = field(default_factory=ConsistencyConfig)
    trap_frequency: Callable[[dict], float] | None = None
    systems: tuple[str, ...] = ("levitated_dimer",)

    def __post_init__(self) -> None:
        check_whole(self, "max_gap", minimum=0, optional=True)
        check_fraction(self, "max_missing_fraction", closed=True)
        check_fraction(self, "uniform_tol")
        check_non_negative(self, "min_periods")
        check_that(self, self.trap_frequency is None or callable(self.trap_frequency),
                   f"trap_frequency must be callable or None, got {self.trap_frequency!r}")

    @property
    def fill_limit(self) -> int:
        """The longest gap filled [frames]: ``max_gap``, or :data:`DEFAULT_MAX_GAP` when it is None."""
        return DEFAULT_MAX_GAP if self.max_gap is None else int(self.max_gap)

#: The loader's command-line options: the glitch mask, the shortest run, the longest gap filled.
LOAD_OPTIONS: tuple[SettingOption, ...] = (
    SettingOption("--no-glitch-mask", "glitches", switch=None,
                  help="keep every recorded frame: no isolated tracking glitch is masked and filled (by default the "
                       "frames masked per run are counted in model.json's per_run entries)"),
    SettingOption("--min-periods", "min_periods", type=positive_float, metavar="N",
                  help="oscillation periods (of the dominant frequency of y, or of the first declared coordinate) a "
                       "run must hold to be fitted (default {default})"),
    SettingOption("--max-gap", "max_gap", type=positive_int, metavar="FRAMES",
                  help="longest gap of missing frames (not measured, or masked as tracking glitches) filled by "
                       "interpolation; a run is split into two at a longer gap, and a part too short to fit is "
                       "skipped (default: the data set's meta.json tracking.max_gap_frames, written by tracking "
                       f"track --max-gap, else {DEFAULT_MAX_GAP}); given, it overrides meta.json"),
)
