"""The blind check's hidden draws and scoring."""
import pytest

from validation.blind import STRENGTHS, draw_case, score_case, summarize


def test_blind_draws_are_seeded_and_scored():
    a, b = draw_case(7, 3), draw_case(7, 3)
    assert a == b and draw_case(8, 3) != a  # same seed, same hidden truth
    for name, params in a["effects"].items():
        for p, v in params.items():
            lo, hi, signed = STRENGTHS[name][p]
            assert lo <= abs(v) <= hi
    case = {"index": 0, "effects": {"pair_scattering": {"kappa": 1e4}}, "pressure_error": 0.05, "twin_seed": 1}
    diag = {"identified": ["pair_scattering", "linear_damping"], "gap_before": 0.4, "gap_after": 0.02,
            "effects": [{"name": "pair_scattering", "params": {"kappa": 1.1e4}},
                        {"name": "linear_damping", "params": {"gamma_y": 0.1, "gamma_theta": 0.1}}],
            "calibration": {"pressure_amplitude_pa": 3100.0}}
    r = score_case(case, {"pressure_amplitude_pa": 3150.0}, diag, None)
    assert not r["exact"] and r["parameter_relative_error"]["pair_scattering"]["kappa"] == pytest.approx(0.1)
    s = summarize([r])
    assert s["per_effect"]["linear_damping"]["fp"] == 1 and s["per_effect"]["pair_scattering"]["recall"] == 1.0
    assert s["median_shrink_with_effect"] == pytest.approx(0.95)
