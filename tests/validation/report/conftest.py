"""A small report with two figures and a table, written by the HTML writer."""
import numpy as np
import pytest

from validation.report import Figure, Section, Table, write_report


@pytest.fixture
def small_report(tmp_path):
    import matplotlib.pyplot as plt

    figs = []
    for i in range(2):
        fig, ax = plt.subplots(figsize=(3, 2))
        ax.plot(np.arange(5) ** (i + 1))
        ax.set_xlabel("t [s]")
        ax.set_ylabel("y [um]")
        p = tmp_path / f"fig{i}.png"
        fig.savefig(p)
        plt.close(fig)
        figs.append(Figure(p, f"figure {i}"))
    sections = [Section("data", "The data", "What the data show.", figs, [Table("numbers", ["term", "value"], [["theta", 1.5], ["y", float("nan")]])], {"a": 1.0, "b": float("nan")})]
    return write_report(sections, tmp_path / "report", "Test report")
