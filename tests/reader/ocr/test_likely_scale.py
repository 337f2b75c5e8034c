"""The second look at refused dials: grids of numbers found in the recogniser's probabilities.

The recogniser is replaced by constructed per-column probabilities (a known truth to read back):
each text's columns spell what it "saw", each character with a chosen confidence, so the test
decides which strings a text makes likely. The real engine's likelihood is tested in test_ocr.py.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from gauged.reader.ocr.likely_scale import RingText, decimals, likely_markers, spellings
from gauged.reader.ocr.text import Recognition, ctc_greedy, ctc_log_likelihood

CHARS = ("0", "1", "2", "3", "4", "5", "6", "7", "8", "9", ".", ",", "-", "−")
LABEL = {c: k for k, c in enumerate(CHARS, start=1)}


def score(reading: Recognition, text: str) -> float:
    labels = [LABEL.get(c) for c in text]
    return -math.inf if None in labels else ctc_log_likelihood(reading.digit_logp, labels)


def seen(columns: list[dict[str, float]]) -> Recognition:
    """A reading whose columns give the characters (and blank, '') the probabilities listed; a column
    of blank separates every two. The rest of each column's mass is spread over the others."""
    rows = []
    for column in [{"": 0.98}] + [c for col in columns for c in (col, {"": 0.98})]:
        p = np.full(len(CHARS) + 1, 1e-3)
        for char, prob in column.items():
            p[0 if char == "" else LABEL[char]] = prob
        rows.append(p / p.sum())
    logp = np.log(np.array(rows))
    digits, digits_score = ctc_greedy(np.exp(logp), np.arange(len(CHARS) + 1), ("",) + CHARS)
    return Recognition(digits, digits_score, digits, digits_score, logp.astype(np.float32))


def plain(text: str, confidence: float = 0.95) -> Recognition:
    return seen([{c: confidence} for c in text])


def faint_minus(text: str) -> Recognition:
    """``text`` (a negative number) with its minus sign only faintly seen: best read without it."""
    return seen([{"-": 0.3, "": 0.68}] + [{c: 0.95} for c in text.lstrip("-")])


def ring(readings: list[Recognition], first_deg: float = 0.0, step_deg: float = 45.0, radial=None,
         radii=None) -> list[RingText]:
    """Texts at evenly spaced dial angles (at 0.85 scale radii unless ``radii`` are given);
    ``radial`` (optional) their readings turned radially."""
    return [RingText((10.0 * k, 0.0, 10.0 * k + 8.0, 8.0), math.radians(first_deg + step_deg * k),
                     0.85 if radii is None else radii[k], {"upright": r} | ({} if radial is None else {"radial": radial[k]}))
            for k, r in enumerate(readings)]


def test_a_negative_scale_whose_minus_signs_were_lost_is_found_with_its_signs():
    # -30..0 in steps of 5 over 270 degrees; the recogniser's best strings are "30", "25", ... "0"
    # (values that fall clockwise: no scale), but a faint minus sign is seen on each
    printed = ["-30", "-25", "-20", "-15", "-10", "-5", "0"]
    texts = ring([faint_minus(t) if t != "0" else plain(t) for t in printed])
    assert [t.readings["upright"].digits for t in texts] == ["30", "25", "20", "15", "10", "5", "0"]
    markers = likely_markers([texts], 0.0, math.radians(270.0), score)
    assert markers is not None
    assert sorted((m.value, m.box) for m in markers) == sorted((float(v), t.box) for v, t in zip(printed, texts))


def test_a_misread_number_is_corrected_when_its_printed_string_is_nearly_as_likely():
    # "20" read as "0": its "2" was seen at 0.4 against a blank at 0.58
    readings = [plain("0"), seen([{"2": 0.4, "": 0.58}, {"0": 0.95}]), plain("40"), plain("60"), plain("80"), plain("100")]
    assert readings[1].digits == "0"
    markers = likely_markers([ring(readings, step_deg=50.0)], 0.0, math.radians(250.0), score)
    assert [m.value for m in sorted(markers, key=lambda m: m.box)] == [0.0, 20.0, 40.0, 60.0, 80.0, 100.0]
    assert [m.text for m in sorted(markers, key=lambda m: m.box)][:2] == ["0", "20"]


def test_no_grid_without_enough_agreeing_texts():
    # three good numbers (the first reading's minimum) are not enough for a second look
    assert likely_markers([ring([plain("0"), plain("10"), plain("20")])], 0.0, math.radians(90.0), score) is None
    # four texts whose strings no evenly spaced grid spells
    assert likely_markers([ring([plain("0"), plain("70"), plain("30"), plain("5")])], 0.0, math.radians(135.0), score) is None
    # confidently read other numbers on the grid's places refute it when they are many...
    texts = ring([plain(t) for t in ("0", "10", "20", "30", "90", "80", "70")])
    assert likely_markers([texts], 0.0, math.radians(270.0), score) is None
    # ...and are left out when they are few
    texts = ring([plain(t) for t in ("0", "10", "20", "80", "40", "90", "60")])
    assert [m.value for m in likely_markers([texts], 0.0, math.radians(270.0), score)] == [0.0, 10.0, 20.0, 40.0, 60.0]


