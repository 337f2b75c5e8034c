"""The scale stage on dual-scale dials: numbers grouped by the radius they are printed at, the outer
ring is the primary scale, and an unreadable outer ring is refused rather than answered with the
inner (secondary) scale's value."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from gauged.geometry.dial_frame import point_at_dial_angle
from gauged.reader.ocr.units import PrintedUnit
from gauged.reader.stages.ellipse import fit_scale_arc
from gauged.reader.stages.scale import fit_scales, scale_from_prior, with_round_ends
from gauged.types import ScaleMarker, ScaleModel, StageFailure
from tests.reader.dial_maps import CROP, Dial, keypoints_for


def _point(dial: Dial, position: float, radius: float, intervals: int) -> np.ndarray:
    """The point at ``radius`` of the scale ring, ``position`` of ``intervals`` equal steps from the start."""
    angle = math.radians(dial.start_deg + position * dial.span_deg / intervals)
    return point_at_dial_angle(dial.ellipse.scaled(radius), angle)[0]


def _box(point: np.ndarray) -> tuple[float, float, float, float]:
    x, y = point
    return (x - 6, y - 5, x + 6, y + 5)


def _ring(dial: Dial, values: list[float], radius: float, steps: list[int] | None = None) -> list[ScaleMarker]:
    """Numbers printed at ``radius`` of the scale ring, at the dial's major notches ``steps``."""
    return [ScaleMarker(f"{values[k]:g}", float(values[k]), _box(_point(dial, k, radius, len(values) - 1)))
            for k in (steps if steps is not None else range(len(values)))]


DIAL = Dial()
BAR = [float(v) for v in range(11)]  # 0..10 bar, outer
PSI = [15.0 * v for v in range(11)]  # 0..150 psi, inner: a second scale prints round numbers of its own unit


@pytest.mark.parametrize("outer_radius,inner_radius", [(1.15, 0.75), (0.9, 0.6)])
def test_the_outer_ring_is_the_primary_scale(outer_radius, inner_radius):
    arc = fit_scale_arc(keypoints_for(DIAL, pivot=False), CROP)
    markers = _ring(DIAL, PSI, inner_radius, [0, 2, 4, 6, 8, 10]) + _ring(DIAL, BAR, outer_radius, [0, 2, 4, 6, 8, 10])
    scales = fit_scales(arc, markers)
    assert not isinstance(scales, StageFailure), scales
    assert [round(s.max_value, 3) for s in scales] == [10.0, 150.0]


def test_each_scale_of_a_dual_scale_dial_is_in_its_own_unit():
    # psi was read best, but 0..10 outside and 0..150 inside convert as bar and psi (docs/ocr.md, units)
    arc = fit_scale_arc(keypoints_for(DIAL, pivot=False), CROP)
    markers = _ring(DIAL, PSI, 0.75, [0, 2, 4, 6, 8, 10]) + _ring(DIAL, BAR, 1.15, [0, 2, 4, 6, 8, 10])
    scales = fit_scales(arc, markers, (PrintedUnit("psi", 0.99, 0.4), PrintedUnit("bar", 0.9, 0.3)))
    assert [(round(s.max_value, 3), s.unit) for s in scales] == [(10.0, "bar"), (150.0, "psi")]


def test_an_unreadable_outer_ring_is_refused_not_answered_with_the_inner_scale():
    arc = fit_scale_arc(keypoints_for(DIAL, pivot=False), CROP)
    markers = _ring(DIAL, PSI, 0.6, [0, 2, 4, 6, 8, 10]) + _ring(DIAL, BAR, 1.15, [4, 6])
    failure = fit_scales(arc, markers)
    assert isinstance(failure, StageFailure)
    assert (failure.stage, failure.reason) == ("scale", "too_few_inliers")
    assert failure.detail.startswith("outer scale:")
    # the inner ring alone, deep inside the scale ring, is a secondary scale whose main one went unread
    alone = fit_scales(arc, markers[:6])
    assert isinstance(alone, StageFailure)
    assert (alone.stage, alone.reason) == ("scale", "secondary_scale_only")
    # the same numbers printed just inside the ring are the main scale
    assert not isinstance(fit_scales(arc, _ring(DIAL, PSI, 0.75, [0, 2, 4, 6, 8, 10])), StageFailure)


