"""Closest point on an ellipse (Eberly's robust method)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gauged.geometry.ellipse_distance import orthogonal_distance, project_to_ellipse
from gauged.types import Ellipse

ELLIPSES = [
    Ellipse(0.0, 0.0, 2.0, 1.0, 0.0),
    Ellipse(320.0, 240.0, 150.0, 100.0, 0.3),
    Ellipse(-5.0, 17.0, 300.0, 30.0, 2.2),
    Ellipse(1.0, 1.0, 50.0, 50.0, 0.0),
]


def _outward_normals(ellipse: Ellipse, t: np.ndarray) -> np.ndarray:
    c, s = math.cos(ellipse.theta), math.sin(ellipse.theta)
    u, v = np.array([c, s]), np.array([-s, c])
    n = (ellipse.b * np.cos(t))[:, None] * u + (ellipse.a * np.sin(t))[:, None] * v
    return n / np.linalg.norm(n, axis=1, keepdims=True)


@pytest.mark.parametrize("ellipse", ELLIPSES)
@pytest.mark.parametrize("offset_fraction", [-0.9, -0.3, 0.0, 0.5, 3.0])
def test_project_to_ellipse_recovers_normal_offsets(ellipse: Ellipse, offset_fraction: float) -> None:
    # Inside, the normal offset is the closest point only within the radius of curvature (>= b^2/a).
    t = np.linspace(-math.pi, math.pi, 73, endpoint=False)
    offset = offset_fraction * ellipse.b**2 / ellipse.a
    points = ellipse.point_at(t) + offset * _outward_normals(ellipse, t)
    proj = project_to_ellipse(ellipse, points)
    assert np.allclose(proj.points, ellipse.point_at(t), atol=1e-9 * ellipse.a)
    assert np.allclose(proj.distance, offset, atol=1e-9 * ellipse.a)
    assert np.allclose(np.cos(proj.t - t), 1.0)


def test_project_to_ellipse_axis_cases() -> None:
    e = Ellipse(0.0, 0.0, 2.0, 1.0, 0.0)
    proj = project_to_ellipse(e, np.array([[0.5, 0.0], [3.0, 0.0], [0.0, 0.2], [0.0, -4.0], [0.0, 0.0]]))
    # On the major axis inside the evolute cusp (x < (a^2-b^2)/a = 1.5): off-axis closest point.
    assert proj.points[0] == pytest.approx([2.0 / 3.0, math.sqrt(1.0 - 1.0 / 9.0)])
    assert proj.points[1] == pytest.approx([2.0, 0.0])
    assert proj.points[2] == pytest.approx([0.0, 1.0])
    assert proj.points[3] == pytest.approx([0.0, -1.0])
    assert proj.distance[1] == pytest.approx(1.0)
    assert proj.distance[3] == pytest.approx(3.0)
    assert proj.distance[4] == pytest.approx(-1.0)  # the centre: nearest is the minor vertex


@settings(max_examples=150, deadline=None)
@given(
    ellipse_index=st.integers(0, len(ELLIPSES) - 1),
    x=st.floats(-3.0, 3.0),
    y=st.floats(-3.0, 3.0),
)
def test_orthogonal_distance_matches_brute_force(ellipse_index: int, x: float, y: float) -> None:
    e = ELLIPSES[ellipse_index]
    point = np.array([[e.cx + x * e.a, e.cy + y * e.a]])
    dense = e.point_at(np.linspace(0.0, 2.0 * math.pi, 200_000, endpoint=False))
    brute = np.min(np.linalg.norm(dense - point, axis=1))
    got = abs(orthogonal_distance(e, point)[0])
    # 1e-8 a: near the centre the projection's root finding settles to ~2e-9 a (hypothesis found
    # x = 1.2e-7, y = 0 off by 3e-7 px on a = 150), far below any pixel but above 1e-9 a.
    tol = 1e-8 * e.a
    assert got <= brute + tol
    # The nearest sample is at most s = half a spacing (arc length) from the true closest point,
    # which lengthens the distance by at most min(s, s^2 (1 + kappa d) / 2d), kappa <= a / b^2.
    s = 0.5 * 2.0 * math.pi * e.a / 200_000
    slack = min(s, s * s * (1.0 + e.a / e.b**2 * got) / (2.0 * max(got, 1e-300)))
    assert got >= brute - slack - tol


@pytest.mark.parametrize("y", [1e-6, 1e-9, 1e-12, 1e-17, 1e-64])
def test_project_to_ellipse_near_major_axis_stays_accurate(y: float) -> None:
    # Found by hypothesis: a point 1e-64 off the major axis used to give an infinite distance.
    e = Ellipse(0.0, 0.0, 2.0, 1.0, 0.0)
    proj = project_to_ellipse(e, np.array([[0.5, y]]))
    assert proj.points[0] == pytest.approx([2.0 / 3.0, math.sqrt(8.0 / 9.0)], abs=1e-6)
    assert proj.distance[0] == pytest.approx(-math.hypot(0.5 - 2.0 / 3.0, math.sqrt(8.0 / 9.0)), abs=1e-6)
