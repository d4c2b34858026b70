"""Command-line options declared by the settings they set: :class:`SettingOption`.

A frozen settings dataclass (a loader's :class:`~cubedimer.load_config.LoadConfig`, a fitting method's settings)
declares, next to its fields, the options a command offers for them: each names its flag, the field it sets (a
dotted path through nested settings), the value's type or choices and its help text; the default the help names is
read from the field itself.  A command adds the declared options to its parser (:meth:`SettingOption.add_to`) and
applies the given ones to the settings (:meth:`SettingOption.applied`), so that an option is written once, where its
setting lives, and every command that fills those settings offers it with the same name, help and meaning.
"""
from __future__ import annotations

import argparse
from dataclasses import dataclass, replace
from typing import Any, Callable, Mapping, Sequence

__all__ = ["SettingOption", "positive_int", "positive_float", "field_value"]


def positive_int(text: str) -> int:
    """argparse type: an integer >= 1."""
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if v < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1, got {v}")
    return v


def positive_float(text: str) -> float:
    """argparse type: a finite number > 0."""
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not (v > 0 and v < float("inf")):
        raise argparse.ArgumentTypeError(f"must be a positive finite number, got {text!r}")
    return v


def field_value(settings: object, path: str) -> Any:
    """The value of the field at the dotted ``path`` of ``settings`` (``"selection.heldout_tolerance"``)."""
    value = settings
    for name in path.split("."):
        value = getattr(value, name)
    return value


def _with_field(settings: Any, path: str, value: Any) -> Any:
    """``settings`` with the field at the dotted ``path`` set to ``value`` (each level rebuilt, and so checked)."""
    head, _, rest = path.partition(".")
    return replace(settings, **{head: _with_field(getattr(settings, head), rest, value) if rest else value})


_SWITCH = object()  # not a switch: the option takes a value


@dataclass(frozen=True)
class SettingOption:
    """One command-line option that sets one field of a frozen settings dataclass.

    Parameters
    ----------
    flag : str
        The option (``"--min-periods"``); its argparse destination is the flag's words joined by ``_``.
    field : str
        The field it sets, a dotted path from the declaring settings (``"selection.heldout_tolerance"``).
    help : str or callable
        Its help line, or a function returning it (read when the parser is built, e.g. to list a registry);
        ``{default}`` in it is replaced by the field's default (as :meth:`default_text` writes it).
    type : callable, optional
        Converts the typed text (e.g. :func:`positive_int`); argparse reports a bad value in one line.
    choices : mapping, sequence or callable, optional
        The values it takes: a mapping from each choice to the field's value, a sequence of values set as typed, or
        a function returning either (read when the parser is built, so a registry's later entries count).
    metavar : str, optional
        The value's name in the help.
    switch : object, optional
        Makes the option a switch without a value (``--no-glitch-mask``) that sets the field to this value.
    valid : callable, optional
        ``valid(value) -> bool`` beyond the type; a value it refuses is reported with ``requirement``.
    requirement : str
        What a valid value is, in words (``"needs a fraction in [0, 1)"``), for the one-line error.
    """

    flag: str
    field: str
    help: str | Callable[[], str]
    type: Callable[[str], Any] | None = None
    choices: Mapping[str, Any] | Sequence[Any] | Callable[[], Mapping[str, Any] | Sequence[Any]] | None = None
    metavar: str | None = None
    switch: Any = _SWITCH
    valid: Callable[[Any], bool] | None = None
    requirement: str = ""

    @property
    def dest(self) -> str:
        """The argparse destination (``min_periods`` for ``--min-periods``)."""
        return self.flag.lstrip("-").replace("-", "_")

    @property
    def is_switch(self) -> bool:
        """Whether the option is a switch without a value."""
        return self.switch is not _SWITCH

    def choice_values(self) -> Mapping[str, Any] | None:
        """The choices as a mapping from the typed text to the field's value (None: the option takes any value of
        its type)."""
        choices = self.choices() if callable(self.choices) else self.choices
        if choices is None:
            return None
        return dict(choices) if isinstance(choices, Mapping) else {c: c for c in choices}

    def default_text(self, settings: object) -> str:
        """The field's value in ``settings`` as the help names it: a choice's name, a number in ``%g``."""
        value = field_value(settings, self.field)
        for name, choice in (self.choice_values() or {}).items():
            if choice == value:
                return str(name)
        return f"{value:g}" if isinstance(value, float) else str(value)

    def help_text(self, defaults: object) -> str:
        """The help line with ``{default}`` read from the settings ``defaults``."""
        text = self.help() if callable(self.help) else self.help
        return text.replace("{default}", self.default_text(defaults))

    def add_to(self, parser: argparse.ArgumentParser | argparse._ArgumentGroup, defaults: object,
               help: str | None = None) -> None:
        """Add the option to ``parser``; ``help`` replaces the declared line (e.g. the lines of several methods that
        declare the same flag).  An option not given leaves no attribute (:meth:`given` reads None), so the help
        names the field's default and no argparse default beside it."""
        text = self.help_text(defaults) if help is None else help
        if self.is_switch:
            parser.add_argument(self.flag, dest=self.dest, action="store_true", default=argparse.SUPPRESS, help=text)
            return
        choices = self.choice_values()
        parser.add_argument(self.flag, dest=self.dest, type=self.type, default=argparse.SUPPRESS, metavar=self.metavar,
                            choices=tuple(choices) if choices is not None else None, help=text)

    def given(self, args: argparse.Namespace) -> Any:
        """The value the user gave (None when not given: a switch not set, or a command without the option)."""
        value = getattr(args, self.dest, None)
        return None if value is False and self.is_switch else value

    def applied(self, settings: Any, value: Any) -> Any:
        """``settings`` with the field set from the given ``value`` (the switch's value, or a choice's value).

        Raises
        ------
        ValueError
            One line, to follow ``"<flag> "``: a value outside the choices, refused by ``valid``, or refused by
            the settings' own checks.
        """
        if self.is_switch:
            return _with_field(settings, self.field, self.switch)
        shown = f"{value:g}" if isinstance(value, float) else str(value)
        choices = self.choice_values()
        if choices is not None and value not in choices:
            raise ValueError(f"{shown}: needs one of {', '.join(map(str, choices))}")
        if choices is None and self.valid is not None and not self.valid(value):
            raise ValueError(f"{shown}: {self.requirement}")
        try:
            return _with_field(settings, self.field, choices[value] if choices is not None else value)
        except ValueError as exc:  # the settings' own checks (cubedimer.config_checks)
            raise ValueError(f"{shown}: {exc}") from None