def test_whole_numbers_with_a_decimal_one_on_their_line_are_a_dropped_decimal_point():
    """A 0..1 MPa dial whose OCR dropped the "0." of most numbers (synthetic 000110): 2, 4, 6, 8 agree
    on a line, but "0.5" sits where that line puts 5, so the scale is refused, not read 10x too high."""
    arc = fit_scale_arc(keypoints_for(DIAL, pivot=False), CROP)
    values = [float(v) for v in range(11)]
    whole = _ring(DIAL, values, 0.8, [0, 2, 4, 6, 8, 10])
    (decimal,) = _ring(DIAL, values, 0.8, [5])
    decimal = ScaleMarker("0.5", 0.5, decimal.box)
    failure = fit_scales(arc, whole + [decimal])
    assert isinstance(failure, StageFailure)
    assert (failure.stage, failure.reason) == ("scale", "dropped_decimal_point")
    # a tick before it read as a minus sign ("-0.5") is the same evidence (held-out 000658: "15, 20, 25"
    # read for 1.5, 2.0, 2.5 and "-0.5" for 0.5 answered 17% off)
    failure = fit_scales(arc, whole + [ScaleMarker("-0.5", -0.5, decimal.box)])
    assert isinstance(failure, StageFailure)
    assert (failure.stage, failure.reason) == ("scale", "dropped_decimal_point")
    # so is a whole value printed with decimals: "1.0" where the line puts 10 ("5, 15, 25" read for
    # "0.5, 1.5, 2.5" on a 0..2.5 dial answered 10x too high)
    (at_ten,) = _ring(DIAL, values, 0.8, [10])
    failure = fit_scales(arc, whole[:-1] + [ScaleMarker("1.0", 1.0, at_ten.box)])
    assert isinstance(failure, StageFailure)
    assert (failure.stage, failure.reason) == ("scale", "dropped_decimal_point")
    # a decimal elsewhere (an accuracy class "1.6" near the centre) is no such evidence
    (centre,) = _ring(DIAL, values, 0.1, [7])
    scales = fit_scales(arc, whole + [ScaleMarker("1.6", 1.6, centre.box)])
    assert not isinstance(scales, StageFailure), scales
    assert scales[0].max_value == pytest.approx(10.0)


def test_one_scale_whose_numbers_look_like_two_rings_is_fitted_whole():
    """A skewed ellipse puts one scale's numbers at two apparent radii (5 and 10 nearer the ring than
    15 and 20): agreeing numbers from both groups make them one scale, not two too-small ones."""
    arc = fit_scale_arc(keypoints_for(DIAL, pivot=False), CROP)
    values = [5.0 * v for v in range(6)]
    markers = _ring(DIAL, values, 0.95, [1, 2]) + _ring(DIAL, values, 0.7, [3, 4])
    scales = fit_scales(arc, markers)
    assert not isinstance(scales, StageFailure), scales
    assert len(scales) == 1 and scales[0].inliers == 4
    assert scales[0].max_value == pytest.approx(25.0, abs=0.01)


def test_two_outer_numbers_with_an_inner_one_on_their_line_are_one_scale():
    """A "0" printed nearer the centre than "4" and "8" splits the numbers into two rings, the outer
    one too small for a scale; the three agree on one line, so they are one scale (synthetic dev 000077)."""
    arc = fit_scale_arc(keypoints_for(DIAL, pivot=False), CROP)
    markers = _ring(DIAL, BAR, 0.7, [0]) + _ring(DIAL, BAR, 1.1, [4, 8])
    scales = fit_scales(arc, markers)
    assert not isinstance(scales, StageFailure), scales
    assert len(scales) == 1 and scales[0].inliers == 3
    assert scales[0].max_value == pytest.approx(10.0, abs=0.01)
    # a misread inner number off the outer ones' line leaves them too few, as before
    wrong = _ring(DIAL, [3.0] + BAR[1:], 0.7, [0]) + _ring(DIAL, BAR, 1.1, [4, 8])
    failure = fit_scales(arc, wrong)
    assert isinstance(failure, StageFailure) and failure.reason == "too_few_inliers"


