"""The typed result of a diagnosis: :class:`Diagnosis` (diagnosis.json, docs/formats.md) and its
:class:`EffectVerdict` per candidate effect.

:meth:`Diagnosis.to_json` gives the diagnosis.json document, key for key in the documented order, and
:meth:`Diagnosis.from_json` reads one back (a written diagnosis.json, or the blind study's records). The nested
records that are documents of their own (the localisation, the long-time gaps, the identification rounds, the
remaining gap, the calibration) stay JSON mappings: their layouts are documented in docs/formats.md and read by
key in one place each.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping, Sequence

from ..calibrate.gap_model import GapFit
from ..prepare.problem import DiagnosisProblem
from ..prepare.runs import RunAccelerations
from .uncertainty import ParameterInterval

__all__ = ["Diagnosis", "DiagnosisInternals", "EffectVerdict", "RejectedCandidateError", "STATUSES", "REJECTIONS", "rejection"]

#: An effect's status: named as a cause; one of a pair the data cannot tell apart (named together); rejected.
STATUSES = ("named", "indistinguishable", "rejected")
#: Why a candidate is rejected (``rejected_because[i]["code"]``).
REJECTIONS = {
    "not_significant": "not a significant held-out improvement on top of the model's effects",
    "removed_by_backward_check": "improved held-out runs when added, but not given the other effects",
    "replaced_by_discovered_terms": "not needed once the discovered library terms are fitted",
    "withheld": "the calibration equation stays unexplained, so no cause is named",
    "not_shrinking_gap": "improved held-out runs, but adding it to the model's other effects raises the gap beyond "
                         "its error (the gaps without and with it are given, and the change with its standard error "
                         "over runs), so it is not named as a cause",
    "non_physical_sign": "a parameter fitted with a sign its physics excludes (a negative damping rate, drag "
                         "coefficient or scattering stiffness)",
    "no_cavity_mode": "the cavity's lag gain has the sign of its quasi-static gain, beyond its 95 % interval: no "
                      "cavity mode has such gains (a resonator's have opposite signs at every detuning), so it is not "
                      "named as a cause",
    "within_cavity_response": "pair scattering beside the named cavity, with a hinge stiffness within the cavity's own "
                              "modulation of the hinge's acoustic stiffness over the data (max |s - 1| K): the data "
                              "cannot tell it from what the cavity's columns leave of its response, so it is not "
                              "named as a cause",
}


def rejection(code: str, detail: str = "") -> dict:
    """A rejected candidate's reason as diagnosis.json holds it: its code (a key of :data:`REJECTIONS`) and the
    code's sentence with the numbers that decided it in parentheses."""
    return {"code": code, "reason": REJECTIONS[code] + (f" ({detail})" if detail else "")}


class RejectedCandidateError(ValueError):
    """A rejected candidate's parameters were asked for as a result."""


def _reference_model() -> str:
    """The registry's first model (a diagnosis.json written before the key ``model`` was diagnosed on it)."""
    from acousim.models import force_model_names

    return force_model_names()[0]


