"""The HTML report writer: self-contained, every figure embedded, finite numbers, renders in Chromium."""
import json
import re
from pathlib import Path

import numpy as np
import pytest

from validation.report import Figure, Section, Table, write_report


@pytest.fixture
def small_report(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
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


def test_report_is_self_contained(small_report):
    text = small_report.read_text()
    srcs = re.findall(r'src="([^"]+)"', text)
    assert len(srcs) == 2 and all(s.startswith("data:image/png;base64,") for s in srcs)
    assert "<script" not in text and "http" not in text
    assert sorted(p.name for p in (small_report.parent / "figures").iterdir()) == ["fig0.png", "fig1.png"]
    numbers = json.loads((small_report.parent / "numbers.json").read_text())
    assert numbers["data"] == {"a": 1.0, "b": None}  # strict JSON: NaN written as null


def test_report_renders_in_headless_chromium(small_report, tmp_path, chromium_required):
    from validation.browser import check_report_in_browser

    check = check_report_in_browser(small_report, tmp_path / "shot.png")
    assert check.console == [], check.console
    assert check.images_total == 2 and check.images_ok == 2 and not check.broken_images
    import matplotlib.image as mpimg

    img = mpimg.imread(check.screenshot)
    assert img.shape[0] > 500 and len(np.unique(img[..., 0])) > 10  # a rendered page, not blank


def test_broken_image_is_detected(tmp_path, chromium_required):
    from validation.browser import check_report_in_browser

    page = tmp_path / "bad.html"
    page.write_text('<html><body><img alt="nothing" src="data:image/png;base64,AAAA"></body></html>')
    check = check_report_in_browser(page, tmp_path / "shot.png")
    assert check.broken_images == ["nothing"] and check.images_ok == 0