def test_a_letter_read_as_a_digit_does_not_make_the_third_agreeing_number():
    """ "S" read as 5 beside "15" and "25" (a 0..2.5 scale whose decimal points went unread): the three
    agree on a line 10x too steep; two numbers read as digits are too few, so it is refused."""
    arc = fit_scale_arc(keypoints_for(DIAL, pivot=False), CROP)
    values = [5.0 * v for v in range(6)]  # 0..25 in steps of 5, numbers printed at every other one
    markers = _ring(DIAL, values, 0.8, [1, 3, 5])
    assert not isinstance(fit_scales(arc, markers), StageFailure)  # 5, 15, 25 read as digits: a scale
    letter = [ScaleMarker("S", 5.0, markers[0].box)] + markers[1:]
    failure = fit_scales(arc, letter)
    assert isinstance(failure, StageFailure) and failure.reason == "too_few_inliers"
    assert "read as digits" in failure.detail


def test_one_number_read_twice_does_not_make_the_third_agreeing_number():
    """Two boxes read "0" at one printed "0" beside "5" (held-out 000744, 176% off): three markers agree
    on a line but only two printed numbers do, too few, so it is refused; with more numbers it is a scale."""
    arc = fit_scale_arc(keypoints_for(DIAL, pivot=False), CROP)
    values = [5.0 * v for v in range(6)]
    zero, five, fifteen, twenty_five = _ring(DIAL, values, 0.8, [0, 1, 3, 5])
    x0, y0, x1, y1 = zero.box
    twice = [zero, ScaleMarker("0", 0.0, (x0 + 3, y0 + 1, x1 + 3, y1 + 1)), five]
    failure = fit_scales(arc, twice)
    assert isinstance(failure, StageFailure) and failure.reason == "too_few_inliers"
    assert "2 distinct values" in failure.detail
    scales = fit_scales(arc, twice + [fifteen, twenty_five])
    assert not isinstance(scales, StageFailure), scales
    assert scales[0].max_value == pytest.approx(25.0, abs=0.05)


def test_agreeing_numbers_that_are_not_steps_of_one_progression_are_irregular():
    """10, 150, 200 of a 0..300 dial ("50" misread "10" near the line): the differences 140 and 50
    are no multiples of one step, so the bent line is refused."""
    arc = fit_scale_arc(keypoints_for(DIAL, pivot=False), CROP)
    values = [50.0 * v for v in range(7)]
    x, y = point_at_dial_angle(DIAL.ellipse.scaled(0.8), math.radians(DIAL.start_deg + DIAL.span_deg * 10 / 300))[0]
    ten = ScaleMarker("10", 10.0, (x - 6, y - 5, x + 6, y + 5))  # on the line: where 10 would be
    failure = fit_scales(arc, [ten] + _ring(DIAL, values, 0.8, [3, 4, 6]))
    assert isinstance(failure, StageFailure)
    assert (failure.stage, failure.reason) == ("scale", "irregular_numbers")
    # unread numbers in between are fine: 50, 150, 200 are steps of 50
    assert not isinstance(fit_scales(arc, _ring(DIAL, values, 0.8, [1, 3, 4, 6])), StageFailure)


def test_numbers_thousands_of_steps_apart_are_irregular():
    """"0.4" and "1" side by side where a dial's scale starts and "1867" (a number off the face) at
    its end: 0.6 divides 1866, but three thousand steps are no printed scale (its line read 1462 for
    0.01 on a 0..0.6 dial)."""
    arc = fit_scale_arc(keypoints_for(DIAL, pivot=False), CROP)

    def at(text: str, share: float, radius: float) -> ScaleMarker:
        x, y = point_at_dial_angle(DIAL.ellipse.scaled(radius), math.radians(DIAL.start_deg + DIAL.span_deg * share))[0]
        return ScaleMarker(text, float(text), (x - 6, y - 5, x + 6, y + 5))

    failure = fit_scales(arc, [at("0.4", 0.4 / 1867, 0.8), at("1", 1 / 1867, 0.65), at("1867", 1.0, 0.8)])
    assert isinstance(failure, StageFailure)
    assert (failure.stage, failure.reason) == ("scale", "irregular_numbers")


