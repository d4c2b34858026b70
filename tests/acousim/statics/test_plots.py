"""Sweep figures name the force model the sweep was made with (a full-wave sweep is not titled Gor'kov)."""
import numpy as np
import pytest

from acousim.statics.plots import plot_restoring_force, plot_restoring_torque
from acousim.statics.sweep import SweepResult


def _sweep(model: str) -> SweepResult:
    theta, y = np.linspace(-0.9, 0.9, 5), np.linspace(-1e-4, 1e-4, 4)
    tt, yy = np.meshgrid(theta, y, indexing="ij")
    cols = {"theta": tt, "y": yy, "z_com": yy, "yddot": -yy, "thetaddot": -tt}
    return SweepResult(theta, y, cols, {"model": model})


@pytest.mark.parametrize("model, label", [("gorkov", "Gor'kov model"), ("fullwave", "full wave model")])
def test_the_titles_name_the_sweeps_model(model, label):
    import matplotlib.pyplot as plt

    for plot in (plot_restoring_force, plot_restoring_torque):
        fig = plot(_sweep(model))
        assert fig.axes[0].get_title().endswith(f"({label})")
        plt.close(fig)
