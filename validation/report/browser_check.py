"""Open a report in headless Chromium: console messages, image decoding and a screenshot.

The report is static (no scripts, images as data URIs).  :func:`check_report_in_browser` loads a
copy of it with a small probe appended that, once the page has loaded, logs ``images-ok N`` or
``broken-image NAME`` for every <img>; Chromium writes console output to stderr
(``--enable-logging=stderr``), from which the messages are parsed.  Anything else on the console
is a console error of the page.
"""
from __future__ import annotations

import re
import shutil
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path

__all__ = ["BrowserCheck", "find_chromium", "check_report_in_browser"]

_PROBE = """<script>
window.addEventListener('load', function () {
  var imgs = document.images, bad = 0;
  for (var i = 0; i < imgs.length; i++) {
    if (!imgs[i].complete || imgs[i].naturalWidth === 0) { bad++; console.log('broken-image ' + imgs[i].alt); }
  }
  console.log('images-ok ' + (imgs.length - bad) + ' of ' + imgs.length);
});
</script>"""

_CONSOLE = re.compile(r'CONSOLE[^\]]*\]\s+"(.*)", source: (\S+)')


@dataclass(frozen=True)
class BrowserCheck:
    console: list[str]  # console messages of the page itself (excluding the probe's)
    images_ok: int
    images_total: int
    broken_images: list[str]
    screenshot: Path


def find_chromium() -> str | None:
    """Path of a Chromium/Chrome executable, or None."""
    for name in ("chromium", "chromium-browser", "google-chrome", "chrome"):
        path = shutil.which(name)
        if path:
            return path
    return None


def check_report_in_browser(html_path: str | Path, screenshot: str | Path, window=(1200, 2400), timeout: float = 60.0) -> BrowserCheck:
    """Render ``html_path`` headless, return its console messages, image status and a screenshot PNG."""
    exe = find_chromium()
    if exe is None:
        raise FileNotFoundError("no Chromium found: install Debian's `chromium` package (make test does this as root)")
    html_path, screenshot = Path(html_path), Path(screenshot)
    with tempfile.TemporaryDirectory(prefix="report-check-") as tmp:
        probe = Path(tmp) / "probed.html"
        text = html_path.read_text()
        probe.write_text(text.replace("</body>", _PROBE + "</body>") if "</body>" in text else text + _PROBE)
        cmd = [exe, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
               "--disable-background-networking", "--disable-component-update", "--disable-sync",
               f"--user-data-dir={Path(tmp) / 'profile'}", "--enable-logging=stderr", "--v=0",
               "--virtual-time-budget=5000", f"--window-size={window[0]},{window[1]}",
               f"--screenshot={screenshot}", probe.as_uri()]
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    messages = [m.group(1) for m in _CONSOLE.finditer(proc.stderr)]
    ok, total, broken, console = 0, -1, [], []
    for m in messages:
        if m.startswith("images-ok "):
            parts = m.split()
            ok, total = int(parts[1]), int(parts[3])
        elif m.startswith("broken-image "):
            broken.append(m[len("broken-image "):])
        else:
            console.append(m)
    if not screenshot.exists():
        raise RuntimeError(f"Chromium wrote no screenshot (exit {proc.returncode}): {proc.stderr[-500:]}")
    return BrowserCheck(console, ok, total, broken, screenshot)