def _centres(dial: Dial, steps: list[int], radius: float = 0.8) -> np.ndarray:
    """Printed-number centres (the crop model's hints) at the dial's major notches ``steps``."""
    return np.vstack([_point(dial, k, radius, dial.majors - 1) for k in steps])


def _at(dial: Dial, text: str, position: float) -> ScaleMarker:
    """A number read at ``position`` major steps from the start notch (fractional: between numbers)."""
    return ScaleMarker(text, float(text), _box(_point(dial, position, 0.8, dial.majors - 1)))


def test_printed_numbers_between_the_steps_of_the_read_ones_are_off_grid():
    """Numbers are printed at all 11 majors of a 0..10 dial (the crop model's number centres). Misread
    numbers 0, 1, 3, 4 that happen to lie on a line (at 0, 1.8, 5.4 and 7.2 major steps, as on the
    synthetic vacuum dial 000212) put most printed numbers between the steps of that line: refused.
    Reading every fourth number right (0, 4, 8) is fine."""
    arc = fit_scale_arc(keypoints_for(DIAL, pivot=False), CROP)
    hints = _centres(DIAL, list(range(11)))
    wrong = [_at(DIAL, text, position) for text, position in (("0", 0.0), ("1", 1.8), ("3", 5.4), ("4", 7.2))]
    assert not isinstance(fit_scales(arc, wrong), StageFailure)  # without the number centres it passes
    failure = fit_scales(arc, wrong, hints=hints)
    assert isinstance(failure, StageFailure)
    assert (failure.stage, failure.reason) == ("scale", "numbers_off_grid")
    right = fit_scales(arc, _ring(DIAL, BAR, 0.8, [0, 4, 8]), hints=hints)
    assert not isinstance(right, StageFailure), right
    assert right[0].max_value == pytest.approx(10.0)


def test_a_bare_number_beside_one_printed_with_decimals_lost_its_point():
    """0..1.6 printed "0.0, 0.4, 0.8, 1.2, 1.6" and read "0.0", "8", "12" (synthetic 000111 with the
    v3 crop model): the three agree on a line 10x too steep; "0.0" shows the scale prints decimals."""
    arc = fit_scale_arc(keypoints_for(DIAL, pivot=False), CROP)
    values = [0.0, 4.0, 8.0, 12.0, 16.0]
    dial = Dial(majors=5)
    markers = _ring(dial, values, 0.8, [0, 2, 3])
    markers[0] = ScaleMarker("0.0", 0.0, markers[0].box)
    failure = fit_scales(fit_scale_arc(keypoints_for(dial, pivot=False), CROP), markers)
    assert isinstance(failure, StageFailure)
    assert (failure.stage, failure.reason) == ("scale", "dropped_decimal_point")
    # "0" beside "0.5", "1", "1.5" is the usual way to print a decimal scale: no evidence
    half = _ring(DIAL, [0.5 * v for v in range(11)], 0.8, [0, 1, 2, 3, 4, 6, 8, 10])
    half = [ScaleMarker(f"{m.value:g}", m.value, m.box) for m in half]
    assert not isinstance(fit_scales(arc, half), StageFailure)
    # "2" beside "1.0" and "1.5" is "2.0" printed short (synthetic 000095): the value is right
    short = [ScaleMarker("2" if m.value == 2.0 else f"{m.value:.1f}", m.value, m.box) for m in half]
    assert not isinstance(fit_scales(arc, short), StageFailure)


def test_unread_printed_numbers_further_out_make_the_read_ring_a_secondary_scale():
    """Synthetic 000650: the 0..350 inner scale was read at 0.62 of the ring (just at the radius rule),
    while the crop model saw printed numbers at 0.85 that no read number explains: its main scale."""
    arc = fit_scale_arc(keypoints_for(DIAL, pivot=False), CROP)
    inner = _ring(DIAL, PSI, 0.66, [0, 2, 4, 6, 8, 10])
    assert not isinstance(fit_scales(arc, inner), StageFailure)  # alone, at 0.66, it passes as a main scale
    further = _centres(DIAL, [1, 5, 9], radius=0.88)
    failure = fit_scales(arc, inner, hints=further)
    assert isinstance(failure, StageFailure)
    assert (failure.stage, failure.reason) == ("scale", "secondary_scale_only")
    assert "further out" in failure.detail
    # hints on the read ring itself are no such evidence
    assert not isinstance(fit_scales(arc, inner, hints=_centres(DIAL, [1, 5, 9], radius=0.66)), StageFailure)