@dataclass(frozen=True)
class EffectVerdict:
    """One candidate effect's verdict (diagnosis.json ``effects[i]``).

    Attributes
    ----------
    name : the effect (a key of :data:`acousim.dynamics.effects.EFFECT_TYPES`)
    params : its fitted parameters (SI), by parameter name
    gap_after : the scalar gap with it fitted (with the effects before it, for one in the model; on top of the
        model's effects otherwise)
    shrink : ``1 - gap_after / gap_before``
    significant : in the fitted model (a significant held-out improvement given the others)
    p_value, wilcoxon_p : the held-out sign-flip and signed-rank p-values when it was tested (None: never tested)
    held_out_improvement_fraction : its median held-out improvement as a fraction of the gap
    added_in_round : the identification round that added it (model effects only)
    named : named as a cause (False for a model effect that stands for an indistinguishable pair)
    note : why it is not in the model (the other candidates)
    p_value_given_others, median_improvement_given_others : the backward check given every other effect
    indistinguishable_from : the effects the data cannot tell it from
    params_without_discovered_terms : its parameters fitted without the discovered library terms, when they differ
    status : one of :data:`STATUSES`; a ``rejected`` candidate's ``params`` are its fit on top of the model, never a
        result (:meth:`estimate` refuses them)
    rejected_because : ``({"code", "reason"}, ...)``, the codes of :data:`REJECTIONS` (empty unless rejected)
    uncertainty : per parameter, the standard error and 95 % interval
        (:class:`~validation.diagnosis.summarise.uncertainty.ParameterInterval`; the model's effects only)
    derived : quantities computed from the parameters, with their intervals (the cavity's ``quality_factor``,
        ``detuning_half_widths`` from its gains and ``quasi_static_response`` from its static gain)
    gap_change, gap_change_std_error : the change of the scalar gap its addition causes (``gap_after`` minus the gap
        with the model's effects before it; the model's effects only) and its standard error over runs, from the
        runs' paired changes (None with fewer than 3 runs, or in a diagnosis.json written before the key)
    gap_without_given_others, gap_change_given_others, gap_change_given_others_std_error : the scalar gap of the
        final model refitted without it (the model's other effects), the change its addition to them causes (the
        final model's gap minus that) and the change's standard error over runs; the rule ``not_shrinking_gap`` and
        the report judge this change (in the order added, an early effect is judged against a model that still
        lacks the later ones); None in a diagnosis.json written before the keys
    """

    name: str
    params: Mapping[str, float]
    gap_after: float
    shrink: float
    significant: bool
    p_value: float | None
    wilcoxon_p: float | None
    held_out_improvement_fraction: float | None
    added_in_round: int | None = None
    named: bool = False
    note: str | None = None
    p_value_given_others: float | None = None
    median_improvement_given_others: float | None = None
    indistinguishable_from: tuple[str, ...] | None = None
    params_without_discovered_terms: Mapping[str, float] | None = None
    status: str | None = None
    rejected_because: tuple[Mapping[str, str], ...] = ()
    uncertainty: Mapping[str, ParameterInterval] | None = None
    derived: Mapping[str, ParameterInterval] | None = None
    gap_change: float | None = None
    gap_change_std_error: float | None = None
    gap_without_given_others: float | None = None
    gap_change_given_others: float | None = None
    gap_change_given_others_std_error: float | None = None

    def __post_init__(self) -> None:
        if self.status is None:  # from the verdict's flags: a model effect is named or stands for a pair
            status = ("named" if self.named else "indistinguishable") if self.significant else (
                "indistinguishable" if self.indistinguishable_from else "rejected")
            object.__setattr__(self, "status", status)
        if self.status not in STATUSES:
            raise ValueError(f"an effect's status is one of {', '.join(STATUSES)}, got {self.status!r}")

    @property
    def rejected(self) -> bool:
        """Tried and rejected: its parameters are no result."""
        return self.status == "rejected"

    def estimate(self, parameter: str) -> ParameterInterval:
        """The parameter's value with its standard error and 95 % interval.

        Raises
        ------
        RejectedCandidateError
            For a rejected candidate (with the reasons): its fitted values are no result.
        KeyError
            For a parameter the effect does not have.
        """
        if self.rejected:
            raise RejectedCandidateError(f"{self.name} is a rejected candidate ({self.rejection_text()}); its fitted "
                                         "parameters are not a result")
        if parameter not in self.params:
            raise KeyError(f"{self.name} has no parameter {parameter!r}; it has {', '.join(self.params)}")
        if self.uncertainty is None or parameter not in self.uncertainty:
            return ParameterInterval(float(self.params[parameter]), None, None, None, "no error was computed")
        return self.uncertainty[parameter]

    def rejection_text(self) -> str:
        """The reasons of a rejection, joined (its note when written without them; "" unless rejected)."""
        return "; ".join(r["reason"] for r in self.rejected_because) or (self.note or "" if self.rejected else "")

    def __str__(self) -> str:
        if self.rejected:
            return f"{self.name}: rejected ({self.rejection_text()})"
        values = ", ".join([f"{p} = {self.estimate(p).format()}" for p in self.params]
                           + [f"{p} = {iv.format()}" for p, iv in (self.derived or {}).items()])
        return f"{self.name}: {self.status} ({values})"

    def to_json(self) -> dict[str, Any]:
        """The diagnosis.json form: a model effect carries its round, ``named`` and its backward check; another
        candidate carries its ``note`` and, when it was checked, its backward check."""
        out: dict[str, Any] = {"name": self.name, "params": dict(self.params), "gap_after": self.gap_after,
                               "shrink": self.shrink, "significant": self.significant, "p_value": self.p_value,
                               "wilcoxon_p": self.wilcoxon_p,
                               "held_out_improvement_fraction": self.held_out_improvement_fraction}
        given = {"p_value_given_others": self.p_value_given_others,
                 "median_improvement_given_others": self.median_improvement_given_others}
        if self.significant:
            out.update({"added_in_round": self.added_in_round, "named": self.named, **given})
            if self.indistinguishable_from is not None:
                out["indistinguishable_from"] = list(self.indistinguishable_from)
            if self.params_without_discovered_terms is not None:
                out["params_without_discovered_terms"] = dict(self.params_without_discovered_terms)
            if self.gap_change is not None:
                out.update({"gap_change": self.gap_change, "gap_change_std_error": self.gap_change_std_error})
            if self.gap_change_given_others is not None:
                out.update({"gap_without_given_others": self.gap_without_given_others,
                            "gap_change_given_others": self.gap_change_given_others,
                            "gap_change_given_others_std_error": self.gap_change_given_others_std_error})
        else:
            out["note"] = self.note
            if self.p_value_given_others is not None:
                out.update(given)
        out["status"] = self.status
        out["rejected_because"] = [dict(r) for r in self.rejected_because]
        if self.uncertainty is not None:
            out["uncertainty"] = {p: iv.to_dict() for p, iv in self.uncertainty.items()}
        if self.derived is not None:
            out["derived"] = {p: iv.to_dict() for p, iv in self.derived.items()}
        return out

    @classmethod
    def from_json(cls, doc: Mapping[str, Any]) -> "EffectVerdict":
        """The verdict of a diagnosis.json ``effects`` entry."""
        pair = doc.get("indistinguishable_from")
        unc, der = doc.get("uncertainty"), doc.get("derived")
        # a diagnosis.json written before the key: an "indistinguishable from" note marks a pair's other member
        status = doc.get("status") or ("indistinguishable" if (doc.get("note") or "").startswith("indistinguishable")
                                       else None)
        return cls(doc["name"], dict(doc["params"]), doc["gap_after"], doc["shrink"], bool(doc["significant"]),
                   doc.get("p_value"), doc.get("wilcoxon_p"), doc.get("held_out_improvement_fraction"),
                   doc.get("added_in_round"), bool(doc.get("named", False)), doc.get("note"),
                   doc.get("p_value_given_others"), doc.get("median_improvement_given_others"),
                   None if pair is None else tuple(pair), doc.get("params_without_discovered_terms"),
                   status=status, rejected_because=tuple(doc.get("rejected_because", ())),
                   uncertainty=None if unc is None else {p: ParameterInterval.from_dict(v) for p, v in unc.items()},
                   derived=None if der is None else {p: ParameterInterval.from_dict(v) for p, v in der.items()},
                   gap_change=doc.get("gap_change"), gap_change_std_error=doc.get("gap_change_std_error"),
                   gap_without_given_others=doc.get("gap_without_given_others"),
                   gap_change_given_others=doc.get("gap_change_given_others"),
                   gap_change_given_others_std_error=doc.get("gap_change_given_others_std_error"))


