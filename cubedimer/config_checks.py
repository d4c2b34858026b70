"""Construction-time checks of the suite's frozen configuration dataclasses: one-line ``ValueError`` messages.

Every config's ``__post_init__`` calls these, so a bad value fails where the config is made, before any work,
with a message naming the config, the field and the value (``"RefineConfig.max_evals must be a whole number
>= 1, got 0"``).

A field that a command's option sets can be named by that option instead: give it the metadata :func:`named`
(``pressure_pa: float = field(default=3000.0, metadata=named("--pressure"))``), and the message names
``--pressure``.  A config whose package has its own error class (a subclass of ``ValueError`` that its command
turns into exit 2) makes its checks inside ``with raising(ThatError):``.
"""
from __future__ import annotations

import dataclasses
import math
import numbers
from contextlib import contextmanager
from typing import Callable, Iterator

__all__ = ["check_whole", "check_positive", "check_non_negative", "check_fraction", "check_choice", "check_choices",
           "check_bounds", "check_above", "check_in_range", "check_given", "check_builds", "check_that", "named",
           "raising"]

#: The field metadata key of the name a message gives a field (:func:`named`).
LABEL = "config_checks_label"


def named(label: str) -> dict[str, str]:
    """Field metadata naming the field by ``label`` (a command's option, ``"--pressure"``) in the checks' messages,
    instead of ``Config.field``."""
    return {LABEL: label}


@contextmanager
def raising(error: type[ValueError]) -> Iterator[None]:
    """Inside: a ``ValueError`` of a check (or of anything else called) leaves as ``error``, a subclass of
    ``ValueError``, with the same one-line message."""
    try:
        yield
    except error:
        raise
    except ValueError as exc:
        raise error(str(exc)) from None


def _is_number(value: object) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def _label(owner: object, name: str) -> str:
    """How a message names ``owner.name``: its :func:`named` label, else ``Config.name``."""
    fields = {f.name: f for f in dataclasses.fields(owner)} if dataclasses.is_dataclass(owner) else {}
    f = fields.get(name)
    if f is not None and LABEL in f.metadata:
        return f.metadata[LABEL]
    return f"{type(owner).__name__}.{name}"


def check_whole(owner: object, name: str, minimum: int = 1, optional: bool = False) -> None:
    """``owner.name`` is a whole number >= ``minimum`` (or None when ``optional``)."""
    v = getattr(owner, name)
    if optional and v is None:
        return
    if not (isinstance(v, numbers.Integral) and not isinstance(v, bool) and v >= minimum):
        raise ValueError(f"{_label(owner, name)} must be a whole number >= {minimum}, got {v!r}")


def check_positive(owner: object, name: str, optional: bool = False) -> None:
    """``owner.name`` is a finite number > 0 (or None when ``optional``)."""
    v = getattr(owner, name)
    if optional and v is None:
        return
    if not (_is_number(v) and math.isfinite(v) and v > 0):
        raise ValueError(f"{_label(owner, name)} must be a positive finite number, got {v!r}")


def check_above(owner: object, name: str, bound: float) -> None:
    """``owner.name`` is a finite number > ``bound``."""
    v = getattr(owner, name)
    if not (_is_number(v) and math.isfinite(v) and v > bound):
        raise ValueError(f"{_label(owner, name)} must be a finite number above {bound:g}, got {v!r}")


def check_non_negative(owner: object, name: str) -> None:
    """``owner.name`` is a finite number >= 0."""
    v = getattr(owner, name)
    if not (_is_number(v) and math.isfinite(v) and v >= 0):
        raise ValueError(f"{_label(owner, name)} must be a finite number >= 0, got {v!r}")


