"""Units read against the vocabulary: canonical spellings, OCR confusions, distractors."""

from __future__ import annotations

import numpy as np
import pytest

from gauged.reader.ocr_engine import TextBox
from gauged.reader.units import match_unit, read_unit


@pytest.mark.parametrize("text,unit", [
    ("bar", "bar"), ("BAR", "bar"), ("Bar", "bar"), ("(bar)", "bar"), ("mbar", "mbar"), ("kPa", "kPa"),
    ("KPA", "kPa"), ("kpa", "kPa"), ("MPa", "MPa"), ("MPA", "MPa"), ("Pa", "Pa"), ("psi", "psi"), ("PSI", "psi"),
    ("psig", "psi"), ("kg/cm2", "kg/cm2"), ("kg/cm²", "kg/cm2"), ("kgf/cm2", "kg/cm2"), ("kgf/cm²", "kg/cm2"),
    ("kg/cm²(g)", "kg/cm2"), ("kg/cm(g)", "kg/cm2"), ("inHg", "inHg"), ("mmHg", "mmHg"), ("inH2O", "inH2O"),
    ("mmH2O", "mmH2O"), ("°C", "degC"), ("℃", "degC"), ("oC", "degC"), ("C", "degC"), ("°F", "degF"),
    ("℉", "degF"), ("F", "degF"), ("%", "%"), ("%RH", "%"), ("A", "A"), ("V", "V"), ("100xkPa", "kPa"),
    ("100×kPa", "kPa"), ("x100 kPa", "kPa"), ("rpm", "rpm"), ("km/h", "km/h"),
    # OCR confusions: digits for letters, one wrong/missing/extra letter on longer spellings
    ("mbaR", "mbar"), ("inHq", "inHg"), ("1nHg", "inHg"), ("p5i", "psi"), ("kgf/crn2", "kg/cm2"), ("mmH20", "mmH2O"),
])
def test_match_unit_canonical_names(text, unit):
    match = match_unit(text)
    assert match, match
    assert match.unit == unit


@pytest.mark.parametrize("text,reason", [
    ("", "empty"), ("WIKA", "distractor"), ("OIL", "distractor"), ("EN", "distractor"), ("316L", "distractor"),
    ("Glycerin", "distractor"), ("1.6", "no_unit"), ("EN 837-1", "no_unit"), ("TRANS", "distractor"),
    ("SPORT-COMP", "no_unit"), ("B", "no_unit"), ("ps", "no_unit"),
])
def test_match_unit_rejects_fragments_and_other_text(text, reason):
    match = match_unit(text)
    assert not match and match.reason == reason, match


def test_match_unit_scores_exact_over_fuzzy_and_lone_letters_lowest():
    assert match_unit("bar").score > match_unit("baR1").score if match_unit("baR1") else True
    assert match_unit("°C").score > match_unit("C").score


def test_read_unit_prefers_the_confident_spelled_out_unit():
    q = np.float32([[0, 0], [10, 0], [10, 5], [0, 5]])
    boxes = [TextBox("C", 0.99, q + 50), TextBox("°C", 0.95, q + 100), TextBox("WIKA", 0.99, q)]
    assert read_unit(boxes).unit == "degC" and read_unit(boxes).text == "°C"
    assert read_unit([TextBox("WIKA", 0.9, q)]) is None
