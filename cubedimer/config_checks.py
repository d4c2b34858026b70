"""Construction-time checks of the suite's frozen configuration dataclasses: one-line ``ValueError`` messages.

Every config's ``__post_init__`` calls these, so a bad value fails where the config is made, before any work,
with a message naming the config, the field and the value (``"RefineConfig.max_evals must be a whole number
>= 1, got 0"``).
"""
from __future__ import annotations

import math
import numbers

__all__ = ["check_whole", "check_positive", "check_non_negative", "check_fraction", "check_choice"]


def _is_number(value: object) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def check_whole(owner: object, name: str, minimum: int = 1) -> None:
    """``owner.name`` is a whole number >= ``minimum``."""
    v = getattr(owner, name)
    if not (isinstance(v, numbers.Integral) and not isinstance(v, bool) and v >= minimum):
        raise ValueError(f"{type(owner).__name__}.{name} must be a whole number >= {minimum}, got {v!r}")


def check_positive(owner: object, name: str) -> None:
    """``owner.name`` is a finite number > 0."""
    v = getattr(owner, name)
    if not (_is_number(v) and math.isfinite(v) and v > 0):
        raise ValueError(f"{type(owner).__name__}.{name} must be a positive finite number, got {v!r}")


def check_non_negative(owner: object, name: str) -> None:
    """``owner.name`` is a finite number >= 0."""
    v = getattr(owner, name)
    if not (_is_number(v) and math.isfinite(v) and v >= 0):
        raise ValueError(f"{type(owner).__name__}.{name} must be a finite number >= 0, got {v!r}")


def check_fraction(owner: object, name: str, closed: bool = False) -> None:
    """``owner.name`` lies in (0, 1), or in [0, 1] when ``closed``."""
    v = getattr(owner, name)
    ok = _is_number(v) and ((0.0 <= v <= 1.0) if closed else (0.0 < v < 1.0))
    if not ok:
        raise ValueError(f"{type(owner).__name__}.{name} must lie in {'[0, 1]' if closed else '(0, 1)'}, got {v!r}")


def check_choice(owner: object, name: str, choices) -> None:
    """``owner.name`` is one of ``choices``."""
    v = getattr(owner, name)
    if v not in choices:
        raise ValueError(f"{type(owner).__name__}.{name}: unknown {v!r} (use one of {', '.join(map(str, choices))})")
