"""The needle scan on dials drawn at a known needle angle: it reads the angle back, and refuses when
it cannot tell (a second stroke, no stroke, an unsupported jump, a line off the pivot, no anchor)."""

from __future__ import annotations

import math
import re
from dataclasses import replace
from pathlib import Path

import cv2
import numpy as np
import pytest

from gauged.geometry.angles import wrap_angle, wrap_to_pi
from gauged.geometry.dial_frame import from_unit_circle
from gauged.reader.stages import needle_scan
from gauged.reader.stages.ellipse import ScaleArc
from gauged.reader.stages.needle import NeedleReading
from gauged.reader.stages.needle_scan import (
    NeedleLook,
    ScannedNeedle,
    anchor_offset,
    follow_needle,
    learn_needle_look,
    pivot_offset,
    scan_needle,
)
from gauged.types import Ellipse, NeedleLine, StageFailure

from ..dial_maps import CROP, Dial

LIGHT = ((222, 226, 220), (35, 30, 30))  # (face, needle and print) BGR: a dark needle on a light face
DARK = ((70, 30, 25), (240, 240, 240))  # a white needle on a navy face
ROUND = (Dial(), None)
TILTED = (Dial(ellipse=Ellipse(128.0, 126.0, 100.0, 80.0, 0.4)), None)
PERSPECTIVE = (Dial(ellipse=Ellipse(128.0, 126.0, 100.0, 80.0, 0.4)), (131.0, 122.0))  # the pivot off the centre


def arc_of(dial: Dial, centre: tuple[float, float] | None = None) -> ScaleArc:
    """The locked arc of ``dial``: angles about ``centre`` (the pivot's image), else the ellipse centre."""
    return ScaleArc(dial.ellipse, centre or dial.ellipse.center, dial.start, dial.end, wrap_angle(dial.start, dial.end),
                    np.zeros((0, 2)), 0.0, False)


def render(dial: Dial, needle_deg: float | tuple[float, ...], centre: tuple[float, float] | None = None,
           colours=LIGHT, needle=None, width: float = 0.05, length: float = 0.85, offset: float = 0.0,
           numbers: bool = True) -> np.ndarray:
    """A (CROP, CROP, 3) dial: ring, ticks, printed numbers (ink blocks at 0.74-0.82 radii) and one needle
    per angle in ``needle_deg`` (dial angles, degrees), drawn in the dial frame (the unit circle about
    the pivot) and mapped into the image, so a straight needle through the pivot reads its angle."""
    face, ink = colours
    image = np.full((CROP, CROP, 3), face, np.uint8)

    def fill(points: np.ndarray, colour) -> None:
        pixels = from_unit_circle(dial.ellipse, np.asarray(points, float), centre)
        cv2.fillPoly(image, [np.rint((pixels - 0.5) * 16).astype(np.int32)], colour, cv2.LINE_AA, shift=4)

    def band(angle: float, r0: float, r1: float, half: float, colour, shift: float = 0.0) -> None:
        u, n = np.array([math.cos(angle), math.sin(angle)]), np.array([-math.sin(angle), math.cos(angle)])
        half0, half1 = (half, half) if np.ndim(half) == 0 else half
        fill([r0 * u + (shift - half0) * n, r1 * u + (shift - half1) * n, r1 * u + (shift + half1) * n,
              r0 * u + (shift + half0) * n], colour)

    ring = np.radians(np.arange(0.0, 360.0, 2.0))
    cv2.polylines(image, [np.rint((from_unit_circle(dial.ellipse, np.stack([np.cos(ring), np.sin(ring)], 1), centre)
                                   - 0.5) * 16).astype(np.int32)], True, ink, 1, cv2.LINE_AA, shift=4)
    for k, angle in enumerate(np.radians(dial.start_deg + np.linspace(0.0, dial.span_deg, 5 * (dial.majors - 1) + 1))):
        major = k % 5 == 0
        band(angle, 0.9 if major else 0.95, 1.0, 0.012 if major else 0.005, ink)
        if major and numbers:
            band(angle, 0.74, 0.82, 0.05, ink)
    for deg in np.atleast_1d(needle_deg):
        angle = math.radians(deg)
        band(angle, 0.0, length, (width / 2, width / 6), needle or ink, offset)
        band(angle + math.pi, 0.0, 0.2, width / 2, needle or ink, -offset)  # the tail
    hub = np.radians(np.arange(0.0, 360.0, 10.0))
    fill(0.06 * np.stack([np.cos(hub), np.sin(hub)], 1), needle or ink)
    return image


