"""Rectifying homography: ellipse -> centred circle with the gap at the bottom, and cv2 warping."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gauged.geometry.angles import angle_difference, wrap_angle
from gauged.geometry.dial_frame import dial_angle, point_at_dial_angle
from gauged.geometry.ellipse_fit import fit_ellipse_direct
from gauged.geometry.rectify import (
    apply_homography,
    cv2_matrix,
    rectified_angle,
    rectifying_homography,
    unrectify_points,
    warp_rectified,
)
from gauged.types import Ellipse

ELLIPSES = [
    Ellipse(320.0, 240.0, 150.0, 150.0, 0.0),
    Ellipse(300.5, 200.25, 120.0, 80.0, 0.2),
    Ellipse(100.0, 400.0, 90.0, 30.0, 2.5),
]
NOTCHES = [(math.radians(135.0), math.radians(45.0)), (math.radians(-170.0), math.radians(100.0)), (0.3, -0.2)]


@pytest.mark.parametrize("ellipse", ELLIPSES)
@pytest.mark.parametrize(("start", "end"), NOTCHES)
def test_rectifying_homography_sends_ellipse_to_upright_circle(ellipse: Ellipse, start: float, end: float) -> None:
    size, radius = 256, 100.0
    zero = wrap_angle(start, end)
    h = rectifying_homography(ellipse, zero, size, radius)
    assert np.allclose(h[2], [0.0, 0.0, 1.0])  # affine without a centre
    ring = apply_homography(h, ellipse.point_at(np.linspace(0.0, 6.0, 40)))
    assert np.allclose(np.hypot(ring[:, 0] - 128.0, ring[:, 1] - 128.0), radius)
    gap, notches = point_at_dial_angle(ellipse, [zero]), point_at_dial_angle(ellipse, [start, end])
    assert apply_homography(h, gap)[0] == pytest.approx([128.0, 128.0 + radius])  # gap straight down
    start_r, end_r = apply_homography(h, notches)
    assert start_r[0] == pytest.approx(256.0 - end_r[0])  # notches mirror about the vertical axis
    assert start_r[1] == pytest.approx(end_r[1])
    assert start_r[0] < 128.0 < end_r[0] or abs(start_r[0] - 128.0) < 1e-9


@pytest.mark.parametrize("ellipse", ELLIPSES)
def test_rectified_angle_is_the_polar_angle_in_the_rectified_view(ellipse: Ellipse) -> None:
    zero, size = 1.3, 200
    h = rectifying_homography(ellipse, zero, size)
    points = np.random.default_rng(2).normal(ellipse.center, 0.5 * ellipse.b, (30, 2))
    mapped = apply_homography(h, points)
    polar = np.arctan2(mapped[:, 1] - size / 2.0, mapped[:, 0] - size / 2.0)
    assert np.allclose(angle_difference(polar, rectified_angle(dial_angle(ellipse, points), zero)), 0.0)


@pytest.mark.parametrize("ellipse", ELLIPSES)
def test_unrectify_points_inverts_the_homography(ellipse: Ellipse) -> None:
    h = rectifying_homography(ellipse, 0.7, 300, 110.0, centre=np.array(ellipse.center) + 2.0)
    points = np.random.default_rng(3).uniform(0.0, 300.0, (25, 2))
    assert np.allclose(unrectify_points(h, apply_homography(h, points)), points)


def test_rectifying_homography_with_centre_undoes_perspective(tilted_dial) -> None:
    project = tilted_dial(12.0, 100.0, 45.0)
    truth = np.linspace(-math.pi, math.pi, 90, endpoint=False)
    ellipse = fit_ellipse_direct(project(truth))
    h = rectifying_homography(ellipse, math.pi / 2.0, 400, 150.0, centre=project(None)[0])
    # The dial's numbers at 70% of the radius land on a concentric circle, evenly spaced in angle.
    inner = apply_homography(h, tilted_dial(0.7 * 12.0, 100.0, 45.0)(truth))
    assert np.allclose(np.hypot(inner[:, 0] - 200.0, inner[:, 1] - 200.0), 0.7 * 150.0)
    angles = np.arctan2(inner[:, 1] - 200.0, inner[:, 0] - 200.0)
    assert np.allclose(angle_difference(angles, truth), angle_difference(angles, truth)[0], atol=1e-9)


def _ellipse_mask(ellipse: Ellipse, shape: tuple[int, int], supersample: int = 4) -> np.ndarray:
    """uint8 image, 255 * coverage of each pixel by the ellipse (gauged pixel-centre convention)."""
    h, w = shape
    offsets = (np.arange(supersample) + 0.5) / supersample
    ys = (np.arange(h)[:, None] + offsets[None, :]).reshape(-1)
    xs = (np.arange(w)[:, None] + offsets[None, :]).reshape(-1)
    gx, gy = np.meshgrid(xs, ys)
    c, s = math.cos(ellipse.theta), math.sin(ellipse.theta)
    u = (gx - ellipse.cx) * c + (gy - ellipse.cy) * s
    v = -(gx - ellipse.cx) * s + (gy - ellipse.cy) * c
    inside = (u / ellipse.a) ** 2 + (v / ellipse.b) ** 2 <= 1.0
    coverage = inside.reshape(h, supersample, w, supersample).mean(axis=(1, 3))
    return np.round(255.0 * coverage).astype(np.uint8)


def _centroid(image: np.ndarray) -> np.ndarray:
    weights = image.astype(float)
    ys, xs = np.indices(image.shape)
    return np.array([(weights * (xs + 0.5)).sum(), (weights * (ys + 0.5)).sum()]) / weights.sum()


@pytest.mark.parametrize("ellipse", [Ellipse(60.3, 50.7, 40.0, 25.0, 0.6), Ellipse(45.0, 40.0, 20.0, 20.0, 0.0)])
def test_warp_rectified_centres_the_dial_to_a_tenth_of_a_pixel(ellipse: Ellipse) -> None:
    # Upscaling by 2-4x makes a half-pixel convention slip show as a 0.5-1.5 px offset.
    image = _ellipse_mask(ellipse, (100, 120))
    size, radius = 200, 80.0
    warped = warp_rectified(image, rectifying_homography(ellipse, 0.0, size, radius), size)
    assert warped.shape == (size, size)
    assert _centroid(warped) == pytest.approx([100.0, 100.0], abs=0.1)
    assert warped.astype(float).sum() / 255.0 == pytest.approx(math.pi * radius**2, rel=0.01)


def test_cv2_matrix_shifts_by_half_a_pixel() -> None:
    scale = np.diag([2.0, 2.0, 1.0])
    assert np.allclose(cv2_matrix(scale), [[2.0, 0.0, 0.5], [0.0, 2.0, 0.5], [0.0, 0.0, 1.0]])


def test_rectifying_homography_rejects_bad_size() -> None:
    with pytest.raises(ValueError, match="size"):
        rectifying_homography(ELLIPSES[0], 0.0, 0)
