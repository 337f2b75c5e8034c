"""Full-circle scales (dial indicators): numbers all the way round, no gap, read from the numbers."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gauged.geometry.angles import wrap_angle, wrap_to_pi
from gauged.reader.stages.ellipse import ScaleArc
from gauged.reader.stages.full_circle import fit_full_circle
from gauged.reader.stages.needle import NeedleReading
from gauged.reader.stages.reading import read_value
from gauged.reader.stages.scale import fit_scales
from gauged.types import Ellipse, NeedleLine, ScaleMarker, StageFailure

E = Ellipse(128, 128, 100, 100, 0)
TOP = -math.pi / 2  # where a dial indicator prints its 0


def _arc(start_deg: float = 128.0, end_deg: float = 86.0, inferred: bool = True) -> ScaleArc:
    """The arc the ellipse stage gives a full-circle dial: ends inferred from a missed notch's gap."""
    start, end = math.radians(start_deg), math.radians(end_deg)
    return ScaleArc(E, E.center, start, end, wrap_angle(start, end), np.zeros((0, 2)), 0.5, inferred)


def _numbers(values, degrees_per_unit: float = 36.0, zero: float = TOP, jitter_deg: float = 1.0, text=None):
    rng = np.random.default_rng(0)
    out = []
    for v in values:
        angle = wrap_to_pi(zero + math.radians(degrees_per_unit * v + rng.uniform(-jitter_deg, jitter_deg)))
        x, y = 128 + 80 * math.cos(angle), 128 + 80 * math.sin(angle)
        out.append(ScaleMarker(text(v) if text else f"{v:g}", float(v), (x - 6, y - 5, x + 6, y + 5), float(angle)))
    return out


def _needle_at(angle: float) -> NeedleReading:
    tip = (128 + 90 * math.cos(angle), 128 + 90 * math.sin(angle))
    line = NeedleLine((128.0, 128.0), (math.cos(angle), math.sin(angle)), tip)
    return NeedleReading(line, angle, mask_score=0.9, offset=0.0)


def test_numbers_one_to_nine_round_the_dial_make_a_zero_to_ten_full_circle():
    scale = fit_full_circle(_arc(), _numbers(range(1, 10)), "mm")
    assert scale is not None and scale.full_circle
    assert (scale.min_value, scale.unit) == (pytest.approx(0.0, abs=0.05), "mm")
    assert scale.max_value == pytest.approx(10.0)  # a turn is exactly ten steps
    for value in (0.0, 2.5, 5.0, 9.0):
        assert scale.value_at(wrap_to_pi(TOP + math.radians(36.0 * value))) == pytest.approx(value, abs=0.05)
    # a needle a hair before the zero reads a small negative value, not nearly 10
    assert scale.value_at(TOP - math.radians(1.0)) == pytest.approx(-1 / 36, abs=0.05)
    # the number at the seam and one more unread (a real dial indicator's "0" under the needle, "1")
    two_short = fit_full_circle(_arc(), _numbers(range(2, 10)), "mm")
    assert two_short is not None and (two_short.min_value, two_short.max_value) == (0.0, pytest.approx(10.0))
    assert fit_full_circle(_arc(), _numbers(range(3, 10)), "mm") is None  # three unread: too little of the turn


def test_a_sector_scale_or_found_ends_are_not_a_full_circle():
    # 0..8 over 270 degrees: a turn would be 10.7 steps, not a whole number
    assert fit_full_circle(_arc(), _numbers(range(9), degrees_per_unit=270 / 8, zero=math.radians(135)), None) is None
    # end notches found: the dial has a gap
    assert fit_full_circle(_arc(inferred=False), _numbers(range(1, 10)), None) is None
    # too few numbers, or numbers leaving half the turn empty
    assert fit_full_circle(_arc(), _numbers(range(1, 6)), None) is None
    assert fit_full_circle(_arc(), _numbers([0, 1, 2, 3, 4, 5], degrees_per_unit=30), None) is None
    # a letter read as a digit is no evidence: six numbers make a full circle, five and an "S" do not
    six = [1, 2, 3, 5, 7, 9]
    assert fit_full_circle(_arc(), _numbers(six), None) is not None
    assert fit_full_circle(_arc(), _numbers(six, text=lambda v: "S" if v == 5 else f"{v:g}"), None) is None


def test_the_scale_stage_reads_a_full_circle_dial_whose_inferred_ends_cut_its_numbers():
    arc = _arc()
    markers = _numbers(range(1, 10))
    ordinary = fit_full_circle(_arc(inferred=False), markers, None)
    assert ordinary is None
    scales = fit_scales(arc, markers)
    assert not isinstance(scales, StageFailure), scales
    (scale,) = scales
    assert scale.full_circle and scale.inliers == 9
    value = read_value(_needle_at(wrap_to_pi(TOP + math.radians(36.0 * 7.3))), arc, scale)
    assert not isinstance(value, StageFailure), value
    assert value.value == pytest.approx(7.3, abs=0.05)
    at_zero = read_value(_needle_at(TOP - math.radians(0.3)), arc, scale)
    assert abs(at_zero.value) < 0.05  # the needle at rest on the zero
