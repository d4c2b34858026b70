"""Atomic writers for validation outputs (JSON with non-finite numbers as null, text)."""
from __future__ import annotations

import json
import math
from pathlib import Path

from fitting.atomic import atomic_write_text

__all__ = ["write_json_atomic", "json_safe"]


def json_safe(obj):
    """Replace NaN and infinities by None recursively (strict JSON)."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_safe(v) for v in obj]
    return obj


def write_json_atomic(path: str | Path, obj) -> None:
    atomic_write_text(path, json.dumps(json_safe(obj), indent=2, allow_nan=False) + "\n")

