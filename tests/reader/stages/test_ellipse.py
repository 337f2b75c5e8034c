from __future__ import annotations

import math

import numpy as np
import pytest

from gauged.geometry.angles import angle_difference, unwrap, wrap_angle, wrap_to_pi
from gauged.geometry.dial_frame import point_at_dial_angle
from gauged.reader.stages.ellipse import ScaleArc, fit_scale_arc, notch_grid
from gauged.types import Ellipse, StageFailure
from tests.reader.dial_maps import CROP, Dial, keypoints_for


@pytest.mark.parametrize("ellipse", [Ellipse(128, 128, 100, 100, 0), Ellipse(120, 131, 105, 80, 0.4),
                                     Ellipse(128, 128, 90, 60, 2.0)])
@pytest.mark.parametrize("start_deg,span_deg", [(135, 270), (90, 180), (200, 300), (-30, 100)])
def test_fit_scale_arc_recovers_ellipse_and_ends(ellipse, start_deg, span_deg):
    dial = Dial(ellipse=ellipse, start_deg=start_deg, span_deg=span_deg)
    arc = fit_scale_arc(keypoints_for(dial, pivot=False), CROP)
    assert arc, arc
    assert math.hypot(arc.ellipse.cx - ellipse.cx, arc.ellipse.cy - ellipse.cy) < 0.5
    assert abs(arc.ellipse.a - ellipse.a) < 0.5 and abs(arc.ellipse.b - ellipse.b) < 0.5
    assert abs(angle_difference(arc.start_angle, dial.start)) < math.radians(0.5)
    assert abs(angle_difference(arc.end_angle, dial.end)) < math.radians(0.5)
    assert abs(arc.span - math.radians(span_deg)) < math.radians(1)
    assert not arc.ends_inferred


def test_fit_scale_arc_infers_missing_ends_from_gap():
    dial = Dial(start_deg=135, span_deg=270)
    arc = fit_scale_arc(keypoints_for(dial, start=False, end=False), CROP)
    assert arc and arc.ends_inferred
    assert abs(angle_difference(arc.start_angle, dial.start)) < math.radians(0.5)
    assert abs(angle_difference(arc.end_angle, dial.end)) < math.radians(0.5)


def test_fit_scale_arc_ignores_a_false_notch():
    dial = Dial()
    notches = np.vstack([dial.notch_points(), [[128.0, 150.0]]])  # a screw head inside the dial
    arc = fit_scale_arc(keypoints_for(dial, majors=notches), CROP)
    assert arc and abs(arc.ellipse.a - 100) < 0.5 and len(arc.notches) == dial.majors + 2  # + start, end


@pytest.mark.parametrize("false_peaks,read", [(10, True), (18, False)])
def test_a_ring_must_explain_45_percent_of_the_notch_peaks(false_peaks, read):
    """The crop model's peaks off the ring (medium ticks, number strokes) are 22% of its peaks on
    average and 38% on far gauges: a ring through 13 of 23 peaks (57%) with both ends and the pivot
    on it is read, one through 13 of 31 (42%) is a poor fit."""
    dial = Dial()
    turn = np.radians(np.arange(false_peaks) * 137.5)  # spread over the face inside the scale
    radius = 20.0 + 45.0 * np.arange(false_peaks) / false_peaks
    inside = np.stack([128 + radius * np.cos(turn), 128 + radius * np.sin(turn)], axis=1)
    keypoints = keypoints_for(dial, majors=np.vstack([dial.notch_points(), inside]))
    total = len(keypoints.major) + len(keypoints.start) + len(keypoints.end)
    assert total == dial.majors + 2 + false_peaks
    arc = fit_scale_arc(keypoints, CROP)
    if read:
        assert arc, arc
        assert abs(arc.ellipse.a - 100) < 0.5 and len(arc.notches) == dial.majors + 2
    else:
        assert not arc and arc.reason == "poor_fit" and f"13 of {total}" in arc.detail, arc
    if read:  # without the evidence of a found end, 60% are needed
        from dataclasses import replace

        from gauged.reader.stages.keypoints import Peaks

        no_start = replace(keypoints, start=Peaks(np.zeros((0, 2)), np.zeros(0)))
        failure = fit_scale_arc(no_start, CROP)
        assert not failure and failure.reason == "poor_fit" and f"12 of {total - 1}" in failure.detail, failure