def shifted(image: np.ndarray, dx: float, dy: float) -> np.ndarray:
    """``image`` moved by (dx, dy) px, as a camera's shake or a knock moves the dial against its lock."""
    return cv2.warpAffine(image, np.float32([[1, 0, dx], [0, 1, dy]]), (CROP, CROP), borderMode=cv2.BORDER_REPLICATE)


def crop_model_read(deg: float, offset: float = 0.0) -> NeedleReading:
    """What the crop model would say of a needle drawn at ``deg``: its angle where it meets the ring."""
    angle = math.radians(deg) + math.asin(offset)
    return NeedleReading(NeedleLine((0.0, 0.0), (math.cos(angle), math.sin(angle)), (0.0, 0.0)), angle, 0.97, offset)


def learnt(dial_centre, deg: float, previous: NeedleLook | None = None, **drawn) -> NeedleLook:
    dial, centre = dial_centre
    look = learn_needle_look(render(dial, deg, centre, **drawn), arc_of(dial, centre), crop_model_read(deg), previous)
    assert isinstance(look, NeedleLook), look
    return look


def degrees_off(angle: float, deg: float) -> float:
    return abs(math.degrees(wrap_to_pi(angle - math.radians(deg))))


def assert_failure(result, reason: str) -> StageFailure:
    assert isinstance(result, StageFailure), f"expected needle_scan/{reason}, got {result!r}"
    assert (result.stage, result.reason) == ("needle_scan", reason), result
    return result


# reading the angle back -----------------------------------------------------------------------------

@pytest.mark.parametrize("dial_centre", [ROUND, TILTED, PERSPECTIVE], ids=["round", "tilted", "perspective"])
@pytest.mark.parametrize("colours", [LIGHT, DARK], ids=["dark_needle", "white_needle"])
def test_scan_needle_reads_the_drawn_angle_back(dial_centre, colours):
    dial, centre = dial_centre
    look = learnt(dial_centre, 220.0, colours=colours)
    assert look.polarity == (1.0 if colours is LIGHT else -1.0)
    for deg in (205.0, 214.0, 220.0, 224.0, 232.0, 238.0):  # within ANCHOR_NEAR of the read it learnt from
        needle = scan_needle(render(dial, deg, centre, colours=colours), arc_of(dial, centre), look)
        assert isinstance(needle, ScannedNeedle), needle
        assert degrees_off(needle.angle, deg) < 0.6, (deg, math.degrees(needle.angle))
        assert needle.mask_score == look.mask_score and needle.offset < 0.01


def test_scan_needle_follows_the_needle_round_the_scale():
    """The runner's way: scans follow the needle, and each crop-model read (here every third angle)
    re-learns the look and adds an anchor where the needle now is."""
    dial, centre = PERSPECTIVE
    arc = arc_of(dial, centre)
    look = learnt(PERSPECTIVE, 140.0)
    reads = 1
    for k, deg in enumerate(np.arange(146.0, 400.0, 6.0)):
        if k % 3 == 2:
            look, reads = learnt(PERSPECTIVE, float(deg), look), reads + 1
            continue
        needle = scan_needle(render(dial, float(deg), centre), arc, look)
        assert isinstance(needle, ScannedNeedle), (deg, needle)
        assert degrees_off(needle.angle, float(deg)) < 0.6, (deg, math.degrees(needle.angle))
        look = follow_needle(look, needle)
    assert len(look.lines) == needle_scan.LINES and len(look.anchors) == min(reads, needle_scan.ANCHORS) == 15


def test_an_off_centre_needle_is_read_where_it_crosses_the_ring():
    """A needle whose line passes 0.05 radii beside the locked pivot (a pivot found a little off) is
    read where it meets the ring, as the crop model's needle stage reads it."""
    dial, centre = ROUND
    look = learn_needle_look(render(dial, 250.0, offset=0.05), arc_of(dial), crop_model_read(250.0, 0.05))
    assert isinstance(look, NeedleLook), look
    needle = scan_needle(render(dial, 256.0, offset=0.05), arc_of(dial), look)
    assert isinstance(needle, ScannedNeedle), needle
    assert abs(needle.signed_offset - 0.05) < 0.005
    assert degrees_off(needle.crossing, 256.0 + math.degrees(math.asin(0.05))) < 0.25
    assert degrees_off(needle.angle, 256.0 + math.degrees(math.asin(0.05))) < 0.25