def test_one_orientation_per_grid():
    # two numbers read upright, two others only when turned radially: no four of one orientation
    good = {"upright": [plain("0"), plain("10"), plain("77", 0.9), plain("77", 0.9)],
            "radial": [plain("44", 0.9), plain("44", 0.9), plain("20"), plain("30")]}
    texts = ring(good["upright"], radial=good["radial"])
    assert likely_markers([texts], 0.0, math.radians(135.0), score) is None
    # all four read radially: a grid
    texts = ring(good["upright"], radial=[plain("0"), plain("10"), plain("20"), plain("30")])
    assert [m.value for m in likely_markers([texts], 0.0, math.radians(135.0), score)] == [0.0, 10.0, 20.0, 30.0]


def test_a_grids_numbers_lie_at_one_distance_from_the_centre():
    # digits read on blobs all over a blurred face: a grid by value and angle, but not on one circle
    readings = [plain(t) for t in ("1", "2", "3", "4", "5")]
    scattered = ring(readings, radii=[1.3, 0.7, 0.95, 0.75, 1.2])
    assert likely_markers([scattered], 0.0, math.radians(180.0), score) is None
    assert len(likely_markers([ring(readings, radii=[0.8, 0.84, 0.9, 0.86, 0.82])], 0.0, math.radians(180.0), score)) == 5


def test_no_grid_of_whole_numbers_where_a_decimal_number_is_read():
    # 0..1.6 printed "0.0, 0.2, ..."; most read without their "0.", one read right: 0..12 is not proposed
    readings = [plain(t) for t in ("0", "2", "4", "6", "0.8", "10", "12")]
    assert likely_markers([ring(readings, step_deg=40.0)], 0.0, math.radians(320.0), score) is None
    # a decimal grid keeps its texts' own strings ("0.0" stays "0.0") for the scale stage's checks
    readings = [plain(t) for t in ("0.0", "0.2", "0.4", "6", "0.8")]
    markers = likely_markers([ring(readings, step_deg=40.0)], 0.0, math.radians(160.0), score)
    assert [(m.text, m.value) for m in markers] == [("0.0", 0.0), ("0.2", 0.2), ("0.4", 0.4), ("0.8", 0.8)]


def test_the_signs_seen_decide_between_the_mirror_grids_of_a_ring():
    # "30, 25, 20, 15" falling clockwise with no minus sign anywhere: printed so, rising counter-clockwise
    no_minus = ring([plain(t) for t in ("30", "25", "20", "15")])
    assert [m.value for m in likely_markers([no_minus], 0.0, math.radians(135.0), score)] == [30.0, 25.0, 20.0, 15.0]
    # the same with a faint minus sign seen on each: -30..-15 rising clockwise
    texts = ring([faint_minus(t) for t in ("-30", "-25", "-20", "-15")])
    assert [m.value for m in likely_markers([texts], 0.0, math.radians(135.0), score)] == [-30.0, -25.0, -20.0, -15.0]
    # "30, 20, 10, 0" and no minus sign: 0..30 counter-clockwise, not -30..0 with every sign unread
    up_to_zero = ring([plain(t) for t in ("30", "20", "10", "0")])
    assert [m.value for m in likely_markers([up_to_zero], 0.0, math.radians(135.0), score)] == [30.0, 20.0, 10.0, 0.0]
    # no grid that crosses 0 with no minus sign seen ("6, 4, 2, 0, 2" taken for 6..-2)
    crossing = ring([plain(t) for t in ("6", "4", "2", "0", "2")])
    assert likely_markers([crossing], 0.0, math.radians(180.0), score) is None


def test_texts_outside_the_scale_are_not_on_the_grid():
    readings = [plain(t) for t in ("0", "1", "2", "3", "4")] + [plain("9")]  # "9": a serial number's digit
    texts = ring(readings, step_deg=40.0)
    markers = likely_markers([texts], 0.0, math.radians(160.0), score)  # the scale ends at "4"
    assert [m.value for m in markers] == [0.0, 1.0, 2.0, 3.0, 4.0]


@pytest.mark.parametrize("step, places", [(5.0, 0), (2.5, 1), (0.5, 1), (0.25, 2), (100.0, 0), (0.001, 3)])
def test_decimals_of_a_step(step, places):
    assert decimals(step) == places


def test_spellings_of_printed_numbers():
    assert spellings(0.5, 1) == ([",5", ".5", "0,5", "0.5"], [])
    assert spellings(0.0, 1) == (["0", "0,0", "0.0"], [])
    signed, unsigned = spellings(-10.0, 0)
    assert signed == ["-10"] and unsigned == ["10"]