def test_fit_scale_arc_too_few_notches():
    dial = Dial(majors=2)
    failure = fit_scale_arc(keypoints_for(dial, start=False, end=False), CROP)
    assert failure.stage == "ellipse" and failure.reason == "too_few_notches"


def test_fit_scale_arc_poor_fit():
    rng = np.random.default_rng(1)
    dial = Dial(majors=14)
    scattered = rng.uniform(20, 236, (dial.majors, 2))  # peaks everywhere: no ring to be found
    failure = fit_scale_arc(keypoints_for(dial, majors=scattered, start=False, end=False), CROP)
    assert not failure and failure.reason in ("poor_fit", "degenerate_conic")


def test_fit_scale_arc_too_oblique():
    dial = Dial(ellipse=Ellipse(128, 128, 110, 25, 0.3))
    failure = fit_scale_arc(keypoints_for(dial), CROP)
    assert failure.reason == "too_oblique"


def test_fit_scale_arc_implausible_span():
    dial = Dial(start_deg=100, span_deg=30, majors=6)
    failure = fit_scale_arc(keypoints_for(dial), CROP)
    assert failure.reason == "implausible_span"


def test_fit_scale_arc_no_scale_ends():
    keypoints = keypoints_for(Dial(majors=3), start=False, end=False)
    failure = fit_scale_arc(keypoints, CROP, min_notches=3)
    assert not failure and failure.reason == "no_scale_ends"


def test_fit_scale_arc_numbers_in_the_gap_refute_inferred_ends():
    from gauged.geometry.dial_frame import point_at_dial_angle
    from gauged.reader.stages.keypoints import find_peaks
    from gauged.training.targets import gaussian_heatmap

    dial = Dial(start_deg=135, span_deg=270)
    # The model found only the notches of the upper half, so the largest gap is a false one...
    upper = dial.notch_points()[4:9]
    keypoints = keypoints_for(dial, start=False, end=False, majors=upper)
    # ...but numbers printed along the whole scale contradict it.
    numbers = point_at_dial_angle(dial.ellipse.scaled(0.8), dial.notch_angles())
    peaks = find_peaks(gaussian_heatmap(numbers, (128, 128), 2, 1.5), 2, 0.3, 64, 3)
    from dataclasses import replace

    failure = fit_scale_arc(replace(keypoints, numbers=peaks), CROP)
    assert not failure and failure.reason == "numbers_outside_scale"
    assert fit_scale_arc(keypoints, CROP)  # without the numbers the false gap is accepted
    # asked for the gap's ends whatever lies in it (a dial whose ends are hidden), it gives them
    arc = fit_scale_arc(replace(keypoints, numbers=peaks), CROP, ends_from_gap=True)
    assert arc and arc.ends_inferred
    first, last = dial.notch_angles()[4], dial.notch_angles()[8]
    assert abs(wrap_to_pi(arc.start_angle - first)) < math.radians(3)
    assert abs(wrap_to_pi(arc.end_angle - last)) < math.radians(3)


def test_fit_scale_arc_refuses_to_guess_ends_when_no_gap_stands_out():
    # 330 degrees in 8 steps of 41.25 degrees leaves a 30 degree gap: smaller than a step.
    dial = Dial(start_deg=105, span_deg=330, majors=9)
    failure = fit_scale_arc(keypoints_for(dial, start=False, end=False), CROP)
    assert not failure and failure.reason == "no_scale_ends"
    assert fit_scale_arc(keypoints_for(dial), CROP)  # with the end notches found it is read