@dataclass(frozen=True, eq=False)
class DiagnosisInternals:
    """What the figures and the report need beyond diagnosis.json: the problem and the fits before and after."""

    problem: DiagnosisProblem
    base: GapFit  #: the calibrated simulation alone
    final: GapFit  #: with the identified effects

    @property
    def runs(self) -> tuple[RunAccelerations, ...]:
        return self.problem.runs

    @property
    def model(self):
        return self.problem.model


@dataclass(frozen=True)
class Diagnosis:
    """A data set's diagnosis (diagnosis.json, docs/formats.md).

    Attributes
    ----------
    model : the simulation model's registry name
    simulation : the calibrated simulation's scalar record
    identified : the effects named as causes, in the order added
    indistinguishable : pairs of effects the data cannot tell apart (``validation.diagnosis.identify.elimination``)
    model_effects : every effect the final model fits (the named ones and one of each indistinguishable pair)
    dropped_by_backward_check, greedy_identified : the backward check's drops and the greedy rounds' choice
    calibration : pressure, height origin, the model's calibrated parameters and a pressure drift
    gap_before, gap_after : the scalar gap of the calibrated simulation alone and with the model's effects
    gap_definition, gap_components, gap_component_forms : what the gap is made of
    gap_per_run : ``{"before", "after", "runs"}``
    noise_floor, noise_floor_note : the mean noise floor subtracted from every gap
    effects : every candidate's :class:`EffectVerdict`, the model's effects first
    localization, long_time, remaining_gap, identification_rounds : the documents of docs/formats.md
    data_warnings : warnings about the data (code and message)
    skipped_files : files the loader skipped, with reasons
    glitch_frames_masked : tracking glitches masked by the loader
    settings : the test settings (alpha, smallest attainable p, ...)
    constants : every constant the simulation was built from, with where it came from
        (:func:`~validation.diagnosis.summarise.constants.constants_used`)
    model_comparison : every registered force model calibrated on the runs, side by side, with its static
        coefficients and restoring curves (:mod:`~validation.diagnosis.summarise.calibrated_simulations`; None unless
        asked for: the report stores it)
    overlay : one run's data against the calibrated simulation with the identified effects (None unless asked for)
    data_set : the diagnosed data set: its ``path`` (absolute), its ``meta`` (meta.json as read) and its ``runs``
    internals : the problem and the fits before and after, for the figures (None when read from JSON)
    """

    model: str
    simulation: Mapping[str, Any]
    identified: tuple[str, ...]
    indistinguishable: tuple[Mapping[str, Any], ...]
    model_effects: tuple[str, ...]
    dropped_by_backward_check: tuple[str, ...]
    greedy_identified: tuple[str, ...]
    calibration: Mapping[str, Any]
    gap_before: float
    gap_after: float
    gap_definition: str
    gap_components: tuple[str, ...]
    gap_component_forms: Mapping[str, str]
    gap_per_run: Mapping[str, Sequence]
    noise_floor: float
    noise_floor_note: str
    effects: tuple[EffectVerdict, ...]
    localization: Mapping[str, Any]
    long_time: Mapping[str, Any]
    remaining_gap: Mapping[str, Any]
    identification_rounds: tuple[Mapping[str, Any], ...]
    data_warnings: tuple[Mapping[str, Any], ...] = ()
    skipped_files: tuple = ()
    glitch_frames_masked: int = 0
    settings: Mapping[str, Any] = field(default_factory=dict)
    constants: tuple[Mapping[str, Any], ...] = ()
    model_comparison: Mapping[str, Any] | None = None
    overlay: Mapping[str, Any] | None = None
    data_set: Mapping[str, Any] | None = None
    internals: DiagnosisInternals | None = field(default=None, compare=False, repr=False)

    def effect(self, name: str) -> EffectVerdict:
        """The verdict of the candidate ``name`` (KeyError if it was not a candidate).  Its ``status`` says whether it
        is named, one of an indistinguishable pair or rejected (with ``rejected_because``); a rejected candidate's
        :meth:`EffectVerdict.estimate` raises :class:`RejectedCandidateError`."""
        for e in self.effects:
            if e.name == name:
                return e
        raise KeyError(f"{name} was not a candidate of this diagnosis")

    def calibration_estimate(self, key: str) -> ParameterInterval:
        """A calibrated number (``pressure_amplitude_pa``, ``y_origin_height_m`` or a model parameter such as
        ``gap_m``) with its standard error and 95 % interval; "not determined" with the reason when the data give no
        finite interval (or the diagnosis.json was written without errors)."""
        doc = (self.calibration.get("uncertainty") or {}).get(key)
        if doc is None:
            if key not in self.calibration:
                raise KeyError(f"the calibration has no {key!r}")
            return ParameterInterval(float(self.calibration[key]), None, None, None, "no error was computed")
        return ParameterInterval.from_dict(doc)

    def to_json(self) -> dict[str, Any]:
        """The diagnosis.json document, in its documented key order."""
        return {"model": self.model, "simulation": dict(self.simulation), "identified": list(self.identified),
                "indistinguishable": [dict(p) for p in self.indistinguishable],
                "model_effects": list(self.model_effects),
                "dropped_by_backward_check": list(self.dropped_by_backward_check),
                "greedy_identified": list(self.greedy_identified), "calibration": dict(self.calibration),
                "gap_before": self.gap_before, "gap_after": self.gap_after, "gap_definition": self.gap_definition,
                "gap_components": list(self.gap_components), "gap_component_forms": dict(self.gap_component_forms),
                "gap_per_run": dict(self.gap_per_run), "noise_floor": self.noise_floor,
                "noise_floor_note": self.noise_floor_note, "effects": [e.to_json() for e in self.effects],
                "localization": dict(self.localization), "long_time": dict(self.long_time),
                "remaining_gap": dict(self.remaining_gap),
                "identification_rounds": [dict(r) for r in self.identification_rounds],
                "data_warnings": [dict(w) for w in self.data_warnings], "skipped_files": list(self.skipped_files),
                "glitch_frames_masked": self.glitch_frames_masked, "settings": dict(self.settings),
                "constants": [dict(c) for c in self.constants],
                **({} if self.model_comparison is None else {"model_comparison": dict(self.model_comparison)}),
                **({} if self.overlay is None else {"overlay": dict(self.overlay)}),
                **({} if self.data_set is None else {"data_set": dict(self.data_set)})}

    @classmethod
    def from_json(cls, doc: Mapping[str, Any]) -> "Diagnosis":
        """The diagnosis of a diagnosis.json document (the keys added since the first layout are optional)."""
        return cls(
            model=doc.get("model") or _reference_model(), simulation=dict(doc.get("simulation", {})),
            identified=tuple(doc["identified"]), indistinguishable=tuple(doc.get("indistinguishable", ())),
            model_effects=tuple(doc.get("model_effects", doc["identified"])),
            dropped_by_backward_check=tuple(doc.get("dropped_by_backward_check", ())),
            greedy_identified=tuple(doc.get("greedy_identified", doc["identified"])),
            calibration=dict(doc["calibration"]), gap_before=doc["gap_before"], gap_after=doc["gap_after"],
            gap_definition=doc.get("gap_definition", ""), gap_components=tuple(doc.get("gap_components", ())),
            gap_component_forms=dict(doc.get("gap_component_forms", {})), gap_per_run=dict(doc.get("gap_per_run", {})),
            noise_floor=doc.get("noise_floor", 0.0), noise_floor_note=doc.get("noise_floor_note", ""),
            effects=tuple(EffectVerdict.from_json(e) for e in doc.get("effects", ())),
            localization=dict(doc.get("localization", {})), long_time=dict(doc.get("long_time", {})),
            remaining_gap=dict(doc.get("remaining_gap", {})),
            identification_rounds=tuple(doc.get("identification_rounds", ())),
            data_warnings=tuple(doc.get("data_warnings", ())), skipped_files=tuple(doc.get("skipped_files", ())),
            glitch_frames_masked=int(doc.get("glitch_frames_masked", 0)), settings=dict(doc.get("settings", {})),
            constants=tuple(doc.get("constants", ())), model_comparison=doc.get("model_comparison"),
            overlay=doc.get("overlay"), data_set=doc.get("data_set"))