@pytest.mark.parametrize("values,step", [
    ([2040.0, 6080.0, 8010.0], 10.0),  # two numbers read as one: only 10 divides their differences
    ([20.0, 40.0, 60.0, 100.0], 20.0),
    ([0.0, 0.2, 0.6], 0.2),
    ([-30.0, -20.0, 0.0], 10.0),
    ([0.0, 250.0, 1000.0], 250.0),
    ([0.0, 15.0, 45.0], 5.0),  # a step of 15 is printed as multiples of the round 5
    ([7.0], 0.0),
])
def test_round_step_is_the_largest_round_step_dividing_every_difference(values, step):
    from gauged.reader.ocr.numbers import round_step

    assert round_step(np.array(values)) == pytest.approx(step)


def test_a_number_with_a_dangling_point_is_no_evidence():
    """"0." is as often a decimal cut short ("-0.3") as a "0" beside a tick: "0.", "1" and "2" on a
    line made a 0..2.2 scale of a -1..0 vacuum dial, 195% off (fresh13 000257). Such a number does not
    count towards the three agreeing numbers; read "0" it does."""
    arc = fit_scale_arc(keypoints_for(DIAL, pivot=False), CROP)
    values = [float(v) for v in range(11)]
    cut = _ring(DIAL, values, 0.8, [0, 5, 10])
    cut[0] = ScaleMarker("0.", 0.0, cut[0].box)
    failure = fit_scales(arc, cut)
    assert isinstance(failure, StageFailure)
    assert (failure.stage, failure.reason) == ("scale", "too_few_inliers")
    assert not isinstance(fit_scales(arc, _ring(DIAL, values, 0.8, [0, 5, 10])), StageFailure)


def _line_through(arc, low: float, high: float, values: list[float]) -> ScaleModel:
    """A fitted scale whose line puts ``low`` and ``high`` at the arc's ends, with agreeing numbers
    ``values`` on the line."""
    zero = arc.zero_angle
    model = ScaleModel(arc.ellipse, 1.0, 0.0, zero, low, high)
    u0, u1 = model.unwrap(arc.start_angle), model.unwrap(arc.end_angle)
    slope = (high - low) / (u1 - u0)
    intercept = low - slope * u0
    markers = tuple(ScaleMarker(f"{v:g}", v, (0, 0, 1, 1), (v - intercept) / slope, True) for v in values)
    return ScaleModel(arc.ellipse, slope, intercept, zero, low, high, markers=markers, inliers=len(values))


def test_a_line_that_puts_the_scale_ends_near_round_values_is_fitted_with_them():
    # numbers 200..1000 whose line says 13.3 at the start notch and 998.7 at the end (a real 0..1000 kPa
    # dial read 15.7 at rest): each end counts as a number at 0 and 1000
    arc = fit_scale_arc(keypoints_for(DIAL, pivot=False), CROP)
    fitted = _line_through(arc, 13.3, 998.7, [200.0, 400.0, 600.0, 800.0, 1000.0])
    pinned = with_round_ends(arc, fitted)
    assert abs(pinned.min_value) < 0.6 * 13.3 and abs(pinned.max_value - 1000.0) < 1.3
    assert pinned.value_at(arc.start_angle) == pytest.approx(pinned.min_value)
    # ends the numbers already put on round values stay exactly there, without float noise
    exact = with_round_ends(arc, _line_through(arc, 0.0, 16.0, [4.0, 8.0, 12.0, 16.0]))
    assert (exact.min_value, exact.max_value) == (0.0, 16.0)
    # ends a third of a step off a round value are not evidence of where the scale starts
    assert with_round_ends(arc, _line_through(arc, 70.0, 1000.0, [200.0, 400.0, 600.0])) == \
        _line_through(arc, 70.0, 1000.0, [200.0, 400.0, 600.0])
    # nor are ends inferred from a gap between notches (hidden ends, or a guess)
    inferred = replace(arc, ends_inferred=True)
    assert with_round_ends(inferred, fitted) == fitted


