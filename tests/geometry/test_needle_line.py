"""Needle line fit (total least squares) and its intersection with the scale ellipse."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gauged.geometry.angles import angle_difference
from gauged.geometry.dial_frame import dial_angle, dial_direction_angle, normalized_radius
from gauged.geometry.ellipse_fit import fit_ellipse_direct
from gauged.geometry.needle_line import fit_needle_line, intersect_line_ellipse, needle_dial_angle
from gauged.types import Ellipse, StageFailure


def _needle_pixels(pivot: np.ndarray, angle: float, length: float, width: float, tail: float = 0.0) -> np.ndarray:
    """Centres (N, 2) of the pixels covered by a needle from ``pivot - tail * d`` to ``pivot + length * d``."""
    d = np.array([math.cos(angle), math.sin(angle)])
    n = np.array([-d[1], d[0]])
    reach = length + tail + width
    xs = np.arange(math.floor(pivot[0] - reach), math.ceil(pivot[0] + reach)) + 0.5
    ys = np.arange(math.floor(pivot[1] - reach), math.ceil(pivot[1] + reach)) + 0.5
    grid = np.stack(np.meshgrid(xs, ys), axis=-1).reshape(-1, 2)
    along, across = (grid - pivot) @ d, (grid - pivot) @ n
    return grid[(along >= -tail) & (along <= length) & (np.abs(across) <= width / 2.0)]


@pytest.mark.parametrize("angle_deg", np.arange(-180.0, 180.0, 15.0))
@pytest.mark.parametrize(("length", "width", "tail"), [(100.0, 3.0, 0.0), (60.0, 6.0, 15.0), (200.0, 2.0, 40.0)])
def test_fit_needle_line_round_trip_over_swept_needles(angle_deg: float, length: float, width: float, tail: float) -> None:
    pivot = np.array([320.3, 240.7])
    angle = math.radians(angle_deg)
    line = fit_needle_line(_needle_pixels(pivot, angle, length, width, tail), pivot)
    assert line, line
    assert abs(math.degrees(angle_difference(line.angle, angle))) < 0.3
    true_tip = pivot + length * np.array([math.cos(angle), math.sin(angle)])
    assert math.dist(line.tip, true_tip) < 1.0
    # The fitted line passes within a fraction of a pixel of the pivot.
    dx, dy = line.direction
    rel = pivot - np.array(line.point)
    assert abs(dx * rel[1] - dy * rel[0]) < 0.5
    assert line.rms_px == pytest.approx(width / math.sqrt(12.0), rel=0.5)
    assert line.support == len(_needle_pixels(pivot, angle, length, width, tail))


def test_fit_needle_line_tip_side_follows_the_pivot() -> None:
    pixels = _needle_pixels(np.array([0.0, 0.0]), 0.0, 100.0, 3.0)
    towards_plus_x = fit_needle_line(pixels, pivot=(0.0, 0.0))
    towards_minus_x = fit_needle_line(pixels, pivot=(100.0, 0.0))
    assert towards_plus_x.direction[0] == pytest.approx(1.0)
    assert towards_minus_x.direction[0] == pytest.approx(-1.0)
    assert towards_minus_x.tip[0] < 1.0


def test_fit_needle_line_ignores_zero_weight_pixels() -> None:
    pixels = _needle_pixels(np.array([50.0, 50.0]), 0.7, 80.0, 3.0)
    clutter = np.random.default_rng(0).uniform(0.0, 150.0, (200, 2))
    weights = np.concatenate([np.ones(len(pixels)), np.zeros(len(clutter))])
    weighted = fit_needle_line(np.vstack([pixels, clutter]), (50.0, 50.0), weights=weights)
    plain = fit_needle_line(pixels, (50.0, 50.0))
    assert weighted.direction == pytest.approx(plain.direction)
    assert weighted.support == len(pixels)


@settings(max_examples=100, deadline=None)
@given(angle=st.floats(-math.pi, math.pi), noise=st.floats(0.0, 1.0), seed=st.integers(0, 2**32 - 1))
def test_fit_needle_line_direction_under_pixel_noise(angle: float, noise: float, seed: int) -> None:
    pivot = np.array([200.0, 200.0])
    pixels = _needle_pixels(pivot, angle, 120.0, 4.0)
    pixels = pixels + np.random.default_rng(seed).normal(0.0, noise, pixels.shape)
    line = fit_needle_line(pixels, pivot)
    assert abs(math.degrees(angle_difference(line.angle, angle))) < 0.5


@pytest.mark.parametrize("n", [0, 1, 9])
def test_fit_needle_line_too_few_pixels(n: int) -> None:
    result = fit_needle_line(_needle_pixels(np.array([0.0, 0.0]), 0.0, 100.0, 1.0)[:n], (0.0, 0.0))
    assert isinstance(result, StageFailure)
    assert (result.stage, result.reason) == ("needle", "too_few_pixels")


def test_fit_needle_line_degenerate_line_for_a_round_blob() -> None:
    grid = np.stack(np.meshgrid(np.arange(20) + 0.5, np.arange(20) + 0.5), axis=-1).reshape(-1, 2)
    blob = grid[np.hypot(grid[:, 0] - 10.0, grid[:, 1] - 10.0) < 8.0]
    result = fit_needle_line(blob, (10.0, 10.0))
    assert isinstance(result, StageFailure)
    assert (result.stage, result.reason) == ("needle", "degenerate_line")


def test_fit_needle_line_rejects_bad_weights() -> None:
    with pytest.raises(ValueError, match="weights"):
        fit_needle_line(np.zeros((20, 2)), (0.0, 0.0), weights=-np.ones(20))


ELLIPSES = [Ellipse(320.0, 240.0, 150.0, 150.0, 0.0), Ellipse(320.0, 240.0, 150.0, 90.0, 0.4)]


@pytest.mark.parametrize("ellipse", ELLIPSES)
@pytest.mark.parametrize("angle_deg", np.arange(-180.0, 180.0, 20.0))
def test_intersect_line_ellipse_from_the_centre(ellipse: Ellipse, angle_deg: float) -> None:
    direction = np.array([math.cos(math.radians(angle_deg)), math.sin(math.radians(angle_deg))])
    hit = intersect_line_ellipse(ellipse, ellipse.center, direction)
    assert normalized_radius(ellipse, hit[None, :])[0] == pytest.approx(1.0)
    assert (hit - np.array(ellipse.center)) @ direction > 0.0  # on the tip side
    assert angle_difference(dial_angle(ellipse, hit[None, :])[0], dial_direction_angle(ellipse, direction)) == (
        pytest.approx(0.0, abs=1e-12)
    )


@pytest.mark.parametrize("ellipse", ELLIPSES)
def test_intersect_line_ellipse_picks_the_tip_side_from_an_off_centre_point(ellipse: Ellipse) -> None:
    point = np.array(ellipse.center) + np.array([30.0, -20.0])
    forward = intersect_line_ellipse(ellipse, point, (1.0, 1.0))
    backward = intersect_line_ellipse(ellipse, point, (-1.0, -1.0))
    assert forward[0] > point[0] and backward[0] < point[0]
    assert np.allclose(normalized_radius(ellipse, np.stack([forward, backward])), 1.0)
    # Both lie on the same line through the point.
    (fx, fy), (bx, by) = forward - point, backward - point
    assert abs(fx * by - fy * bx) < 1e-6


def test_intersect_line_ellipse_no_intersection() -> None:
    result = intersect_line_ellipse(ELLIPSES[1], (320.0, 0.0), (1.0, 0.0))
    assert isinstance(result, StageFailure)
    assert (result.stage, result.reason) == ("needle", "no_intersection")


def test_intersect_line_ellipse_intersection_behind() -> None:
    result = intersect_line_ellipse(ELLIPSES[0], (600.0, 240.0), (1.0, 0.0))
    assert isinstance(result, StageFailure)
    assert (result.stage, result.reason) == ("needle", "intersection_behind")


def test_intersect_line_ellipse_rejects_zero_direction() -> None:
    with pytest.raises(ValueError, match="direction"):
        intersect_line_ellipse(ELLIPSES[0], (0.0, 0.0), (0.0, 0.0))


@pytest.mark.parametrize("angle_deg", [-135.0, -30.0, 0.0, 90.0, 170.0])
def test_needle_dial_angle_reads_a_rendered_needle(tilted_dial, angle_deg: float) -> None:
    # A needle drawn in the dial plane of a tilted camera, read back through the projective frame.
    angle = math.radians(angle_deg)
    project = tilted_dial(15.0, 100.0, 35.0)
    ellipse = fit_ellipse_direct(project(np.linspace(-math.pi, math.pi, 60, endpoint=False)))
    pivot = project(None)[0]
    tip = tilted_dial(0.8 * 15.0, 100.0, 35.0)(np.array([angle]))[0]
    along = np.linspace(0.0, 1.0, 400)[:, None]
    pixels = pivot + along * (tip - pivot) + np.random.default_rng(0).normal(0.0, 0.7, (400, 2))
    needle = fit_needle_line(pixels, pivot)
    reference = dial_angle(ellipse, project(np.array([0.0])), pivot)[0]  # the frame's offset
    read = needle_dial_angle(ellipse, needle, pivot)
    assert abs(math.degrees(angle_difference(read - reference, angle))) < 0.5


def test_needle_dial_angle_passes_failures_through() -> None:
    needle = fit_needle_line(_needle_pixels(np.array([320.0, 0.0]), 0.0, 100.0, 3.0), (320.0, 0.0))
    result = needle_dial_angle(ELLIPSES[1], needle)
    assert isinstance(result, StageFailure) and result.reason == "no_intersection"
