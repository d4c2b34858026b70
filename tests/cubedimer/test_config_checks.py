"""The construction-time checks of the frozen configs (cubedimer.config_checks), and that every config of the core,
the fit and the bridge makes its checks through them (read from the source, so that a new config cannot forget)."""
from __future__ import annotations

import ast
import math
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from cubedimer import config_checks as cc

ROOT = Path(__file__).resolve().parents[2]
PACKAGES = ("cubedimer", "acousim", "fitting", "tracking", "validation")

#: Frozen dataclasses that hold settings without "Config" or "Settings" in their name.
SETTINGS_CLASSES = {"LossWeights", "NoiseLevels", "PracticalThresholds", "Medium", "ParticleMaterial", "Camera",
                    "AtlasDimer"}

#: Configs still checked by hand: none (a debt would be listed here as {file: {class}}, and the list can only shrink:
#: the test fails when one of them starts using the checks, or is gone).
HAND_CHECKED: dict[str, set[str]] = {}


@dataclass(frozen=True)
class _Example:
    n: object = 3
    x: object = 0.5
    pair: object = (0.1, 0.2)
    names: object = ("a",)
    choice: object = "a"


@dataclass(frozen=True)
class _Option:
    """A config whose field a command's option sets: the messages name the option."""
    pressure: object = field(default=3000.0, metadata=cc.named("--pressure"))
    starts: object = field(default=(0.1, 0.2), metadata=cc.named("--starts"))


class _OwnError(ValueError):
    pass


@pytest.mark.parametrize("check, field, value, ok", [
    (cc.check_whole, "n", 3, True), (cc.check_whole, "n", 0, False), (cc.check_whole, "n", 2.0, False),
    (cc.check_whole, "n", True, False), (cc.check_positive, "x", 0.5, True), (cc.check_positive, "x", 0.0, False),
    (cc.check_positive, "x", math.inf, False), (cc.check_fraction, "x", 0.5, True), (cc.check_fraction, "x", 1.0, False),
    (cc.check_fraction, "x", 0.0, False), (cc.check_bounds, "pair", (0.1, 0.2), True),
    (cc.check_bounds, "pair", (0.2, 0.1), False), (cc.check_bounds, "pair", (0.0, 0.1), False),
    (cc.check_bounds, "pair", (0.1, math.inf), False), (cc.check_bounds, "pair", 0.1, False),
])
def test_single_field_checks(check, field, value, ok):
    owner = _Example(**{field: value})
    if ok:
        check(owner, field)
    else:
        with pytest.raises(ValueError, match=rf"^_Example\.{field} ") as info:
            check(owner, field)
        assert "\n" not in str(info.value)


def test_the_options_of_the_checks():
    cc.check_whole(_Example(n=None), "n", optional=True)
    cc.check_positive(_Example(x=None), "x", optional=True)
    with pytest.raises(ValueError, match="positive"):
        cc.check_positive(_Example(x=None), "x")
    cc.check_fraction(_Example(x=0.0), "x", zero=True)  # [0, 1)
    with pytest.raises(ValueError, match=r"\[0, 1\)"):
        cc.check_fraction(_Example(x=1.0), "x", zero=True)
    cc.check_fraction(_Example(x=1.0), "x", closed=True)
    with pytest.raises(ValueError, match=r"must be \(low, high\) with 0 < low < high"):
        cc.check_bounds(_Example(pair=(0.1, 0.1)), "pair", strict=True)
    cc.check_bounds(_Example(pair=(0.1, 0.1)), "pair")
    cc.check_above(_Example(x=1.5), "x", 1.0)
    with pytest.raises(ValueError, match="above 1"):
        cc.check_above(_Example(x=1.0), "x", 1.0)


@pytest.mark.parametrize("kwargs, value, ok", [
    (dict(low=0.0, high=1.0), 0.0, True), (dict(low=0.0, high=1.0), 1.0, True),
    (dict(low=0.0, high=1.0, low_open=True), 0.0, False), (dict(low=0.0, high=1.0, high_open=True), 1.0, False),
    (dict(low=0.0, high=1.0), 1.5, False), (dict(low=0.0, high=1.0), -0.1, False),
    (dict(low=0.0, high=1.0), math.nan, False), (dict(low=-math.inf, high=math.inf), math.inf, False),
    (dict(low=0.0, high=1.0), True, False), (dict(low=0.0, high=1.0), "0.5", False),
    (dict(low=16, high=1000, whole=True), 40, True), (dict(low=16, high=1000, whole=True), 40.0, True),
    (dict(low=16, high=1000, whole=True), 40.5, False), (dict(low=16, high=1000, whole=True), 8, False),
])
def test_in_range(kwargs, value, ok):
    owner = _Example(x=value)
    if ok:
        cc.check_in_range(owner, "x", **kwargs)
    else:
        with pytest.raises(ValueError, match=r"^_Example\.x must (lie in|be a whole number in) [\[(]") as info:
            cc.check_in_range(owner, "x", **kwargs)
        assert "\n" not in str(info.value)


@pytest.mark.parametrize("value, ok", [((0.1, 0.2), True), ((0.1,), True), ((), False), ((0.1, 2.0), False),
                                       ((0.1, math.nan), False), (0.1, False), (None, False)])
def test_in_range_of_each_entry(value, ok):
    owner = _Option(starts=value)
    if ok:
        cc.check_in_range(owner, "starts", 0.0, 1.0, low_open=True, unit="m", each=True)
    else:
        with pytest.raises(ValueError, match=r"^--starts: every value must lie in \(0, 1\] m \(one at least\), got "):
            cc.check_in_range(owner, "starts", 0.0, 1.0, low_open=True, unit="m", each=True)