@pytest.mark.parametrize("inner_majors", [9, 21])
def test_fit_scale_arc_on_a_dial_with_two_scales_takes_the_ring_with_the_ends(inner_majors):
    """bar outside, psi inside: the major-notch map marks both rings; the scale is the ring holding
    the start and end notches even when the inner ring has more notches."""
    outer = Dial(ellipse=Ellipse(128, 128, 100, 92, 0.3), majors=9)
    inner = Dial(ellipse=Ellipse(128, 128, 70, 64.4, 0.3), majors=inner_majors, start_deg=140, span_deg=260)
    notches = np.vstack([outer.notch_points(), inner.notch_points()])
    arc = fit_scale_arc(keypoints_for(outer, majors=notches, pivot=False), CROP)
    assert arc, arc
    assert abs(arc.ellipse.a - 100) < 0.5 and abs(arc.ellipse.b - 92) < 0.5
    assert abs(angle_difference(arc.start_angle, outer.start)) < math.radians(0.5)
    assert abs(angle_difference(arc.end_angle, outer.end)) < math.radians(0.5)


@pytest.mark.parametrize("seed", range(3))
def test_fit_scale_arc_finds_an_inner_ring_on_a_short_arc(seed):
    """An inner scale over a third of the dial (synthetic 000083) with a few stray peaks: a free
    ellipse through those notches bends to the strays, but the inner ring is the outer one scaled
    about its centre, so both rings explain their notches and the scale is the outer ring."""
    outer = Dial(ellipse=Ellipse(121, 129, 73, 52, 0.31), majors=13, start_deg=135, span_deg=270)
    inner = Dial(ellipse=Ellipse(121, 129, 41, 29.2, 0.31), majors=9, start_deg=150, span_deg=120)
    rng = np.random.default_rng(seed)
    strays = np.array([121, 129]) + rng.uniform(-30, 30, (4, 2))
    notches = np.vstack([outer.notch_points(), inner.notch_points() + rng.normal(0, 0.8, (9, 2)), strays])
    arc = fit_scale_arc(keypoints_for(outer, majors=notches, pivot=False), CROP)
    assert arc, arc
    assert abs(arc.ellipse.a - 73) < 0.5 and abs(arc.ellipse.b - 52) < 0.5
    assert abs(angle_difference(arc.start_angle, outer.start)) < math.radians(0.5)


def _distorted(even: np.ndarray) -> np.ndarray:
    """Notch angles bent smoothly (by up to ~2 degrees), as a slightly wrong ellipse bends them."""
    return even + math.radians(2.0) * np.sin((even - even[0]) / (even[-1] - even[0]) * math.pi)


def test_notch_grid_maps_bent_notch_angles_back_to_even_steps():
    even = np.linspace(1.0, 1.0 + math.radians(270), 11)
    measured = _distorted(even)
    knots, target = notch_grid(measured[1:-1], measured[0], measured[-1])
    assert np.allclose(knots, measured) and np.allclose(target, np.linspace(measured[0], measured[-1], 11))


def test_notch_grid_bridges_a_missed_notch():
    even = np.linspace(0.0, math.radians(240), 9)
    kept = np.delete(even, 4)[1:-1]  # the middle notch was not detected: one gap of two steps
    knots, target = notch_grid(kept, even[0], even[-1])
    assert np.allclose(target, np.delete(even, 4))


@pytest.mark.parametrize("extra", [math.radians(15.0), math.radians(40.0)])
def test_notch_grid_refuses_irregular_notches(extra):
    even = np.linspace(0.0, math.radians(240), 9)  # steps of 30 degrees
    notches = np.sort(np.append(even[1:-1], extra))  # a false peak half a step (or a third) off the grid
    assert notch_grid(notches, even[0], even[-1]) is None