def _counter_clockwise_vacuum(texts_values: list[tuple[str, float]]) -> list[ScaleMarker]:
    """A -1..0 dial rising counter-clockwise: -1.0 at the start notch's place of a clockwise dial's end,
    so clockwise from the start its numbers read 0.0, -0.2 ... -1.0; (text, value) as the OCR gave them."""
    return [ScaleMarker(text, value, _box(_point(DIAL, k, 1.15, len(texts_values) - 1)))
            for k, (text, value) in enumerate(texts_values)]


def test_a_counter_clockwise_dial_is_read_with_the_signs_its_numbers_show():
    arc = fit_scale_arc(keypoints_for(DIAL, pivot=False), CROP)
    printed = [0.0, -0.2, -0.4, -0.6, -0.8, -1.0]
    # every minus read: the numbers fall clockwise, so the scale rises counter-clockwise
    as_read = _counter_clockwise_vacuum([(f"{v:.1f}", v) for v in printed])
    (scale,) = fit_scales(arc, as_read)
    assert scale.slope < 0 and (scale.min_value, scale.max_value) == pytest.approx((-1.0, 0.0))
    # a reader blind to minus signs gave the values unsigned ("-0.4" valued 0.4): the clockwise 0..1 line
    # would overrule five read signs, the counter-clockwise one none
    unsigned = _counter_clockwise_vacuum([(f"{v:.1f}", abs(v)) for v in printed])
    (scale,) = fit_scales(arc, unsigned)
    assert scale.slope < 0 and (scale.min_value, scale.max_value) == pytest.approx((-1.0, 0.0))
    # with no minus sign read at all the numbers are taken as read, 0..1 rising clockwise: nothing on
    # the dial tells it from its mirror image
    (scale,) = fit_scales(arc, _counter_clockwise_vacuum([(f"{abs(v):.1f}", abs(v)) for v in printed]))
    assert scale.slope > 0 and (scale.min_value, scale.max_value) == pytest.approx((0.0, 1.0))


def test_a_clockwise_dial_keeps_its_direction_when_a_tick_reads_as_a_minus():
    arc = fit_scale_arc(keypoints_for(DIAL, pivot=False), CROP)
    texts = ["0", "1", "-2", "3", "4", "5", "6", "7", "8", "9", "10"]  # a tick before the "2"
    (scale,) = fit_scales(arc, _ring(DIAL, [float(t) for t in texts], 1.15))
    assert scale.slope > 0 and (scale.min_value, scale.max_value) == pytest.approx((0.0, 10.0))


def test_a_line_overruling_a_read_minus_sign_on_little_evidence_is_refused():
    """Three numbers of a -1..0 dial rising counter-clockwise, one read with its minus ("0.2, -0.4,
    0.6"): the counter-clockwise line fails, and the clockwise 0..1 line would take the minus for a
    tick with only two numbers of evidence left. The right magnitude with the wrong sign is refused."""
    arc = fit_scale_arc(keypoints_for(DIAL, pivot=False), CROP)
    read = _counter_clockwise_vacuum([("0.0", 0.0), ("0.2", 0.2), ("-0.4", 0.4), ("0.6", 0.6), ("", 0.0), ("", 0.0)])
    ring = [m for m in read if m.text][1:]
    failure = fit_scales(arc, ring)
    assert isinstance(failure, StageFailure) and failure.reason == "wrong_slope_sign", failure
    # the same three numbers with no minus read are a clockwise scale, taken as read
    (scale,) = fit_scales(arc, [replace(m, text=m.text.lstrip("-")) for m in ring])
    assert scale.slope > 0


