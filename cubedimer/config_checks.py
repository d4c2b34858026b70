"""Construction-time checks of the suite's frozen configuration dataclasses: one-line ``ValueError`` messages.

Every config's ``__post_init__`` calls these, so a bad value fails where the config is made, before any work,
with a message naming the config, the field and the value (``"RefineConfig.max_evals must be a whole number
>= 1, got 0"``).
"""
from __future__ import annotations

import math
import numbers

__all__ = ["check_whole", "check_positive", "check_non_negative", "check_fraction", "check_choice", "check_choices",
           "check_bounds", "check_above", "check_that"]


def _is_number(value: object) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def check_whole(owner: object, name: str, minimum: int = 1, optional: bool = False) -> None:
    """``owner.name`` is a whole number >= ``minimum`` (or None when ``optional``)."""
    v = getattr(owner, name)
    if optional and v is None:
        return
    if not (isinstance(v, numbers.Integral) and not isinstance(v, bool) and v >= minimum):
        raise ValueError(f"{type(owner).__name__}.{name} must be a whole number >= {minimum}, got {v!r}")


def check_positive(owner: object, name: str, optional: bool = False) -> None:
    """``owner.name`` is a finite number > 0 (or None when ``optional``)."""
    v = getattr(owner, name)
    if optional and v is None:
        return
    if not (_is_number(v) and math.isfinite(v) and v > 0):
        raise ValueError(f"{type(owner).__name__}.{name} must be a positive finite number, got {v!r}")


def check_above(owner: object, name: str, bound: float) -> None:
    """``owner.name`` is a finite number > ``bound``."""
    v = getattr(owner, name)
    if not (_is_number(v) and math.isfinite(v) and v > bound):
        raise ValueError(f"{type(owner).__name__}.{name} must be a finite number above {bound:g}, got {v!r}")


def check_non_negative(owner: object, name: str) -> None:
    """``owner.name`` is a finite number >= 0."""
    v = getattr(owner, name)
    if not (_is_number(v) and math.isfinite(v) and v >= 0):
        raise ValueError(f"{type(owner).__name__}.{name} must be a finite number >= 0, got {v!r}")


def check_fraction(owner: object, name: str, closed: bool = False, zero: bool | None = None) -> None:
    """``owner.name`` lies in (0, 1), or in [0, 1] when ``closed``; ``zero`` overrides whether 0 itself is allowed
    (``zero=True``: [0, 1), a share that may be none but never all)."""
    v = getattr(owner, name)
    low_ok = closed if zero is None else zero
    ok = _is_number(v) and (v >= 0.0 if low_ok else v > 0.0) and (v <= 1.0 if closed else v < 1.0)
    if not ok:
        interval = ("[" if low_ok else "(") + "0, 1" + ("]" if closed else ")")
        raise ValueError(f"{type(owner).__name__}.{name} must lie in {interval}, got {v!r}")


def check_choice(owner: object, name: str, choices, what: str = "") -> None:
    """``owner.name`` is one of ``choices`` (``what``: the kind of thing chosen, for the message)."""
    v = getattr(owner, name)
    if v not in choices:
        raise ValueError(f"{type(owner).__name__}.{name}: unknown {what + ' ' if what else ''}{v!r} "
                         f"(use one of {', '.join(map(str, choices))})")


def check_choices(owner: object, name: str, choices, what: str = "", allow_empty: bool = True) -> None:
    """Every entry of the sequence ``owner.name`` is one of ``choices`` (and there is one at least, unless
    ``allow_empty``)."""
    v = tuple(getattr(owner, name))
    unknown = [c for c in v if c not in choices]
    if unknown or (not v and not allow_empty):
        raise ValueError(f"{type(owner).__name__}.{name}: unknown {what + ' ' if what else ''}"
                         f"{', '.join(map(repr, unknown)) or '(none given)'} (use any of {', '.join(map(str, choices))})")


def check_bounds(owner: object, name: str, strict: bool = False) -> None:
    """``owner.name`` is a pair (low, high) of finite numbers with 0 < low <= high (0 < low < high when
    ``strict``)."""
    v = getattr(owner, name)
    try:
        lo, hi = v
        ok = (_is_number(lo) and _is_number(hi) and math.isfinite(hi) and 0 < lo and (lo < hi if strict else lo <= hi))
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise ValueError(f"{type(owner).__name__}.{name} must be (low, high) with 0 < low {'<' if strict else '<='} high, "
                         f"got {v!r}")


def check_that(owner: object, ok: bool, requirement: str) -> None:
    """A rule that no single-field check states (a relation between fields): ``requirement`` says it, in words."""
    if not ok:
        raise ValueError(f"{type(owner).__name__}: {requirement}")
