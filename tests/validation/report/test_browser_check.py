"""The headless-browser check: a written report renders in Chromium; a broken image is detected."""
import numpy as np

from validation.report.browser_check import check_report_in_browser


def test_report_renders_in_headless_chromium(small_report, tmp_path, chromium_required):
    check = check_report_in_browser(small_report, tmp_path / "shot.png")
    assert check.console == [], check.console
    assert check.images_total == 2 and check.images_ok == 2 and not check.broken_images
    import matplotlib.image as mpimg

    img = mpimg.imread(check.screenshot)
    assert img.shape[0] > 500 and len(np.unique(img[..., 0])) > 10  # a rendered page, not blank


def test_broken_image_is_detected(tmp_path, chromium_required):
    page = tmp_path / "bad.html"
    page.write_text('<html><body><img alt="nothing" src="data:image/png;base64,AAAA"></body></html>')
    check = check_report_in_browser(page, tmp_path / "shot.png")
    assert check.broken_images == ["nothing"] and check.images_ok == 0
