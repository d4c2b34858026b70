"""The generic-system worked example runs from an installed package (``fitting synth --system generic``), and log
lines name a generic system's coordinates in their declared units."""
import json

import numpy as np
import pytest

from cubedimer.dataset import LoadConfig, load_dataset
from cubedimer.system import LEVITATED_DIMER, SYSTEM_KINDS, read_system
from fitting.cli import main
from fitting.synthetic import GENERIC_EXAMPLE_SYSTEM, generic_example_model


def test_synth_writes_the_generic_example_as_a_declared_system(tmp_path):
    out = tmp_path / "generic"
    assert main(["synth", str(out), "--system", "generic", "--seed", "5"]) == 0
    ds = load_dataset(out, config=LoadConfig(systems=SYSTEM_KINDS))
    assert ds.system.generic and ds.system.names == ("phi1", "phi2") and len(ds.runs) == 5
    truth = json.loads((out / "truth.json").read_text())["equations"]
    # the truth in the declared names is the model's, coefficient for coefficient (exact: the same floats)
    expected = generic_example_model().equations()
    assert truth["phi1ddot"]["phi1^3"] == expected["yddot"]["y^3"] == 15.0
    assert truth["phi2ddot"]["phi2"] == pytest.approx(-(2 * np.pi * 2.0) ** 2, rel=1e-15)
    # the CSV holds degrees; loaded, the angles are radians: amplitudes drawn in 0.3-0.6 rad, noise 0.002 rad
    assert all(0.25 < np.nanmax(np.abs(r.y)) < 0.7 for r in ds.runs)
    assert json.loads((out / "meta.json").read_text()) == {"system": GENERIC_EXAMPLE_SYSTEM}


@pytest.mark.parametrize("system, text", [
    (LEVITATED_DIMER, "y 0.000415 m, theta 0.308"),
    (read_system({"system": GENERIC_EXAMPLE_SYSTEM}), "phi1 0.000415 rad, phi2 0.308 rad"),
])
def test_log_values_carry_the_declared_names_and_units(system, text):
    assert system.describe((4.15e-4, 0.308)) == text