def test_the_shake_of_a_fixed_camera_averages_out():
    """The dial shaking a pixel against the locked arc moves where the needle crosses the ring, not its
    direction: read through the pivot's fitted offset, the readings of a still needle spread far less."""
    dial, centre = ROUND
    arc = arc_of(dial)
    rng = np.random.default_rng(7)
    still = render(dial, 300.0)
    look = learnt(ROUND, 300.0)
    crossings, readings = [], []
    for _ in range(24):
        dx, dy = rng.normal(0.0, 0.8, 2)
        needle = scan_needle(shifted(still, dx, dy), arc, look)
        assert isinstance(needle, ScannedNeedle), needle
        look = follow_needle(look, needle)
        crossings.append(math.degrees(needle.crossing))
        readings.append(math.degrees(needle.angle))
    assert np.std(readings[8:]) < 0.5 * np.std(crossings[8:])
    assert abs(np.mean(readings[8:]) - (300.0 - 360.0)) < 0.35


def test_pivot_offset_fits_a_fixed_pivot_shift():
    e = np.array([0.02, -0.01])
    turning = tuple((t, float(e @ (-math.sin(t), math.cos(t)))) for t in np.radians(np.arange(150.0, 390.0, 20.0)))
    assert np.allclose(pivot_offset(turning), e, atol=1e-3)
    still = ((1.0, 0.015),) * 5  # a still needle: only the component across it is known, and that is what counts
    across = pivot_offset(still) @ (-math.sin(1.0), math.cos(1.0))
    assert abs(across - 0.015) < 0.001


def test_anchor_offset_is_the_median_of_the_anchors_near_the_angle():
    anchors = ((0.0, 0.01), (0.1, 0.03), (0.2, 0.02), (2.0, -0.5))
    assert anchor_offset(anchors, 0.1) == pytest.approx(0.02)
    assert anchor_offset(anchors, 2.05) == pytest.approx(-0.5)
    assert anchor_offset(anchors, -2.0) is None
    assert anchor_offset((), 0.0) is None


# learning the look --------------------------------------------------------------------------------

def test_learn_needle_look_takes_the_channel_that_shows_a_coloured_needle():
    """A red needle on a green face is nearly as bright as the face in grey; the red or green channel shows it."""
    look = learnt(ROUND, 260.0, colours=((40, 120, 40), (40, 40, 200)))
    assert look.channel in (1, 2)


def test_learn_needle_look_leaves_out_the_circles_of_printed_numbers():
    with_numbers = learnt(ROUND, 260.0)
    plain = learnt(ROUND, 260.0, numbers=False)
    assert not any(0.75 <= r <= 0.8 for r in with_numbers.radii)
    assert any(0.75 <= r <= 0.8 for r in plain.radii)
    assert min(with_numbers.radii) >= needle_scan.INNER_MIN and max(plain.radii) <= 0.85 - needle_scan.TIP_MARGIN + 1e-9


def test_learn_faint_needle_when_the_needle_is_nearly_the_face():
    dial, _ = ROUND
    image = render(dial, 260.0, needle=(214, 218, 212))  # 8 grey levels from the face
    assert_failure(learn_needle_look(image, arc_of(dial), crop_model_read(260.0)), "faint_needle")


def test_learn_short_needle_when_it_shows_on_too_few_circles():
    dial, _ = ROUND
    image = render(dial, 260.0, length=0.52)
    assert_failure(learn_needle_look(image, arc_of(dial), crop_model_read(260.0)), "short_needle")


def test_learn_scan_disagrees_when_the_crop_it_learns_from_has_two_needles():
    dial, _ = ROUND
    image = render(dial, (230.0, 320.0))
    failure = assert_failure(learn_needle_look(image, arc_of(dial), crop_model_read(230.0)), "scan_disagrees")
    assert "two_peaks" in failure.detail


