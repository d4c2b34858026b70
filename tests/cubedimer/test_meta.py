"""meta.json's unknown keys: a misspelt constant is named with the key it most likely means."""
import logging

import pytest

from cubedimer.meta import META_DEFAULTS, validate_meta


@pytest.mark.parametrize("typo, meant", [("side_lenght_m", "side_length_m"), ("frequncy_hz", "frequency_hz"),
                                         ("pressure_amplitude", "pressure_amplitude_pa")])
def test_a_misspelt_key_gets_did_you_mean(typo, meant, caplog):
    with caplog.at_level(logging.WARNING, logger="cubedimer.meta"):
        out = validate_meta({typo: 4.5e-4}, "data/meta.json")
    (record,) = caplog.records
    text = record.getMessage()
    assert text.startswith("data/meta.json: unknown key(s)") and f"{typo!r} (did you mean {meant!r}?)" in text
    assert "\n" not in text and meant not in {k for k in out if k in META_DEFAULTS}  # ignored: the default applies


def test_an_unrelated_key_is_named_without_a_guess(caplog):
    with caplog.at_level(logging.WARNING, logger="cubedimer.meta"):
        validate_meta({"operator": 3.0}, "meta.json")
    assert "'operator' ignored" in caplog.text and "did you mean" not in caplog.text
