"""The dial frame and its angles, affine and with the true centre (perspective)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gauged.geometry.angles import angle_difference
from gauged.geometry.dial_frame import (
    apply_homography,
    as_points,
    dial_angle,
    dial_direction_angle,
    dial_homography,
    from_unit_circle,
    normalized_radius,
    param_angle,
    point_at_dial_angle,
    polar_angle,
    to_unit_circle,
)
from gauged.geometry.ellipse_fit import fit_ellipse_direct
from gauged.types import Ellipse

ELLIPSES = [
    Ellipse(320.0, 240.0, 150.0, 150.0, 0.0),
    Ellipse(320.0, 240.0, 150.0, 100.0, 0.3),
    Ellipse(10.0, 900.0, 400.0, 60.0, 2.9),
    Ellipse(0.0, 0.0, 1.0, 0.99, 1.5),
]
ANGLES = np.linspace(-math.pi, math.pi, 37, endpoint=False)


@pytest.mark.parametrize("ellipse", ELLIPSES)
def test_dial_angle_round_trips_points_on_the_ellipse(ellipse: Ellipse) -> None:
    points = point_at_dial_angle(ellipse, ANGLES)
    assert np.allclose(normalized_radius(ellipse, points), 1.0, atol=1e-12)
    assert np.allclose(angle_difference(dial_angle(ellipse, points), ANGLES), 0.0, atol=1e-12)
    # dial angle = theta + parametric angle, the same for theta and theta + pi
    assert np.allclose(angle_difference(param_angle(ellipse, points) + ellipse.theta, ANGLES), 0.0, atol=1e-12)
    flipped = Ellipse(ellipse.cx, ellipse.cy, ellipse.a, ellipse.b, ellipse.theta + math.pi)
    assert np.allclose(angle_difference(dial_angle(flipped, points), ANGLES), 0.0, atol=1e-12)


@pytest.mark.parametrize("ellipse", ELLIPSES)
def test_dial_angle_is_constant_along_rays_from_the_centre(ellipse: Ellipse) -> None:
    ring = point_at_dial_angle(ellipse, ANGLES)
    centre = np.array(ellipse.center)
    for fraction in (0.2, 0.7, 1.3):
        assert np.allclose(angle_difference(dial_angle(ellipse, centre + fraction * (ring - centre)), ANGLES), 0.0)


def test_dial_angle_equals_polar_angle_on_a_circle() -> None:
    circle = Ellipse(50.0, 60.0, 20.0, 20.0, 1.1)
    points = np.random.default_rng(0).uniform(0.0, 100.0, (50, 2))
    assert np.allclose(angle_difference(dial_angle(circle, points), polar_angle(circle, points)), 0.0)


def test_dial_angle_differs_from_polar_angle_on_a_tilted_dial() -> None:
    ellipse = Ellipse(100.0, 100.0, 50.0, 25.0, 0.0)
    point = np.array([[125.0, 125.0]])
    assert dial_angle(ellipse, point)[0] == pytest.approx(math.atan2(1.0, 0.5))
    assert polar_angle(ellipse, point)[0] == pytest.approx(math.pi / 4.0)


@pytest.mark.parametrize("ellipse", ELLIPSES)
def test_unit_circle_maps_are_inverse(ellipse: Ellipse) -> None:
    points = np.random.default_rng(1).normal(ellipse.center, ellipse.a, (20, 2))
    assert np.allclose(from_unit_circle(ellipse, to_unit_circle(ellipse, points)), points)
    inside = np.array(ellipse.center) + 0.1 * ellipse.b
    assert np.allclose(from_unit_circle(ellipse, to_unit_circle(ellipse, points, inside), inside), points)


@pytest.mark.parametrize("ellipse", ELLIPSES[:3])
@pytest.mark.parametrize("angle", [0.0, 1.0, -2.5])
def test_dial_direction_angle_matches_the_ring_point(ellipse: Ellipse, angle: float) -> None:
    ring = point_at_dial_angle(ellipse, angle)[0]
    assert dial_direction_angle(ellipse, ring - np.array(ellipse.center)) == pytest.approx(angle)
    centre = np.array(ellipse.center) + np.array([0.05, -0.03]) * ellipse.b
    assert angle_difference(dial_direction_angle(ellipse, ring - centre, centre), dial_angle(ellipse, ring, centre)[0]) == (
        pytest.approx(0.0, abs=1e-9)
    )


@pytest.mark.parametrize("tilt_deg", [0.0, 20.0, 40.0, 60.0])
@pytest.mark.parametrize("ratio", [0.05, 0.1, 0.2])
def test_dial_angle_with_true_centre_is_exact_under_perspective(tilted_dial, tilt_deg: float, ratio: float) -> None:
    project = tilted_dial(ratio * 100.0, 100.0, tilt_deg)
    truth = np.linspace(-math.pi, math.pi, 200, endpoint=False)
    ellipse = fit_ellipse_direct(project(truth))
    centre = project(None)[0]
    error = angle_difference(dial_angle(ellipse, project(truth), centre), truth)
    assert np.abs(error - np.mean(error)).max() < 1e-9
    # Points inside the dial (the printed numbers, the needle) too:
    inner = tilted_dial(0.6 * ratio * 100.0, 100.0, tilt_deg)(truth)
    inner_error = angle_difference(dial_angle(ellipse, inner, centre), truth)
    assert np.abs(inner_error - np.mean(error)).max() < 1e-9
    assert np.allclose(normalized_radius(ellipse, project(truth)), 1.0, atol=1e-9)


def test_affine_dial_angle_bends_under_perspective(tilted_dial) -> None:
    # The documented limit of the affine frame: ~3.7 degrees at radius/distance 0.1 and 40 degrees.
    project = tilted_dial(10.0, 100.0, 40.0)
    truth = np.linspace(-math.pi, math.pi, 400, endpoint=False)
    ellipse = fit_ellipse_direct(project(truth))
    error = np.degrees(angle_difference(dial_angle(ellipse, project(truth)), truth))
    assert 3.0 < np.abs(error - error.mean()).max() < 4.5


def test_dial_homography_is_affine_without_centre() -> None:
    matrix = dial_homography(ELLIPSES[1])
    assert np.allclose(matrix[2], [0.0, 0.0, 1.0])
    assert np.allclose(apply_homography(matrix, np.array([ELLIPSES[1].center])), 0.0)


def test_dial_homography_rejects_centre_outside_the_ellipse() -> None:
    with pytest.raises(ValueError, match="inside"):
        dial_homography(ELLIPSES[1], (320.0 + 151.0, 240.0))


def test_dial_homography_is_remembered_read_only_for_the_same_ellipse_and_centre() -> None:
    # A locked gauge maps through the same frame every frame: computed once, shared, never altered.
    ellipse, centre = ELLIPSES[1], (325.0, 236.0)
    matrix = dial_homography(ellipse, centre)
    assert dial_homography(ellipse, np.array(centre)) is matrix and not matrix.flags.writeable
    assert dial_homography(ELLIPSES[1], (325.0, 236.5)) is not matrix
    with pytest.raises(ValueError, match="inside"):  # a refusal is not remembered as a frame
        dial_homography(ellipse, (320.0 + 151.0, 240.0))
    points = np.array([[330.0, 250.0], [300.0, 200.0], [400.0, 260.0]])
    assert np.allclose(from_unit_circle(ellipse, to_unit_circle(ellipse, points, centre), centre), points)


def test_as_points_rejects_bad_input() -> None:
    with pytest.raises(ValueError, match="shape"):
        as_points(np.zeros((3, 3)))
    with pytest.raises(ValueError, match="non-finite"):
        as_points(np.array([[0.0, np.nan]]))
    assert as_points(np.array([1.0, 2.0])).shape == (1, 2)