def test_a_named_field_is_named_by_its_option_and_an_own_error_keeps_the_message():
    with pytest.raises(ValueError, match=r"^--pressure must lie in \(0, 100000\] Pa, got -1$"):
        cc.check_in_range(_Option(pressure=-1), "pressure", 0.0, 1e5, low_open=True, unit="Pa")
    with pytest.raises(ValueError, match=r"^--pressure must be a positive finite number, got -1$"):
        cc.check_positive(_Option(pressure=-1), "pressure")
    cc.check_in_range(_Option(pressure=None), "pressure", 0.0, 1.0, optional=True)
    with pytest.raises(_OwnError, match=r"^--pressure must be a positive finite number, got 0$"):
        with cc.raising(_OwnError):
            cc.check_positive(_Option(pressure=0), "pressure")
    with pytest.raises(_OwnError, match="^as it was$"):  # an own error passes unchanged
        with cc.raising(_OwnError):
            raise _OwnError("as it was")
    with pytest.raises(KeyError):  # only value errors change class
        with cc.raising(_OwnError):
            raise KeyError("x")


def test_given_and_builds():
    cc.check_given(_Option(), "starts", "start")
    with pytest.raises(ValueError, match=r"^--starts: give at least one start$"):
        cc.check_given(_Option(starts=()), "starts", "start")
    def refused():
        raise ValueError("the quality factor must be positive")

    cc.check_builds(_Example(), "--q/--x", lambda: 1)
    with pytest.raises(ValueError, match=r"^--q/--x: the quality factor must be positive$"):
        cc.check_builds(_Example(), "--q/--x", refused)


def test_choices_name_every_unknown_entry_and_the_choices():
    with pytest.raises(ValueError, match=r"_Example\.choice: unknown colour 'z' \(use one of a, b\)"):
        cc.check_choice(_Example(choice="z"), "choice", ("a", "b"), what="colour")
    cc.check_choices(_Example(names=()), "names", ("a", "b"))
    with pytest.raises(ValueError, match=r"\(none given\)"):
        cc.check_choices(_Example(names=()), "names", ("a", "b"), allow_empty=False)
    with pytest.raises(ValueError, match=r"unknown 'x', 'y' \(use any of a, b\)"):
        cc.check_choices(_Example(names=("a", "x", "y")), "names", ("a", "b"))
    with pytest.raises(ValueError, match=r"^_Example: low below high$"):
        cc.check_that(_Example(), False, "low below high")


# ---- every config uses them -----------------------------------------------------------------------------------------
def _is_frozen_dataclass(node: ast.ClassDef) -> bool:
    return any(isinstance(d, ast.Call) and getattr(d.func, "id", None) == "dataclass"
               and any(k.arg == "frozen" and getattr(k.value, "value", False) is True for k in d.keywords)
               for d in node.decorator_list)


def _is_settings(name: str) -> bool:
    return name.endswith(("Config", "Settings")) or name in SETTINGS_CLASSES


def config_check_use(source: str) -> dict[str, str | None]:
    """For every frozen settings dataclass of ``source``: None when its ``__post_init__`` calls a check of
    cubedimer.config_checks and raises nothing itself, else what is wrong."""
    tree = ast.parse(source)
    checks = set(cc.__all__)
    out: dict[str, str | None] = {}
    for node in ast.walk(tree):
        if not (isinstance(node, ast.ClassDef) and _is_frozen_dataclass(node) and _is_settings(node.name)):
            continue
        post = next((n for n in node.body if isinstance(n, ast.FunctionDef) and n.name == "__post_init__"), None)
        if post is None:
            out[node.name] = "no __post_init__"
            continue
        calls = {getattr(n.func, "id", getattr(n.func, "attr", None)) for n in ast.walk(post) if isinstance(n, ast.Call)}
        if any(isinstance(n, ast.Raise) for n in ast.walk(post)):
            out[node.name] = "raises by hand"
        elif not calls & checks:
            out[node.name] = "calls no check of cubedimer.config_checks"
        else:
            out[node.name] = None
    return out


def test_the_scanner_on_known_classes():
    src = ("from dataclasses import dataclass\nfrom cubedimer.config_checks import check_positive\n"
           "@dataclass(frozen=True)\nclass AConfig:\n    x: float = 1.0\n    def __post_init__(self):\n"
           "        check_positive(self, 'x')\n"
           "@dataclass(frozen=True)\nclass BConfig:\n    x: float = 1.0\n    def __post_init__(self):\n"
           "        if self.x < 0:\n            raise ValueError('x')\n"
           "@dataclass(frozen=True)\nclass CSettings:\n    x: float = 1.0\n"
           "@dataclass(frozen=True)\nclass Result:\n    x: float = 1.0\n")
    assert config_check_use(src) == {"AConfig": None, "BConfig": "raises by hand", "CSettings": "no __post_init__"}


def test_every_config_checks_itself_through_config_checks():
    bad, seen = [], {}
    for package in PACKAGES:
        for f in sorted((ROOT / package).rglob("*.py")):
            rel = str(f.relative_to(ROOT))
            for cls, problem in config_check_use(f.read_text(encoding="utf-8")).items():
                seen.setdefault(rel, {})[cls] = problem
                if problem and cls not in HAND_CHECKED.get(rel, set()):
                    bad.append(f"{rel}: {cls}: {problem}")
    assert not bad, "configs that do not check themselves through cubedimer.config_checks:\n" + "\n".join(bad)
    for rel, classes in HAND_CHECKED.items():  # the known debts are still debts (else remove them from the list)
        assert all(seen.get(rel, {}).get(c) for c in classes), (rel, classes, seen.get(rel))
    assert sum(len(v) for v in seen.values()) >= 20  # the scan sees the suite's configs