def test_scale_arc_linear_reads_a_needle_on_a_bent_notch_at_its_true_place():
    e = Ellipse(128, 128, 100, 100, 0)
    start, span = math.radians(135), math.radians(270)
    even = start + np.linspace(0, span, 11)
    measured = _distorted(even)
    notches = point_at_dial_angle(e, measured)
    arc = ScaleArc(e, e.center, float(measured[0]), float(measured[-1]), wrap_angle(measured[0], measured[-1]),
                   notches, 0.0, False)
    for k in (2, 5, 7):  # the needle on the k-th notch reads k steps of the scale
        corrected = unwrap(arc.linear(float(measured[k])), arc.zero_angle)
        assert corrected == pytest.approx(unwrap(measured[0], arc.zero_angle) + k * (measured[-1] - measured[0]) / 10, abs=1e-9)
    outside = float(measured[0]) - 0.2
    assert arc.linear(outside) == pytest.approx(outside)


def test_scale_arc_puts_numbers_printed_beside_their_notch_on_it():
    e = Ellipse(128, 128, 100, 100, 0)
    start, step = math.radians(135), math.radians(27)  # 10 steps over 270 degrees
    even = start + step * np.arange(11)
    notches = point_at_dial_angle(e, np.delete(even, [3, 6]))  # two majors missed by the model
    arc = ScaleArc(e, e.center, float(even[0]), float(even[-1]), wrap_angle(even[0], even[-1]), notches, 0.0, False)
    # Numbers 6.6 degrees beside notches 2 and 6 (a missed one) and on notch 10 take the notches' angles;
    # one midway between notches, and one in the gap beyond the end, keep their own.
    off = math.radians(6.6)
    numbers = np.array([even[2] - off, even[6] + off, even[10], even[4] + 0.5 * step, even[10] + 2 * step])
    snapped = unwrap(arc.on_notches(arc.linear(numbers)), arc.zero_angle)
    expected = unwrap(np.array([even[2], even[6], even[10], even[4] + 0.5 * step, even[10] + 2 * step]), arc.zero_angle)
    assert snapped == pytest.approx(expected, abs=1e-9)


def test_scale_arc_leaves_numbers_alone_without_a_notch_grid():
    e = Ellipse(128, 128, 100, 100, 0)
    arc = ScaleArc(e, e.center, 2.4, 0.8, wrap_angle(2.4, 0.8), np.zeros((0, 2)), 0.0, False)
    angles = np.array([2.5, 3.0, -2.0])
    assert arc.on_notches(angles) == pytest.approx(angles)


def _with_numbers(keypoints, points, score=0.8):
    from dataclasses import replace

    from gauged.reader.stages.keypoints import Peaks

    pts = np.asarray(points, float).reshape(-1, 2)
    return replace(keypoints, numbers=Peaks(pts, np.full(len(pts), score)))


def test_one_number_in_the_gap_refutes_inferred_ends_but_not_found_ones():
    """Missed notches make a gap too: when the ends are only inferred from the largest gap, a single
    scale number in it says the guess is wrong; with found end notches one stray mark is tolerated."""
    dial = Dial(start_deg=135, span_deg=270)
    in_gap = point_at_dial_angle(dial.ellipse.scaled(0.8), math.radians(90.0))  # bottom, between the ends
    inferred = fit_scale_arc(_with_numbers(keypoints_for(dial, start=False, end=False), in_gap), CROP)
    assert isinstance(inferred, StageFailure) and inferred.reason == "numbers_outside_scale"
    found = fit_scale_arc(_with_numbers(keypoints_for(dial), in_gap), CROP)
    assert not isinstance(found, StageFailure), found
    two = point_at_dial_angle(dial.ellipse.scaled(0.8), np.radians([80.0, 100.0]))
    refused = fit_scale_arc(_with_numbers(keypoints_for(dial), two), CROP)
    assert isinstance(refused, StageFailure) and refused.reason == "numbers_outside_scale"
    far = point_at_dial_angle(dial.ellipse.scaled(0.2), np.radians([80.0, 100.0]))  # a maker's mark near the hub
    assert not isinstance(fit_scale_arc(_with_numbers(keypoints_for(dial), far), CROP), StageFailure)


