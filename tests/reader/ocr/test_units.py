"""Units read against the vocabulary: canonical spellings, OCR confusions, distractors."""

from __future__ import annotations

import numpy as np
import pytest

from gauged.reader.ocr.text import TextBox
from gauged.reader.ocr.units import match_unit, names_unit, printed_units


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


def test_printed_units_name_each_unit_once_by_its_best_text():
    q = np.float32([[0, 0], [10, 0], [10, 5], [0, 5]])
    boxes = [TextBox("C", 0.99, q + 50), TextBox("°C", 0.95, q + 100), TextBox("WIKA", 0.99, q)]
    (unit,) = printed_units(boxes)
    assert unit.unit == "degC" and unit.score == pytest.approx(match_unit("°C").score * 0.95)
    assert printed_units([TextBox("WIKA", 0.9, q)]) == ()


def test_printed_units_come_best_read_first_with_their_distance_from_the_centre():
    q = np.float32([[0, 0], [10, 0], [10, 4], [0, 4]])
    boxes = [TextBox("psi", 0.9, q + [95, 145]), TextBox("bar", 0.99, q + [95, 125])]
    units = printed_units(boxes, (100.0, 100.0, 50.0))
    assert [u.unit for u in units] == ["bar", "psi"]
    assert [u.radius for u in units] == [pytest.approx(27 / 50), pytest.approx(47 / 50)]


def test_a_line_of_several_words_names_the_units_among_them():
    q = np.float32([[0, 0], [10, 0], [10, 4], [0, 4]])
    assert [u.unit for u in printed_units([TextBox("Knots km/h", 1.0, q)])] == ["knots", "km/h"]
    assert [u.unit for u in printed_units([TextBox("OIL PSI", 0.9, q)])] == ["psi"]
    # a unit spelled with a space stays whole; words that are no unit (or single letters) name none
    assert [u.unit for u in printed_units([TextBox("in Hg", 0.9, q)])] == ["inHg"]
    assert printed_units([TextBox("USE NO OIL", 0.9, q), TextBox("TYPE A", 0.9, q)]) == ()
    # a brand's word one letter from a unit is no unit ("Barsa" is not "bars"), though a lone word would be
    assert printed_units([TextBox("Barsa GmbH", 0.99, q)]) == ()


def test_names_unit_can_ask_for_a_spelled_unit():
    assert names_unit("C") and not names_unit("C", 0.9)  # a lone letter scores 0.6
    assert names_unit("kPa", 0.9) and names_unit("OIL PSI", 0.9) and not names_unit("WIKA")


def test_a_multiplier_written_with_a_star_keeps_its_unit():
    # a real fuel-pressure gauge prints "x100 kPa", read "*100k Pa": kPa, not Pa
    assert match_unit("*100k Pa").unit == "kPa" and match_unit("x100kPa").unit == "kPa"
