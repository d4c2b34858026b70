"""The verdicts beside the levitator's cavity (validation.diagnosis.summarise.cavity_verdicts): pair scattering within
the cavity's own share of the hinge's stiffness is rejected, and the cavity's mode is not determined beside a negative
damping of y."""
import math
from types import SimpleNamespace

import numpy as np
import pytest

from validation.diagnosis.prepare.cavity_lag import derived_quantities, quasi_static_response
from validation.diagnosis.summarise import cavity_verdicts
from validation.diagnosis.summarise.result import EffectVerdict
from validation.diagnosis.summarise.uncertainty import ParameterInterval, interval_from_error

TWO_K = 2 * 2 * math.pi * 45650.0 / 343.2  # 2k [1/m] of the default air and drive


def _verdict(name: str, params: dict, derived: dict | None = None) -> EffectVerdict:
    return EffectVerdict(name, params, 0.1, 0.5, True, 1e-3, 1e-3, 0.5, named=True, derived=derived)


def _problem():
    """A stand-in for the diagnosis problem: what named_only_beyond_cavity reads of it (its cavity's force model)."""
    return SimpleNamespace(_shared={"cavity_columns": SimpleNamespace(force_model=SimpleNamespace(two_k=TWO_K))})


@pytest.mark.parametrize("kappa, named", [
    (0.9, False),  # the blind false alarm (seed 15001, case 5: 0.90 1/s^2 against max|s - 1| K = 1.8 1/s^2)
    (-1.5, False),  # either sign: the size is compared
    (2000.0, True),  # the weakest drawn pair scattering, 20 times the hinge's stiffness
    (3.5, True)])  # just beyond the cavity's share: 3.5 cos^2(k Z_eq) = 3.07 against 0.03 x 100 = 3 1/s^2
def test_pair_scattering_within_the_cavitys_share_of_the_hinge_stiffness_is_rejected(monkeypatch, kappa, named):
    """Beside a named cavity, pair scattering is named only where kappa cos^2(k Z_eq) exceeds the cavity's own
    modulation of the hinge's acoustic stiffness, max |s - 1| K; else rejected (within_cavity_response), the cavity and
    the other effects untouched."""
    monkeypatch.setattr(cavity_verdicts, "cavity_modulation", lambda problem, cal, gains: 0.03)
    monkeypatch.setattr(cavity_verdicts, "hinge_stiffness", lambda problem, cal: 100.0)
    z_eq = -0.35865 / (TWO_K / 2)  # the default dimer's k Z_eq: cos^2 = 0.877
    cal = SimpleNamespace(equilibrium_height_m=z_eq)
    effects = [_verdict("linear_damping", {"gamma_y": 0.6, "gamma_theta": 1.2}),
               _verdict("cavity_lag", {"static_gain": -1.5e-3, "lag_gain": 2e-6}),
               _verdict("pair_scattering", {"kappa": kappa})]
    out = cavity_verdicts.named_only_beyond_cavity(effects, _problem(), cal)
    assert out[:2] == effects[:2]
    assert (out[2].status == "named") == named and out[2].named == named
    if not named:
        assert [r["code"] for r in out[2].rejected_because] == ["within_cavity_response"]
        reason = out[2].rejected_because[0]["reason"]  # both sides: kappa x 0.877 against 0.03 x 100
        stated = float(reason.split("kappa cos^2(k Z_eq) = ")[1].split(" ")[0])
        # stated to 3 significant digits: within half a unit of the third digit, 0.5 % of a leading 1
        assert stated == pytest.approx(kappa * np.cos(0.35865) ** 2, rel=5e-3) and "= 3 1/s^2" in reason
    # without a named cavity the rule does not apply
    assert cavity_verdicts.named_only_beyond_cavity([effects[0], effects[2]], _problem(), cal)[1] == effects[2]


def test_the_mode_is_not_determined_beside_a_negative_damping_of_y():
    """Beside linear damping with gamma_y < 0 (the lag took more than the whole damping of y) the cavity's Q and
    detuning are not determined, with the reason; its quasi-static response, from the static gain alone, stays."""
    derived = {"quality_factor": interval_from_error(457.0, 18.5, 9),
               "detuning_half_widths": interval_from_error(0.33, 0.018, 9),
               "quasi_static_response": interval_from_error(134.0, 3.0, 9)}
    cavity = _verdict("cavity_lag", {"static_gain": -1.7e-3, "lag_gain": 9.8e-6}, derived)
    for gamma_y, determined in ((-3.02, False), (0.0, True), (0.39, True)):
        damping = _verdict("linear_damping", {"gamma_y": gamma_y, "gamma_theta": 1.2})
        out = cavity_verdicts.mode_only_with_a_positive_damping([damping, cavity])
        assert out[0] == damping
        for q in ("quality_factor", "detuning_half_widths"):
            assert out[1].derived[q].determined == determined and out[1].derived[q].value == derived[q].value
            assert determined or "gamma_y" in out[1].derived[q].reason
        assert out[1].derived["quasi_static_response"] == derived["quasi_static_response"]


@pytest.mark.parametrize("q, x", [(250.0, 1.0), (150.0, 0.5), (400.0, 3.0)])
def test_the_quasi_static_response_is_the_static_gains_combination_of_q_and_x(q, x):
    """Q x / (1 + x^2) from the fitted gains equals that of the mode they came from (the static gain alone: it stays
    where no mode has the gains), and the pressure scale divides the gains out as it does for Q and x."""
    from acousim.dynamics.resonator import CavityMode
    from validation.diagnosis.prepare.cavity_lag import gains_from_mode

    g = gains_from_mode(CavityMode(q, x), 45650.0)
    for scale in (1.0, 0.85):
        params = {"cavity_lag": {"static_gain": g.static_gain * scale, "lag_gain": g.lag_gain * scale}}
        out = derived_quantities(params, SimpleNamespace(pressure_scale=scale))["cavity_lag"]
        assert out["quasi_static_response"] == pytest.approx(quasi_static_response(q, x), rel=1e-9)  # round-off
        assert out["quality_factor"] == pytest.approx(q, rel=1e-9)
        no_mode = {"cavity_lag": {"static_gain": g.static_gain, "lag_gain": -g.lag_gain}}  # one sign: no mode
        out = derived_quantities(no_mode, SimpleNamespace(pressure_scale=1.0))["cavity_lag"]
        assert np.isnan(out["detuning_half_widths"]) and out["quasi_static_response"] == pytest.approx(
            quasi_static_response(q, x), rel=1e-9)
