"""The HTML report writer: self-contained, every figure embedded, finite numbers."""
import json
import re


def test_report_is_self_contained(small_report):
    text = small_report.read_text()
    srcs = re.findall(r'src="([^"]+)"', text)
    assert len(srcs) == 2 and all(s.startswith("data:image/png;base64,") for s in srcs)
    assert "<script" not in text and "http" not in text
    assert sorted(p.name for p in (small_report.parent / "figures").iterdir()) == ["fig0.png", "fig1.png"]
    numbers = json.loads((small_report.parent / "numbers.json").read_text())
    assert numbers["data"] == {"a": 1.0, "b": None}  # strict JSON: NaN written as null
