"""Command-line options declared beside the settings they set (cubedimer.setting_options): the default the help names
is the field's, a given value reaches the field through nested settings, and a refused value is one line."""
from __future__ import annotations

import argparse
from dataclasses import dataclass, field

import pytest

from cubedimer.config_checks import check_fraction
from cubedimer.load_config import LOAD_OPTIONS, LoadConfig
from cubedimer.setting_options import SettingOption, positive_int


@dataclass(frozen=True)
class _Inner:
    share: float = 0.25
    mode: object = None

    def __post_init__(self):
        check_fraction(self, "share")


@dataclass(frozen=True)
class _Outer:
    inner: _Inner = field(default_factory=_Inner)
    count: int = 3


SHARE = SettingOption("--share", "inner.share", type=float, metavar="F", help="a share (default {default})")
MODE = SettingOption("--mode", "inner.mode", choices={"off": None, "fast": 2.0}, help="mode (default {default})")
COUNT = SettingOption("--count", "count", type=positive_int, valid=lambda v: v % 2 == 1, requirement="needs an odd count",
                      help="count")
SWITCH = SettingOption("--no-inner", "inner", switch=None, help="without the inner stage")


def _parser(*options):
    p = argparse.ArgumentParser()
    for o in options:
        o.add_to(p, _Outer())
    return p


def test_the_help_names_the_field_s_default_and_a_choice_by_its_name():
    assert SHARE.help_text(_Outer()) == "a share (default 0.25)"
    assert MODE.help_text(_Outer()) == "mode (default off)"  # the field's None is the choice "off"
    assert MODE.help_text(_Outer(_Inner(mode=2.0))) == "mode (default fast)"


def test_given_values_reach_nested_fields_and_unset_ones_change_nothing():
    args = _parser(SHARE, MODE, COUNT, SWITCH).parse_args(["--share", "0.5", "--mode", "fast", "--count", "5"])
    out = _Outer()
    for option in (SHARE, MODE, COUNT, SWITCH):
        if (value := option.given(args)) is not None:
            out = option.applied(out, value)
    assert out == _Outer(_Inner(share=0.5, mode=2.0), count=5)
    assert SWITCH.given(args) is None and SWITCH.applied(_Outer(), True) == _Outer(inner=None)
    assert all(o.given(_parser(SHARE, MODE, COUNT, SWITCH).parse_args([])) is None for o in (SHARE, MODE, COUNT, SWITCH))


@pytest.mark.parametrize("option, value, says", [
    (SHARE, 1.5, "1.5: _Inner.share must lie in (0, 1), got 1.5"),  # the settings' own check
    (COUNT, 4, "4: needs an odd count"),
    (MODE, "slow", "slow: needs one of off, fast"),
])
def test_a_refused_value_is_one_line_starting_with_the_value(option, value, says):
    with pytest.raises(ValueError) as info:
        option.applied(_Outer(), value)
    assert str(info.value) == says


def test_the_loader_s_options_set_the_loader_s_fields():
    by_flag = {o.flag: o for o in LOAD_OPTIONS}
    assert by_flag["--min-periods"].help_text(LoadConfig()).endswith("(default 5)")
    assert by_flag["--no-glitch-mask"].applied(LoadConfig(), True).glitches is None
    assert by_flag["--max-gap"].applied(LoadConfig(), 40).max_gap == 40
