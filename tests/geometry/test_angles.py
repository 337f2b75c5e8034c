"""Wrap-around angle and unwrapping: the scale must be one continuous interval."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gauged.geometry.angles import angle_difference, scale_span, unwrap, wrap_angle, wrap_to_pi
from gauged.types import Ellipse, ScaleModel

TWO_PI = 2.0 * math.pi


def test_wrap_to_pi_range_and_types() -> None:
    angles = np.linspace(-20.0, 20.0, 1001)
    wrapped = wrap_to_pi(angles)
    assert wrapped.shape == angles.shape
    assert np.all(wrapped > -math.pi) and np.all(wrapped <= math.pi)
    assert np.allclose(np.cos(wrapped), np.cos(angles)) and np.allclose(np.sin(wrapped), np.sin(angles))
    assert isinstance(wrap_to_pi(7.0), float)
    assert wrap_to_pi(-math.pi) == pytest.approx(math.pi)


def test_wrap_angle_is_bottom_for_symmetric_270_degree_dial() -> None:
    zero = wrap_angle(math.radians(135.0), math.radians(45.0))
    assert math.degrees(zero) == pytest.approx(90.0)
    assert math.degrees(unwrap(math.radians(135.0), zero)) == pytest.approx(135.0)
    assert math.degrees(unwrap(math.radians(45.0), zero)) == pytest.approx(405.0)


@pytest.mark.parametrize("start_deg", [-170.0, -90.0, 0.0, 100.0, 135.0, 179.0])
@pytest.mark.parametrize("span_deg", [30.0, 180.0, 270.0, 300.0, 350.0])
def test_wrap_angle_is_middle_of_gap_over_swept_dials(start_deg: float, span_deg: float) -> None:
    start = math.radians(start_deg)
    end = float(wrap_to_pi(start + math.radians(span_deg)))
    zero = wrap_angle(start, end)
    gap = TWO_PI - math.radians(span_deg)
    assert scale_span(start, end) == pytest.approx(math.radians(span_deg))
    # Both notches sit half a gap away from the discontinuity.
    assert unwrap(start, zero) - zero == pytest.approx(gap / 2.0)
    assert zero + TWO_PI - unwrap(end, zero) == pytest.approx(gap / 2.0)


def test_unwrap_agrees_with_scale_model() -> None:
    model = ScaleModel(Ellipse(0, 0, 1, 1, 0), slope=1.0, intercept=0.0, zero_angle=1.2, min_value=0, max_value=1)
    for angle in np.linspace(-7.0, 7.0, 57):
        assert unwrap(float(angle), 1.2) == pytest.approx(model.unwrap(float(angle)))


def test_unwrap_keeps_array_shape() -> None:
    out = unwrap(np.array([[0.0, 1.0], [2.0, 3.0]]), -1.0)
    assert out.shape == (2, 2)
    assert np.all((out >= -1.0) & (out < -1.0 + TWO_PI))


def test_angle_difference_is_signed_and_short() -> None:
    assert angle_difference(math.radians(10.0), math.radians(350.0)) == pytest.approx(math.radians(20.0))
    assert angle_difference(math.radians(350.0), math.radians(10.0)) == pytest.approx(math.radians(-20.0))


@settings(max_examples=200, deadline=None)
@given(
    start=st.floats(-math.pi, math.pi),
    span=st.floats(math.radians(10.0), math.radians(350.0)),
    fractions=st.lists(st.floats(0.0, 1.0), min_size=2, max_size=30),
)
def test_unwrap_is_continuous_over_the_scale(start: float, span: float, fractions: list[float]) -> None:
    end = float(wrap_to_pi(start + span))
    zero = wrap_angle(start, end)
    gap = TWO_PI - span
    # Sample the scale and up to 45% of the half-gap beyond either notch (noisy readings near the stops).
    s = np.sort(np.array(fractions))
    along = -0.45 * gap / 2.0 + s * (span + 0.45 * gap)
    unwrapped = np.asarray(unwrap(wrap_to_pi(start + along), zero))
    expected = unwrap(start, zero) + along
    assert np.allclose(unwrapped, expected, atol=1e-9)
    assert np.all(np.diff(unwrapped) >= -1e-9)
