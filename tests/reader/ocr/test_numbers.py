"""Scale numbers from OCR strings: parsing table, fragment merging, the progression filter."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gauged.reader.ocr.fragments import merge_fragments
from gauged.reader.ocr.numbers import filter_progression, nice_step, parse_number
from gauged.reader.ocr.text import TextBox
from gauged.types import ScaleMarker


@pytest.mark.parametrize("text,value", [
    ("0", 0.0), ("10", 10.0), ("160", 160.0), ("400", 400.0), ("1,6", 1.6), ("1.6", 1.6), ("0.25", 0.25),
    ("2.5", 2.5), ("-1", -1.0), ("−30", -30.0), ("–0.5", -0.5), ("—0.5", -0.5), ("~1", -1.0), ("_2", -2.0),
    ("+5", 5.0), ("O", 0.0), ("O.6", 0.6), ("o", 0.0), ("l0", 10.0), ("I6O", 160.0), ("25O", 250.0),
    ("4OO", 400.0), (" 60 ", 60.0), ("S0", 50.0), ("1B", 18.0), ("B0", 80.0), ("6Q", 60.0), ("Z", 2.0),
    ("16-", 16.0), ("15.", 15.0), ("300.", 300.0), ("260-", 260.0), ("1,000", 1000.0), ("0,025", 0.025),
    ("10000", 10000.0), ("40°", 40.0), ("100%", 100.0), ("-40°C", -40.0), ("1 6", 16.0), (":20", -20.0),
])
def test_parse_number_reads_scale_numbers(text, value):
    parsed = parse_number(text)
    assert parsed, parsed
    assert parsed.value == pytest.approx(value)


@pytest.mark.parametrize("text,reason", [
    ("", "empty"), ("   ", "empty"), ("bar", "text"), ("psi", "text"), ("WIKA", "text"), ("kPa", "text"),
    ("10bar", "text"), ("x10", "text"), ("0.1mm", "text"), ("SN48213", "text"), ("No19070702", "text"),
    ("48213921", "serial"), ("111862848", "serial"), ("123456", "serial"),
    ("CL 1.6", "accuracy_class"), ("Cl. 1.6", "accuracy_class"), ("CL1.6", "accuracy_class"),
    ("KL 1.6", "accuracy_class"), ("KI16", "accuracy_class"), ("Class 1.0", "accuracy_class"),
    ("EN 837", "standard"), ("EN837-1", "standard"), ("EN 837-3", "standard"), ("DIN 16063", "standard"),
    ("12.03.2021", "date"), ("2021-03-12", "date"), ("1.6.2", "malformed"), ("0-10", "malformed"),
    ("05", "leading_zero"), ("09", "leading_zero"), ("Il", "text"), ("SOS", "text"), ("I", "text"), ("l", "text"),
    ("|", "text"),
])
def test_parse_number_rejects_distractors_with_reasons(text, reason):
    parsed = parse_number(text)
    assert not parsed and parsed.stage == "ocr" and parsed.reason == reason, parsed


def test_parse_number_flags_fragments_confusions_and_doubtful_signs():
    assert parse_number(".6").fragment and parse_number(".6").value == pytest.approx(0.6)
    assert parse_number("-").fragment
    assert parse_number("O.6").confusions == 1 and parse_number("0.6").confusions == 0
    assert parse_number("~30").sign_doubtful and not parse_number("-30").sign_doubtful
    assert parse_number("0.25").decimals == 2 and parse_number("-0.25").text == "-0.25"


def box(text: str, x0: float, y0: float, x1: float, y1: float, score: float = 0.9) -> TextBox:
    return TextBox(text, score, np.float32([[x0, y0], [x1, y0], [x1, y1], [x0, y1]]))


def test_merge_fragments_joins_split_numbers_and_keeps_apart_ones():
    boxes = [box("0", 100, 100, 110, 120), box(".6", 112, 100, 128, 120),   # "0" + ".6"
             box("1", 200, 100, 208, 120), box("6", 210, 101, 220, 121),    # "1" + "6"
             box("-", 300, 100, 308, 120), box("30", 310, 100, 330, 120),   # "-" + "30"
             box("10", 400, 100, 420, 120), box("20", 460, 100, 480, 120),  # far apart: two numbers
             box("5", 500, 100, 510, 120), box("bar", 512, 100, 540, 120)]  # a unit is not a fragment
    texts = sorted(b.text for b in merge_fragments(boxes))
    assert texts == sorted(["0.6", "16", "-30", "10", "20", "5", "bar"])
    joined = next(b for b in merge_fragments(boxes) if b.text == "0.6")
    assert joined.box == pytest.approx((100, 100, 128, 120))


def test_merge_fragments_keeps_close_single_numbers_apart():
    """Padded boxes of "1", "2", "3" printed 36 px apart on a short scale come within the gap, but
    their characters are two text heights apart, not a digit pitch: three numbers, not "123"."""
    boxes = [box("1", 90, 100, 118, 120), box("2", 126, 100, 154, 120), box("3", 162, 100, 190, 120)]
    assert sorted(b.text for b in merge_fragments(boxes)) == ["1", "2", "3"]
    # the same padding around the digits of one number still joins them
    assert [b.text for b in merge_fragments([box("1", 90, 100, 108, 120), box("6", 104, 100, 122, 120)])] == ["16"]


def test_merge_fragments_needs_alignment_and_similar_height():
    assert len(merge_fragments([box("1", 100, 100, 108, 120), box("6", 110, 125, 120, 145)])) == 2  # not level
    assert len(merge_fragments([box("1", 100, 100, 108, 120), box("6", 110, 100, 140, 160)])) == 2  # 3x taller


@pytest.mark.parametrize("step,nice", [(1, True), (2, True), (2.5, True), (5, True), (0.2, True), (25, True),
                                       (500, True), (0.025, True), (3, False), (1.5, False), (30, False), (0, False)])
def test_nice_step(step, nice):
    assert nice_step(step) is nice


def dial_markers(values, start=math.radians(135), span=math.radians(270), radius=100.0, jitter=0.0, seed=0):
    """Markers evenly spaced clockwise on a circle, the gap at the bottom (image angle pi/2)."""
    rng = np.random.default_rng(seed)
    out, radii = [], []
    for i, v in enumerate(values):
        a = start + span * i / (len(values) - 1) + rng.normal(0, jitter)
        out.append(ScaleMarker(str(v), float(v), (0, 0, 1, 1), angle=math.atan2(math.sin(a), math.cos(a))))
        radii.append(radius)
    return out, radii


def test_filter_progression_keeps_the_scale_and_rejects_outliers():
    markers, radii = dial_markers([0, 2, 4, 6, 8, 10], jitter=math.radians(1.0))
    distractor = ScaleMarker("1.6", 1.6, (0, 0, 1, 1), angle=math.radians(100))  # accuracy class near the gap
    misread = ScaleMarker("9", 9.0, (0, 0, 1, 1), angle=markers[2].angle)        # a "4" read as "9"
    fit = filter_progression([*markers, distractor, misread], radii=[*radii, 60.0, 100.0])
    assert fit
    assert [m.value for m in fit.kept] == [0, 2, 4, 6, 8, 10]
    assert all(m.inlier for m in fit.kept)
    assert fit.step == pytest.approx(2) and fit.nice and fit.slope > 0
    assert {m.text: reason for m, reason in fit.rejected} == {"1.6": "radius_outlier", "9": "off_progression"}


def test_filter_progression_tolerates_missing_numbers_and_odd_steps():
    markers, radii = dial_markers([-2, -0.5, 1, 2.5, 4])  # a real dial with step 1.5
    fit = filter_progression([markers[0], markers[1], markers[3], markers[4]], radii=[100.0] * 4)
    assert fit and [m.value for m in fit.kept] == [-2, -0.5, 2.5, 4]
    assert fit.step == pytest.approx(1.5) and not fit.nice


def test_filter_progression_drops_a_tick_read_as_minus():
    markers, radii = dial_markers([8, 10, 12, 14, 16, 18])
    markers[1] = ScaleMarker("-10", -10.0, (0, 0, 1, 1), angle=markers[1].angle)
    fit = filter_progression(markers, radii=radii)
    assert fit and [m.value for m in fit.kept] == [8, 10, 12, 14, 16, 18]


def test_filter_progression_separates_concentric_scales_by_radius():
    psi, r1 = dial_markers([0, 50, 100, 150, 200, 250, 300], radius=100.0)
    bar, r2 = dial_markers([0, 5, 10, 15, 20], span=math.radians(270 * 20 / 20.68), radius=60.0)
    fit = filter_progression([*psi, *bar], radii=[*r1, *r2])
    assert fit and [m.value for m in fit.kept] == [0, 50, 100, 150, 200, 250, 300]
    assert {reason for _, reason in fit.rejected} <= {"radius_outlier", "off_progression", "duplicate_value"}


def test_filter_progression_keeps_a_counter_clockwise_scale_and_prefers_clockwise_on_a_tie():
    markers, radii = dial_markers([10, 8, 6, 4, 2, 7])  # falling clockwise: a 0..10 scale rising counter-clockwise
    fit = filter_progression(markers, radii=radii)
    assert fit and [m.value for m in fit.kept] == [2, 4, 6, 8, 10] and fit.slope < 0  # the misread "7" left out
    # "-20, -10, 0" clockwise rises as read and falls with its minus signs taken for ticks: as read wins
    vacuum, r = dial_markers([-20, -10, 0])
    fit = filter_progression(vacuum, radii=r)
    assert fit and fit.slope > 0


def test_filter_progression_refuses_too_few():
    two, r = dial_markers([0, 10])
    assert filter_progression(two, radii=r).reason == "too_few_numbers"
    no_angles = [ScaleMarker("1", 1.0, (0, 0, 1, 1)), ScaleMarker("2", 2.0, (0, 0, 1, 1)), ScaleMarker("3", 3.0, (0, 0, 1, 1))]
    assert filter_progression(no_angles).reason == "too_few_numbers"
