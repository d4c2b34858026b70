"""With the levitator as a resonator a run that leaves the trap is an outcome, recorded up to the escape as a fold
is (acousim.twin.simulation); without one an escape stops the data set."""
import json

import numpy as np
import pytest

from acousim.twin import DropProtocol, TwinConfig, TwinError, simulate_dataset
from cubedimer.dataset import load_dataset
from cubedimer.executor import ExecutorConfig

SERIAL = ExecutorConfig(workers=1)
#: The Gor'kov dimer with a strongly coupled cavity (Q 250, 30 mm^2, the drive 1.5 half-widths above the
#: resonance): y grows by itself and the dimer leaves the trap within 3 s.
FED = dict(runs=2, duration=3.0, seed=3, transducer_q=250.0, cavity_detuning=-1.5, cavity_area=3e-5,
           protocol=DropProtocol(t_off=(0.003, 0.004)))


def test_an_escape_with_a_resonator_is_an_outcome(tmp_path):
    truth = simulate_dataset(TwinConfig(**FED), tmp_path / "d", SERIAL, progress=False)
    events = [r["event"] for r in truth["runs_detail"]]
    assert truth["escaped_runs"] == 2 and truth["folded_runs"] == 0
    assert all(e["event"] == "escaped" and 0 < e["t_s"] < FED["duration"] for e in events)
    states = np.load(tmp_path / "d" / "truth_states.npz")
    for i, e in enumerate(events, 1):  # recorded up to the escape, NaN after it
        s = states[f"run{i:02d}"]
        n = int(np.isfinite(s[:, 0]).sum())
        assert np.all(np.isfinite(s[:n])) and np.all(np.isnan(s[n:])) and n < s.shape[0]
        assert states["t"][n - 1] <= e["t_s"] + 1e-9
    assert len(load_dataset(tmp_path / "d", report=lambda message: None).runs) == 2
    assert json.loads((tmp_path / "d" / "truth.json").read_text())["escaped_runs"] == 2


def test_an_escape_without_a_resonator_still_stops_the_data_set(tmp_path):
    with pytest.raises(TwinError, match="fell out of the trap"):
        simulate_dataset(TwinConfig(runs=1, duration=0.5, protocol=DropProtocol(t_off=(0.012, 0.015))),
                         tmp_path / "d", SERIAL, progress=False)
    assert list(tmp_path.iterdir()) == []
