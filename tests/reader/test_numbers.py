from __future__ import annotations

import pytest

from gauged.reader.numbers import parse_number, parse_unit


@pytest.mark.parametrize("text,value", [
    ("0", 0.0), ("10", 10.0), ("1,6", 1.6), ("1.6", 1.6), ("0.25", 0.25), ("-1", -1.0), ("−30", -30.0),
    ("—0.5", -0.5), ("O", 0.0), ("O.6", 0.6), ("l0", 10.0), ("I6O", 160.0), ("25O", 250.0), ("4OO", 400.0),
    (" 60 ", 60.0), (".5", 0.5), ("S0", 50.0), ("1B", 18.0),
])
def test_parse_number_reads_scale_numbers(text, value):
    assert parse_number(text) == pytest.approx(value)


@pytest.mark.parametrize("text", ["", "bar", "psi", "SN48213", "48213921", "CL 1.6", "EN 837", "WIKA", "1.6.2",
                                  "12:30", "kPa", "10bar", "x10", "0-10"])
def test_parse_number_rejects_words_serials_and_mixed_text(text):
    assert parse_number(text) is None


@pytest.mark.parametrize("text,unit", [
    ("bar", "bar"), ("BAR", "bar"), ("mbar", "mbar"), ("kPa", "kPa"), ("KPA", "kPa"), ("MPa", "MPa"), ("psi", "psi"),
    ("PSI", "psi"), ("kg/cm²", "kg/cm2"), ("kgf/cm2", "kg/cm2"), ("°C", "degC"), ("℃", "degC"), ("°F", "degF"),
    ("%", "%"), ("inHg", "inHg"), ("(bar)", "bar"),
])
def test_parse_unit_canonical_names(text, unit):
    assert parse_unit(text) == unit


@pytest.mark.parametrize("text", ["C", "F", "WIKA", "1.6", "EN 837-1", ""])
def test_parse_unit_rejects_fragments_and_other_text(text):
    assert parse_unit(text) is None
