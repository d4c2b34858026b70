"""Blind check of the gap diagnosis on data sets whose causes are hidden.

* :mod:`validation.blind.config` - :class:`BlindConfig` and the case kinds (:data:`KINDS`);
* :mod:`validation.blind.candidates` - twin data sets with hidden candidate effects, their draws and scores;
* :mod:`validation.blind.extended` - causes no candidate describes (a cubic hinge term, a y-dependent damping), a
  drifting pressure, tracking glitches against clean twins, a file in the wrong units;
* :mod:`validation.blind.twin_like` - the surrogate-based generator of the data sets with non-candidate causes;
* :mod:`validation.blind.study` - running (or resuming) a study and its per-kind table.
"""
from .candidates import (N_EFFECT_PROBABILITIES, STRENGTHS, candidates_table, confusion_figure, draw_case, run_case,
                         score_case, summarize)
from .config import KINDS, BlindConfig
from .extended import (OUT_OF_CANDIDATE, draw_extended_case, insert_glitches, run_extended_case, score_drift,
                       score_glitches, score_out_of_candidate, score_unit_slip, slip_units)
from .study import blind_table, run_blind, summarize_kind
from .twin_like import TwinLikeConfig, TwinLikeError, write_twin_like_dataset

__all__ = ["STRENGTHS", "N_EFFECT_PROBABILITIES", "KINDS", "OUT_OF_CANDIDATE", "BlindConfig", "draw_case",
           "draw_extended_case", "run_case", "run_extended_case", "score_case", "score_out_of_candidate",
           "score_drift", "score_glitches", "score_unit_slip", "insert_glitches", "slip_units", "summarize",
           "summarize_kind", "run_blind", "blind_table", "candidates_table", "confusion_figure",
           "write_twin_like_dataset", "TwinLikeConfig", "TwinLikeError"]
