"""Exact images of circles under homographies, and pose homographies against 3-D projection."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from gauged.synth.projection import (Pose, apply_homography, conic_to_ellipse, ellipse_box, pose_homography,
                                     project_circle, project_points3d, circle_conic)

angles = st.floats(-math.pi, math.pi)


@settings(max_examples=60, deadline=None)
@given(tilt=st.floats(0, 1.05), axis=angles, roll=angles, diameter=st.floats(40, 1000),
       perspective=st.floats(0.05, 0.9), radius=st.floats(0.3, 1.2))
def test_project_circle_passes_through_projected_points(tilt, axis, roll, diameter, perspective, radius):
    pose = Pose((640.0, 360.0), diameter, tilt, axis, roll, diameter / perspective)
    h = pose_homography(pose)
    e = project_circle(h, 0.0, 0.0, radius)
    t = np.linspace(0, 2 * math.pi, 37)
    pts = apply_homography(h, radius * np.column_stack([np.cos(t), np.sin(t)]))
    c, s = math.cos(e.theta), math.sin(e.theta)
    u = ((pts[:, 0] - e.cx) * c + (pts[:, 1] - e.cy) * s) / e.a
    v = (-(pts[:, 0] - e.cx) * s + (pts[:, 1] - e.cy) * c) / e.b
    assert np.allclose(u * u + v * v, 1.0, atol=1e-6)
    assert e.a >= e.b > 0 and 0 <= e.theta < math.pi
    x0, y0, x1, y1 = ellipse_box(e)
    assert pts[:, 0].min() >= x0 - 1e-6 and pts[:, 0].max() <= x1 + 1e-6
    assert pts[:, 1].min() >= y0 - 1e-6 and pts[:, 1].max() <= y1 + 1e-6


@settings(max_examples=40, deadline=None)
@given(tilt=st.floats(0, 1.05), axis=angles, roll=angles)
def test_pose_homography_matches_3d_projection_of_the_plane(tilt, axis, roll):
    pose = Pose((100.0, 80.0), 300.0, tilt, axis, roll, 900.0)
    pts = np.random.default_rng(0).uniform(-1, 1, (20, 2))
    via_h = apply_homography(pose_homography(pose), pts)
    via_3d = project_points3d(pose, np.column_stack([pts, np.zeros(len(pts))]))
    assert np.allclose(via_h, via_3d, atol=1e-9)


def test_frontal_pose_keeps_circle_round_and_centred():
    e = project_circle(pose_homography(Pose((50.0, 60.0), 200.0)), 0.0, 0.0, 1.0)
    assert math.isclose(e.cx, 50.0) and math.isclose(e.cy, 60.0)
    assert math.isclose(e.a, 100.0, rel_tol=1e-9) and math.isclose(e.b, 100.0, rel_tol=1e-9)


def test_tilted_circle_centre_is_not_the_projected_pivot():
    pose = Pose((0.0, 0.0), 400.0, math.radians(50), 0.0, 0.0, 500.0)
    e = project_circle(pose_homography(pose), 0.0, 0.0, 1.0)
    assert abs(e.cy) > 1.0  # perspective moves the ellipse centre off the pivot's image


def test_conic_to_ellipse_rejects_non_ellipses():
    hyperbola = np.array([[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]])
    try:
        conic_to_ellipse(hyperbola)
    except ValueError:
        pass
    else:
        raise AssertionError("a hyperbola was accepted")
    assert conic_to_ellipse(circle_conic(1.0, 2.0, 3.0)).a == 3.0