def test_a_vacuum_dial_with_some_minus_signs_read_is_read_negative():
    """A -30..0 dial rising counter-clockwise read "0, 5, -15, -20, 30" (two minus signs seen, three
    dropped): clockwise, the line overrules two read signs; counter-clockwise with every number
    negative it adds three unread ones, which costs less. A single read minus is a tick."""
    arc = fit_scale_arc(keypoints_for(DIAL, pivot=False), CROP)
    texts = ["0", "5", None, "-15", "-20", None, "30"]
    ring = [m for m in _counter_clockwise_vacuum([(t or "", abs(float(t or 0))) for t in texts]) if m.text]
    (scale,) = fit_scales(arc, ring)
    assert scale.slope < 0 and (scale.min_value, scale.max_value) == pytest.approx((-30.0, 0.0), abs=1e-6)
    one = [replace(m, text="15") if m.text == "-15" else m for m in ring]  # "0, 5, 15, -20, 30"
    (scale,) = fit_scales(arc, one)
    assert scale.slope > 0 and (scale.min_value, scale.max_value) == pytest.approx((0.0, 30.0), abs=1e-6)


def test_a_prior_rising_counter_clockwise_puts_its_max_at_the_start_notch():
    arc = fit_scale_arc(keypoints_for(DIAL, pivot=False), CROP)
    start, end = (float(arc.linear(a)) for a in (arc.start_angle, arc.end_angle))
    clockwise = scale_from_prior(arc, -1.0, 0.0, "bar")
    counter = scale_from_prior(arc, -1.0, 0.0, "bar", direction=-1)
    assert (clockwise.value_at(start), clockwise.value_at(end)) == pytest.approx((-1.0, 0.0))
    assert (counter.value_at(start), counter.value_at(end)) == pytest.approx((0.0, -1.0))
    assert (counter.min_value, counter.max_value, counter.slope < 0) == (-1.0, 0.0, True)


def test_negative_values_given_to_unsigned_texts_are_read_as_printed():
    """A 0..1.6 dial rising counter-clockwise with one tick read as a minus ("-1.4"): a number grid that
    took the ring for negatives with unseen minus signs valued every number negative, which read
    clockwise is -1.6..0. The texts show one minus, so the values are the printed ones, rising
    counter-clockwise."""
    arc = fit_scale_arc(keypoints_for(DIAL, pivot=False), CROP)
    printed = [1.6, 1.4, 1.2, 1.0, 0.8, 0.6, 0.4, 0.2, 0.0]
    texts = [("-" if v == 1.4 else "") + f"{v:.1f}" for v in printed]
    ring = _counter_clockwise_vacuum([(t, -v) for t, v in zip(texts, printed)])
    (scale,) = fit_scales(arc, ring)
    assert scale.slope < 0 and (scale.min_value, scale.max_value) == pytest.approx((0.0, 1.6), abs=1e-6)


def test_a_tick_read_as_a_minus_does_not_turn_a_counter_clockwise_dial_negative():
    """A 0..250 dial rising counter-clockwise with one tick read as a minus ("-100"), valued by a number
    grid that took it for a -250..0 scale rising clockwise whose minus signs went unread. The line
    through the numbers as read explains all six, "-100" with its sign overruled (1); the clockwise
    one adds four unread signs (0.5 each): the dial is read as printed."""
    arc = fit_scale_arc(keypoints_for(DIAL, pivot=False), CROP)
    printed = [250.0, 200.0, 150.0, 100.0, 50.0, 0.0]
    texts = [("-" if v == 100 else "") + f"{v:g}" for v in printed]
    (scale,) = fit_scales(arc, _counter_clockwise_vacuum([(t, -v) for t, v in zip(texts, printed)]))
    assert scale.slope < 0 and (scale.min_value, scale.max_value) == pytest.approx((0.0, 250.0), abs=1e-6)


