"""Dial geometry: ellipse fitting, the dial frame and its angles, needle lines, rectification, scale fits.

Pure functions over numpy arrays in the coordinate convention of :mod:`gauged.types`. The angle a
scale is calibrated in is the *dial angle* (:func:`dial_angle`); see :mod:`gauged.geometry.dial_frame`
and docs/geometry.md.
"""

from __future__ import annotations

from gauged.geometry.angles import angle_difference, scale_span, unwrap, wrap_angle, wrap_to_pi
from gauged.geometry.conic import conic_to_ellipse, ellipse_matrix, ellipse_to_conic, normalized_ellipse
from gauged.geometry.dial_frame import (
    apply_homography,
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
from gauged.geometry.ellipse_distance import EllipseProjection, orthogonal_distance, project_to_ellipse
from gauged.geometry.ellipse_fit import fit_circle, fit_ellipse, fit_ellipse_direct, select_circle_or_ellipse
from gauged.geometry.ellipse_refine import refine_ellipse, rms_orthogonal_distance
from gauged.geometry.needle_line import fit_needle_line, intersect_line_ellipse, needle_dial_angle
from gauged.geometry.rectify import (
    cv2_matrix,
    rectified_angle,
    rectifying_homography,
    unrectify_points,
    warp_rectified,
)
from gauged.geometry.scale_fit import (
    AngleValueFit,
    fit_angle_value,
    fit_scale_model,
    marker_centres,
    number_rings,
)

__all__ = [
    "AngleValueFit",
    "EllipseProjection",
    "angle_difference",
    "apply_homography",
    "conic_to_ellipse",
    "cv2_matrix",
    "dial_angle",
    "dial_direction_angle",
    "dial_homography",
    "ellipse_matrix",
    "ellipse_to_conic",
    "fit_angle_value",
    "fit_circle",
    "fit_ellipse",
    "fit_ellipse_direct",
    "fit_needle_line",
    "fit_scale_model",
    "from_unit_circle",
    "intersect_line_ellipse",
    "marker_centres",
    "needle_dial_angle",
    "normalized_ellipse",
    "normalized_radius",
    "number_rings",
    "orthogonal_distance",
    "param_angle",
    "point_at_dial_angle",
    "polar_angle",
    "project_to_ellipse",
    "rectified_angle",
    "rectifying_homography",
    "refine_ellipse",
    "rms_orthogonal_distance",
    "scale_span",
    "select_circle_or_ellipse",
    "to_unit_circle",
    "unrectify_points",
    "warp_rectified",
    "unwrap",
    "wrap_angle",
    "wrap_to_pi",
]
