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


def test_identified_effects_add_their_static_coefficients():
    """Pair scattering's -kappa cos^2(k (Z_eq + y)) theta adds kappa k^2 cos(2 k Z_eq) to theta*y^2 and
    -kappa cos^2(k Z_eq) to theta (Taylor); on a small box the least squares approaches them."""
    from validation.report_builder import effect_static_coefficients

    k, z_eq, kappa = 836.2, -4.289e-4, 1.95e4
    diag = {"identified": ["pair_scattering"], "effects": [{"name": "pair_scattering", "params": {"kappa": kappa}}]}
    c = effect_static_coefficients(diag, k, z_eq, theta_max=0.05, y_max=20e-6)
    # box of +-20 um: the next Taylor term (y^4) shifts the y^2 coefficient by ~(k y_max)^2 / 3 ~ 1e-4
    np.testing.assert_allclose(c["y^2*theta"], kappa * k**2 * np.cos(2 * k * z_eq), rtol=1e-3)
    np.testing.assert_allclose(c["theta"], -kappa * np.cos(k * z_eq) ** 2, rtol=1e-6)
    np.testing.assert_allclose(c["y*theta"], kappa * k * np.sin(2 * k * z_eq), rtol=1e-3)
    assert abs(c["y^2"]) < 1e-6 * abs(c["y^2*theta"])  # odd in theta: no theta-free terms
    assert effect_static_coefficients({"identified": [], "effects": []}, k, z_eq, 0.3, 1e-4) == {}
