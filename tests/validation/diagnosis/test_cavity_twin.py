"""The cavity's lag as a candidate on twin data with the levitator's resonator (acousim.dynamics.resonator): named
alone, not beside linear damping, with the mode's Q and detuning (docs/diagnosis.md, "The levitator's cavity as a
candidate")."""
import json

import pytest

from validation.diagnosis import DiagnoseConfig, diagnose_dataset

#: The resonator of the twin: Q and the drive's detuning above the resonance [half-widths] (the damping side).
MODE = {"quality_factor": 250.0, "detuning_half_widths": 1.5}


@pytest.fixture(scope="module")
def resonator_diagnosis(pipeline_cache):
    from acousim.twin import DropProtocol, TwinConfig

    # no air damping: the cavity is the only cause, so linear damping named beside it would be a false effect
    cfg = TwinConfig(runs=8, duration=2.0, seed=23, pressure_error=0.05, air_damping=False,
                     transducer_q=MODE["quality_factor"], cavity_detuning=MODE["detuning_half_widths"],
                     protocol=DropProtocol(theta_drop=(-0.2, 0.2), thetadot_drop=(-2.0, 2.0)))
    data = pipeline_cache.twin_dataset(cfg)
    truth = json.loads((data.parent / "truth.json").read_text())
    config = DiagnoseConfig(candidates=("linear_damping", "quadratic_drag", "cavity_lag"), long_time=False)
    diag = pipeline_cache.value("diagnosis", f"{data.parent.name} {config!r}",
                                lambda: diagnose_dataset(data, config, progress=False))
    return diag, truth


@pytest.mark.slow
def test_the_cavity_is_named_alone_with_its_mode(resonator_diagnosis):
    """The second-order columns (cavity_lag.second_order_ratios about the data set's reference mode) explain the
    resonator's damping and stiffness, so neither damping candidate is needed beside it; Q and x within 10 % and
    15 % (the static gain's remaining bias puts them 4-8 % low on the runs of docs/diagnosis.md)."""
    diag, truth = resonator_diagnosis
    assert truth["resonator"]["quality_factor"] == MODE["quality_factor"]
    assert list(diag.identified) == ["cavity_lag"] and not diag.indistinguishable
    assert diag.effect("linear_damping").rejected and diag.effect("quadratic_drag").rejected
    derived = diag.effect("cavity_lag").derived
    assert derived["quality_factor"].value == pytest.approx(MODE["quality_factor"], rel=0.10)
    assert derived["detuning_half_widths"].value == pytest.approx(MODE["detuning_half_widths"], rel=0.15)
    assert derived["quality_factor"].determined and derived["detuning_half_widths"].determined
    # the combination the static gain alone gives, Q x / (1 + x^2) = 115.4, within 10 % as Q (the static gain's bias)
    assert derived["quasi_static_response"].value == pytest.approx(250.0 * 1.5 / (1 + 1.5**2), rel=0.10)
    assert derived["quasi_static_response"].determined