def test_learn_scan_disagrees_when_the_crop_model_points_beside_the_needle():
    dial, _ = ROUND
    look = learn_needle_look(render(dial, 260.0), arc_of(dial), crop_model_read(257.0))  # beside the needle
    failure = assert_failure(look, "scan_disagrees")
    assert "degrees from the crop model" in failure.detail


# refusing what the scan cannot tell ----------------------------------------------------------------

def test_two_peaks_when_a_second_needle_shows():
    dial, _ = ROUND
    look = learnt(ROUND, 260.0)
    failure = assert_failure(scan_needle(render(dial, (262.0, 330.0)), arc_of(dial), look), "two_peaks")
    assert "68 degrees" in failure.detail or "67 degrees" in failure.detail or "69 degrees" in failure.detail


def test_no_clear_peak_when_the_needle_is_gone():
    dial, _ = ROUND
    look = learnt(ROUND, 260.0)
    assert_failure(scan_needle(render(dial, (), numbers=True), arc_of(dial), look), "no_clear_peak")


def test_unsupported_jump_when_a_fainter_stroke_lies_far_from_the_last_angle():
    """A stroke 70 degrees from where the needle was, at 70% of the needle's contrast: perhaps the
    needle, perhaps a shadow or a cable; the crop model decides. The same stroke near the last angle
    is the needle."""
    dial, _ = ROUND
    face, ink = LIGHT
    faded = tuple(int(0.3 * f + 0.7 * i) for f, i in zip(face, ink))
    look = replace(learnt(ROUND, 260.0), anchors=((math.radians(330.0), 0.0), (math.radians(260.0), 0.0)))
    image = render(dial, 330.0, needle=faded)
    assert_failure(scan_needle(image, arc_of(dial), look), "unsupported_jump")
    assert isinstance(scan_needle(image, arc_of(dial), replace(look, angle=math.radians(320.0))), ScannedNeedle)


def test_needle_off_centre_when_the_line_misses_the_pivot(monkeypatch):
    dial, _ = ROUND
    look = learn_needle_look(render(dial, 250.0, offset=0.05), arc_of(dial), crop_model_read(250.0, 0.05))
    assert isinstance(look, NeedleLook), look
    monkeypatch.setattr(needle_scan, "MAX_OFFSET", 0.03)
    failure = assert_failure(scan_needle(render(dial, 250.0, offset=0.05), arc_of(dial), look), "needle_off_centre")
    assert "0.05 radii" in failure.detail


def test_pivot_moved_when_the_needle_turns_about_another_point_than_the_scans_before():
    """The dial knocked 8 px across its needle: the needle's line passes 0.08 radii from where it
    turned so far. The scan leaves that frame to the crop model, whose pivot check releases the lock
    when the dial stays moved; the shake of a fixed camera (a pixel) is far below that."""
    dial, _ = ROUND
    arc, still = arc_of(dial), render(dial, 300.0)
    look = learnt(ROUND, 300.0)
    for dx, dy in ((0.6, -0.4), (-0.5, 0.7), (0.3, 0.2)):
        needle = scan_needle(shifted(still, dx, dy), arc, look)
        assert isinstance(needle, ScannedNeedle), needle
        look = follow_needle(look, needle)
    across = 8.0 * np.array([-math.sin(math.radians(300.0)), math.cos(math.radians(300.0))])
    failure = assert_failure(scan_needle(shifted(still, *across), arc, look), "pivot_moved")
    assert re.search(r"passes 0\.0[78]\d radii", failure.detail)


def test_no_anchor_when_no_crop_model_read_lies_near_the_scanned_angle():
    dial, _ = ROUND
    look = learnt(ROUND, 200.0)
    assert isinstance(scan_needle(render(dial, 215.0), arc_of(dial), look), ScannedNeedle)
    assert_failure(scan_needle(render(dial, 240.0), arc_of(dial), look), "no_anchor")


def test_scan_needle_takes_a_colour_crop_only():
    dial, _ = ROUND
    look = learnt(ROUND, 200.0)
    with pytest.raises(ValueError, match="crop must be"):
        scan_needle(cv2.cvtColor(render(dial, 200.0), cv2.COLOR_BGR2GRAY), arc_of(dial), look)


def test_every_reason_of_the_scan_is_provoked_here():
    text = Path(__file__).read_text()
    assert all(f'"{reason}")' in text for reason in needle_scan.REASONS), needle_scan.REASONS