def check_fraction(owner: object, name: str, closed: bool = False, zero: bool | None = None) -> None:
    """``owner.name`` lies in (0, 1), or in [0, 1] when ``closed``; ``zero`` overrides whether 0 itself is allowed
    (``zero=True``: [0, 1), a share that may be none but never all)."""
    v = getattr(owner, name)
    low_ok = closed if zero is None else zero
    ok = _is_number(v) and (v >= 0.0 if low_ok else v > 0.0) and (v <= 1.0 if closed else v < 1.0)
    if not ok:
        interval = ("[" if low_ok else "(") + "0, 1" + ("]" if closed else ")")
        raise ValueError(f"{_label(owner, name)} must lie in {interval}, got {v!r}")


def check_choice(owner: object, name: str, choices, what: str = "") -> None:
    """``owner.name`` is one of ``choices`` (``what``: the kind of thing chosen, for the message)."""
    v = getattr(owner, name)
    if v not in choices:
        raise ValueError(f"{_label(owner, name)}: unknown {what + ' ' if what else ''}{v!r} "
                         f"(use one of {', '.join(map(str, choices))})")


def check_choices(owner: object, name: str, choices, what: str = "", allow_empty: bool = True) -> None:
    """Every entry of the sequence ``owner.name`` is one of ``choices`` (and there is one at least, unless
    ``allow_empty``)."""
    v = tuple(getattr(owner, name))
    unknown = [c for c in v if c not in choices]
    if unknown or (not v and not allow_empty):
        raise ValueError(f"{_label(owner, name)}: unknown {what + ' ' if what else ''}"
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
        raise ValueError(f"{_label(owner, name)} must be (low, high) with 0 < low {'<' if strict else '<='} high, "
                         f"got {v!r}")


def _interval(low: float, high: float, low_open: bool, high_open: bool) -> str:
    return f"{'(' if low_open else '['}{low:g}, {high:g}{')' if high_open else ']'}"


def check_in_range(owner: object, name: str, low: float, high: float, *, low_open: bool = False,
                   high_open: bool = False, unit: str = "", whole: bool = False, each: bool = False,
                   optional: bool = False) -> None:
    """``owner.name`` is a finite number in [low, high] (open at an end with ``low_open`` / ``high_open``; a whole
    number when ``whole``: an integer or an integral float); with ``each``, a non-empty sequence of such numbers.
    ``unit`` follows the interval in the message; None passes when ``optional``."""
    v = getattr(owner, name)
    if optional and v is None:
        return

    def ok(x: object) -> bool:
        return (_is_number(x) and math.isfinite(x) and (x > low if low_open else x >= low)
                and (x < high if high_open else x <= high) and (not whole or float(x).is_integer()))

    interval = _interval(low, high, low_open, high_open) + (f" {unit}" if unit else "")
    kind = "a whole number in" if whole else "lie in"
    if not each:
        if not ok(v):
            raise ValueError(f"{_label(owner, name)} must {'be ' if whole else ''}{kind} {interval}, got {v!r}")
        return
    try:
        values = list(v)
    except TypeError:
        values = None
    if not values or not all(ok(x) for x in values):
        raise ValueError(f"{_label(owner, name)}: every value must {'be ' if whole else ''}{kind} {interval} (one at "
                         f"least), got {values if values is not None else v!r}")


def check_given(owner: object, name: str, what: str) -> None:
    """The sequence ``owner.name`` holds one ``what`` at least (``what``: what to give, for the message)."""
    if not tuple(getattr(owner, name)):
        raise ValueError(f"{_label(owner, name)}: give at least one {what}")


def check_builds(owner: object, label: str, build: Callable[[], object]) -> None:
    """``build()`` (an object made of some of the owner's fields, such as a sub-config that checks itself) raises
    no ``ValueError`` or ``TypeError``; its message is passed on after ``label`` (the fields or their options)."""
    try:
        build()
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{label}: {exc}") from None


def check_that(owner: object, ok: bool, requirement: str) -> None:
    """A rule that no single-field check states (a relation between fields): ``requirement`` says it, in words."""
    if not ok:
        raise ValueError(f"{type(owner).__name__}: {requirement}")
