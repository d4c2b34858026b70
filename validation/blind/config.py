"""Settings of a blind study: :class:`BlindConfig` and the case kinds it can run."""
from __future__ import annotations

from dataclasses import dataclass

from cubedimer.config_checks import check_choices, check_fraction, check_positive, check_that, check_whole

__all__ = ["KINDS", "BlindConfig"]

#: The case kinds, in table order: hidden candidate effects; an effect no candidate describes (a cubic hinge term
#: or a y-dependent damping); a pressure drifting within runs (with or without a candidate on top); isolated
#: tracking glitches (scored against the same case without them); one run written in micrometres or
#: milliseconds (to be skipped by name).
KINDS = ("candidates", "out_of_candidate", "drift", "glitches", "unit_slip")


@dataclass(frozen=True)
class BlindConfig:
    """Settings of a blind study.

    Parameters
    ----------
    cases : int
        Cases per kind.
    seed : int
        Seed of every hidden choice (each case draws from ``(seed, kind, index)``).
    runs : int
        Runs per data set (at least 3; a unit-slip case needs at least 4, so that 3 remain to compare).
    duration : float
        Duration of each run [s].
    pressure_error : float
        Hidden pressure error: the truth is nominal x (1 + e), e uniform in +-``pressure_error``.
    long_time : bool
        Compute the diagnosis's long-time errors too (not scored).
    air_damping : bool
        The candidate cases' twin runs with the air's computed damping, its default physics (the truth then holds
        ``linear_damping`` at the air's rates); False: the inviscid study, whose drawn effects are the whole truth.
    kinds : tuple of str
        The case kinds to run (a subset of :data:`KINDS`; default the candidate cases alone, whose study is
        the reference of the identification targets; each further kind costs one or two diagnoses per case).
    resonator : bool
        The levitator's resonator is one of the effects a candidate case can draw (its Q and detuning,
        :data:`validation.blind.candidates.RESONATOR_STRENGTHS`), and the diagnosis tries the cavity's lag
        (``cavity_lag``) among its candidates; False: neither (the study without the cavity).
    trajectory_test : bool
        The diagnosis judges the velocity coupling on the whole trajectories too
        (``DiagnoseConfig.trajectory_test``; on by default, as in the diagnosis; False: the held-out rounds alone).
    """

    cases: int = 50
    seed: int = 0
    runs: int = 10
    duration: float = 3.0
    pressure_error: float = 0.10
    long_time: bool = False
    kinds: tuple[str, ...] = ("candidates",)
    air_damping: bool = True
    resonator: bool = True
    trajectory_test: bool = True

    def __post_init__(self) -> None:
        check_whole(self, "cases")
        check_whole(self, "runs", minimum=3)
        check_positive(self, "duration")
        check_fraction(self, "pressure_error", zero=True)
        object.__setattr__(self, "kinds", tuple(self.kinds))
        check_choices(self, "kinds", KINDS, what="case kind(s)", allow_empty=False)
        check_that(self, "unit_slip" not in self.kinds or self.runs >= 4,
                   "unit-slip cases need runs >= 4 (three runs must remain to compare)")