def test_a_tie_between_mirror_lines_goes_to_the_one_that_adds_no_unread_signs():
    """A 0..40 dial rising counter-clockwise with one tick read as a minus ("-20"), valued by a number
    grid that took it for a -40..0 scale rising clockwise. The line through the numbers as read
    explains all five, "-20" with its sign overruled (5 - 1); the clockwise one adds three unread
    signs (5 - 3 x 0.5). Counter-clockwise is short of the clockwise line's lead by half a number, but
    the clockwise line stands only on signs nobody read: the dial is read as printed."""
    arc = fit_scale_arc(keypoints_for(DIAL, pivot=False), CROP)
    printed = [40.0, 30.0, 20.0, 10.0, 0.0]
    texts = [("-" if v == 20 else "") + f"{v:g}" for v in printed]
    (scale,) = fit_scales(arc, _counter_clockwise_vacuum([(t, -v) for t, v in zip(texts, printed)]))
    assert scale.slope < 0 and (scale.min_value, scale.max_value) == pytest.approx((0.0, 40.0), abs=1e-6)
    # with those three minus signs read, the numbers are a -40..0 scale rising clockwise
    signed = [("-" if v else "") + f"{v:g}" for v in printed]
    (scale,) = fit_scales(arc, _counter_clockwise_vacuum([(t, -v) for t, v in zip(signed, printed)]))
    assert scale.slope > 0 and (scale.min_value, scale.max_value) == pytest.approx((-40.0, 0.0), abs=1e-6)


def test_a_counter_clockwise_line_alone_may_overrule_one_read_sign():
    """A 0..50 dial rising counter-clockwise with a tick read as the minus of its "40": no clockwise
    line fits, and the counter-clockwise one explains all six numbers, "-40" with its sign overruled
    as a tick beside it."""
    arc = fit_scale_arc(keypoints_for(DIAL, pivot=False), CROP)
    printed = [50.0, 40.0, 30.0, 20.0, 10.0, 0.0]
    texts = [("-" if v == 40 else "") + f"{v:g}" for v in printed]
    ring = _counter_clockwise_vacuum([(t, float(t)) for t in texts])
    (scale,) = fit_scales(arc, ring)
    assert scale.slope < 0 and (scale.min_value, scale.max_value) == pytest.approx((0.0, 50.0), abs=1e-6)


def test_two_read_minus_signs_are_not_overruled_by_a_counter_clockwise_line_alone():
    """A -30..0 dial rising clockwise read "30, 25, -20, -10, 5" (two minus signs seen, three dropped):
    no clockwise line fits the values as read, and the counter-clockwise 0..30 line through "30, 25, 5"
    would take both read signs for ticks. Two ticks read as minus signs are less likely than a scale
    of negatives: refused, for a look that weighs the signs to read. One read sign is a tick."""
    arc = fit_scale_arc(keypoints_for(DIAL, pivot=False), CROP)
    texts = ["30", "25", "-20", "", "-10", "5", ""]
    ring = [m for m in _counter_clockwise_vacuum([(t, float(t or 0)) for t in texts]) if m.text]
    assert isinstance(fit_scales(arc, ring), StageFailure)
    one = [replace(m, text="20", value=20.0) if m.text == "-20" else m for m in ring]
    (scale,) = fit_scales(arc, one)
    assert scale.slope < 0 and (scale.min_value, scale.max_value) == pytest.approx((0.0, 30.0), abs=1e-6)


def test_the_direction_margin_is_small_where_only_a_sign_or_two_tells_a_scale_from_its_mirror():
    from gauged.reader.stages.scale_direction import direction_margin

    arc = fit_scale_arc(keypoints_for(DIAL, pivot=False), CROP)
    printed = [0.0, -0.2, -0.4, -0.6, -0.8, -1.0]
    # every minus read: the clockwise 0..1 mirror overrules five signs
    (sure,) = fit_scales(arc, _counter_clockwise_vacuum([(f"{v:.1f}", v) for v in printed]))
    # two of five minus signs read: the scale is still -1..0, but its mirror is close behind
    texts = ["0.0", "0.2", "-0.4", "0.6", "-0.8", "1.0"]
    (unsure,) = fit_scales(arc, _counter_clockwise_vacuum([(t, float(t)) for t in texts]))
    assert direction_margin(arc, sure) > direction_margin(arc, unsure) + 2
    # no sign read on a clockwise 0..10 dial: its mirror, -10..0 rising counter-clockwise, adds ten
    # unread minus signs at 0.5 each
    (plain,) = fit_scales(arc, _ring(DIAL, [float(v) for v in range(11)], 1.15))
    assert direction_margin(arc, plain) == pytest.approx(5.0)