def test_a_ring_whose_centre_is_far_from_the_needle_pivot_is_a_poor_fit():
    """A confident pivot 0.3 radii from the fitted ring's centre: the ring passes through notches on
    one side of the dial, not around it (synthetic 000287 came close), so it is refused."""
    from dataclasses import replace

    from gauged.reader.stages.keypoints import Peaks

    dial = Dial()
    keypoints = keypoints_for(dial)
    assert fit_scale_arc(keypoints, CROP)  # the pivot at the centre: read
    off = np.array([[dial.ellipse.cx + 0.3 * dial.ellipse.a, dial.ellipse.cy]])
    failure = fit_scale_arc(replace(keypoints, pivot=Peaks(off, np.array([0.9]))), CROP)
    assert not failure and failure.reason == "poor_fit" and "pivot" in failure.detail
    # an unsure pivot peak is no evidence
    assert fit_scale_arc(replace(keypoints, pivot=Peaks(off, np.array([0.35]))), CROP)


@pytest.mark.parametrize("seed", range(4))
def test_a_sector_scale_is_fitted_about_the_needle_pivot(seed):
    """A 90-degree scale of 11 notches found to 1.5 px (synthetic 000003): a free ellipse through
    so short an arc bends to any centre, so with a confident pivot the ring is fitted about it."""
    dial = Dial(ellipse=Ellipse(128, 128, 60, 60, 0.0), majors=11, start_deg=-45, span_deg=90)
    notches = dial.notch_points() + np.random.default_rng(seed).normal(0, 1.5, (11, 2))
    arc = fit_scale_arc(keypoints_for(dial, majors=notches), CROP)
    assert arc, arc
    assert math.hypot(arc.ellipse.cx - 128, arc.ellipse.cy - 128) < 3.0
    assert abs(math.sqrt(arc.ellipse.a * arc.ellipse.b) - 60) < 3.0
    assert abs(angle_difference(arc.start_angle, dial.start)) < math.radians(2)


def test_found_ends_refuted_by_numbers_give_way_to_the_notches_largest_gap():
    """The crop model took a mid-scale notch for the start (a real 0..160 dial's "start" at 120):
    the numbers printed between it and the end refute those ends, while the notches' largest gap,
    the scale's real one, holds no number: the arc is read with the ends from that gap."""
    from dataclasses import replace

    from gauged.reader.stages.keypoints import Peaks

    dial = Dial(start_deg=135, span_deg=270)
    notches = dial.notch_points()
    keypoints = keypoints_for(dial)
    false_start = Peaks(notches[7:8], np.array([0.9]))  # the 8th of 11 notches taken for the start
    numbers = point_at_dial_angle(dial.ellipse.scaled(0.8), dial.notch_angles())
    wrong = _with_numbers(replace(keypoints, start=false_start), numbers)
    arc = fit_scale_arc(wrong, CROP)
    assert not isinstance(arc, StageFailure), arc
    assert arc.ends_inferred
    assert math.degrees(arc.span) == pytest.approx(270, abs=3)
    assert math.degrees(math.remainder(arc.start_angle - dial.start, 2 * math.pi)) == pytest.approx(0, abs=3)
    # a number printed in the real gap too leaves no gap free of numbers: refused
    in_gap = point_at_dial_angle(dial.ellipse.scaled(0.8), math.radians(90.0))
    refused = fit_scale_arc(_with_numbers(replace(keypoints, start=false_start), np.vstack([numbers, in_gap])), CROP)
    assert isinstance(refused, StageFailure) and refused.reason == "numbers_outside_scale"
