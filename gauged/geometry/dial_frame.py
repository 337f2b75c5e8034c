"""The dial frame: the map that turns the scale ellipse into the unit circle, and the angles it defines.

A circular dial seen by a camera images as an ellipse. Given only the ellipse, the best-defined map
back to a circle is the affine

    q = K (p - c),   K = R(theta) diag(1/a, 1/b) R(-theta)

``K`` is symmetric positive definite: it squeezes along the major axis and stretches along the minor
one *without rotating them*, so the dial frame is oriented like the image (x right, y down, clockwise
stays clockwise) and for a near-circular ellipse it is close to a uniform scale about the centre.
Affine is exact under weak perspective. Under real perspective the ellipse centre is not the image
of the dial centre and dial angles bend by up to ~3.7 degrees (radius/distance 0.1, 40 degree tilt;
docs/geometry.md). When the image of the true centre is known (the needle pivot), pass it as
``centre``: its polar line with respect to the ellipse is the image of the dial plane's line at
infinity (pole-polar duality, Hartley & Zisserman, *Multiple View Geometry*, 2nd ed., sec. 2.8.1 and
result 2.20), and :func:`dial_homography` first sends that line to infinity, then applies the affine
map above to the resulting ellipse, which is then exact for any camera.

Angles of a point ``p``; the names say which:

- :func:`dial_angle` -- **the scale angle used everywhere in gauged** (``ScaleMarker.angle``, the
  angles of :class:`gauged.types.ScaleModel`, notch and needle angles): the image-convention angle
  ``atan2`` of ``p`` in the dial frame, i.e. the polar angle on the rectified circle. Without
  ``centre`` it equals ``theta + t`` with ``t`` the parametric angle, is invariant to the
  ``theta``/``theta + pi`` ambiguity, and equals the polar image angle when the ellipse is a circle.
  Every point on a ray from the centre (a scale number inside the ring, the needle tip) gets the
  same angle as the ring point on that ray, which is what a printed scale means.
- :func:`param_angle` -- the parametric angle ``t`` of :meth:`Ellipse.point_at` (measured from the
  major axis): the affine ``dial_angle - theta``.
- :func:`polar_angle` -- the raw image angle ``atan2(p - c)``; it differs from the dial angle on a
  tilted dial, so it must not be mixed with dial angles.

One scale must use one frame: markers, notches and needle of a gauge all with the same ``centre``
(or all without).

Example:
    >>> from gauged.types import Ellipse
    >>> e = Ellipse(100.0, 100.0, 50.0, 25.0, 0.0)
    >>> round(float(dial_angle(e, np.array([[125.0, 125.0]]))[0]), 6)   # 45 deg in the rectified frame
    1.107149
    >>> round(float(polar_angle(e, np.array([[125.0, 125.0]]))[0]), 6)
    0.785398
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from gauged.geometry.angles import wrap_to_pi
from gauged.geometry.conic import conic_to_ellipse, ellipse_matrix
from gauged.types import Ellipse, Point


def as_points(points: np.ndarray, name: str = "points") -> np.ndarray:
    """``points`` as a float64 (N, 2) array; raises ValueError on another shape or non-finite values."""
    array = np.asarray(points, dtype=float)
    if array.ndim == 1 and array.shape == (2,):
        array = array[None, :]
    if array.ndim != 2 or array.shape[1] != 2:
        raise ValueError(f"{name} must have shape (N, 2), got {array.shape}")
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{name} contains non-finite values")
    return array


def apply_homography(matrix: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Map points (N, 2) through a 3x3 homography; returns (N, 2) float64 (inf on the vanishing line)."""
    matrix = np.asarray(matrix, dtype=float)
    if matrix.shape != (3, 3):
        raise ValueError(f"matrix must have shape (3, 3), got {matrix.shape}")
    points = as_points(points)
    homogeneous = np.hstack([points, np.ones((len(points), 1))]) @ matrix.T
    with np.errstate(divide="ignore", invalid="ignore"):
        return homogeneous[:, :2] / homogeneous[:, 2:3]


def rectifying_matrix(ellipse: Ellipse) -> np.ndarray:
    """The 2x2 matrix ``K = R(theta) diag(1/a, 1/b) R(-theta)`` taking ``p - c`` to the unit circle."""
    c, s = math.cos(ellipse.theta), math.sin(ellipse.theta)
    rot = np.array([[c, -s], [s, c]])
    return rot @ np.diag([1.0 / ellipse.a, 1.0 / ellipse.b]) @ rot.T


def _affine_frame(ellipse: Ellipse) -> np.ndarray:
    k = rectifying_matrix(ellipse)
    frame = np.eye(3)
    frame[:2, :2] = k
    frame[:2, 2] = -k @ np.array(ellipse.center)
    return frame


def dial_homography(ellipse: Ellipse, centre: Point | np.ndarray | None = None) -> np.ndarray:
    """3x3 float64 homography from image pixels to the dial frame, where ``ellipse`` is the unit circle.

    Without ``centre``: the affine map ``K (p - c)`` (module docstring). With ``centre`` (2,) px, the
    image of the dial's true centre: the projective map that also undoes perspective. ``centre``
    must lie strictly inside the ellipse (check with :func:`normalized_radius` first); otherwise
    ValueError, since no real camera puts it elsewhere.
    """
    return dial_homographies(ellipse, centre)[0]


def dial_homographies(ellipse: Ellipse, centre: Point | np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(:func:`dial_homography`, its inverse): image pixels -> dial frame and back, read-only arrays
    remembered per ellipse and centre."""
    return _homographies(ellipse, _centre_key(centre))


def _centre_key(centre: Point | np.ndarray | None) -> tuple[float, float] | None:
    return None if centre is None else tuple(float(v) for v in np.asarray(centre, dtype=float).reshape(2))


@lru_cache(maxsize=256)
def _homographies(ellipse: Ellipse, centre: tuple[float, float] | None) -> tuple[np.ndarray, np.ndarray]:
    """:func:`dial_homography` and its inverse, read-only, remembered: a locked gauge's ellipse and
    centre are the same frame after frame, and the needle scan, the value and the overlay each map
    through them (the homography was 6% of the daemon's camera threads under the load test)."""
    matrix = _dial_homography(ellipse, centre)
    inverse = np.linalg.inv(matrix)
    matrix.setflags(write=False)
    inverse.setflags(write=False)
    return matrix, inverse


def _dial_homography(ellipse: Ellipse, centre: tuple[float, float] | None) -> np.ndarray:
    if centre is None:
        return _affine_frame(ellipse)
    centre = np.asarray(centre, dtype=float).reshape(2)
    if not np.all(np.isfinite(centre)) or normalized_radius(ellipse, centre[None, :])[0] >= 1.0:
        raise ValueError(f"centre {centre.tolist()} must lie inside the ellipse")
    # Work in coordinates where the ellipse is roughly unit-sized around the origin (conditioning).
    to_norm = np.diag([1.0 / ellipse.a, 1.0 / ellipse.a, 1.0])
    to_norm[:2, 2] = -np.array(ellipse.center) / ellipse.a
    norm_inv = np.linalg.inv(to_norm)
    conic = norm_inv.T @ ellipse_matrix(ellipse) @ norm_inv
    pole = to_norm @ np.array([centre[0], centre[1], 1.0])
    horizon = conic @ pole  # the polar of the centre: image of the line at infinity
    # The origin is inside the ellipse, so the horizon (outside it) does not pass through it: l3 != 0.
    horizon = horizon / horizon[2]
    to_affine = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [horizon[0], horizon[1], 1.0]])
    to_affine_inv = np.linalg.inv(to_affine)
    affine_conic = conic_to_ellipse(_conic_vector(to_affine_inv.T @ conic @ to_affine_inv))
    if not affine_conic:  # cannot happen for a centre inside the ellipse, up to rounding
        raise ValueError(f"centre {centre.tolist()} gives no dial frame: {affine_conic.detail}")
    return _affine_frame(affine_conic) @ to_affine @ to_norm


def _conic_vector(matrix: np.ndarray) -> np.ndarray:
    return np.array([matrix[0, 0], 2 * matrix[0, 1], matrix[1, 1], 2 * matrix[0, 2], 2 * matrix[1, 2], matrix[2, 2]])


def to_unit_circle(ellipse: Ellipse, points: np.ndarray, centre: Point | np.ndarray | None = None) -> np.ndarray:
    """Points (N, 2) px -> dial-frame coordinates (N, 2) in which ``ellipse`` is the unit circle."""
    return apply_homography(dial_homography(ellipse, centre), points)


def from_unit_circle(
    ellipse: Ellipse, rectified: np.ndarray, centre: Point | np.ndarray | None = None
) -> np.ndarray:
    """Inverse of :func:`to_unit_circle`: dial-frame coordinates (N, 2) -> pixels (N, 2)."""
    return apply_homography(dial_homographies(ellipse, centre)[1], as_points(rectified, "rectified"))


def dial_angle(ellipse: Ellipse, points: np.ndarray, centre: Point | np.ndarray | None = None) -> np.ndarray:
    """Dial angles (N,) radians in ``(-pi, pi]`` of points (N, 2) px: polar angle in the dial frame.

    This is the angle the scale is calibrated in (see the module docstring). Undefined (returns 0)
    at the centre itself.
    """
    q = to_unit_circle(ellipse, points, centre)
    return np.asarray(wrap_to_pi(np.arctan2(q[:, 1], q[:, 0])))  # wrap: atan2(-0.0, -1) is -pi


def dial_direction_angle(
    ellipse: Ellipse, direction: Point | np.ndarray, centre: Point | np.ndarray | None = None
) -> float:
    """Dial angle (radians) of the ray leaving the dial centre along image ``direction`` (2,), e.g. a needle.

    The ray starts at ``centre`` (or the ellipse centre without it). Homographies send lines to
    lines, so every point of the ray inside the ellipse has the same dial angle; a point a thousandth
    of the minor axis out is used.
    """
    direction = np.asarray(direction, dtype=float).reshape(2)
    norm = float(np.linalg.norm(direction))
    if norm == 0.0:
        raise ValueError("direction must be non-zero")
    origin = np.array(ellipse.center) if centre is None else np.asarray(centre, dtype=float).reshape(2)
    probe = origin + direction * (1e-3 * ellipse.b / norm)
    return float(dial_angle(ellipse, probe[None, :], centre)[0])


def param_angle(ellipse: Ellipse, points: np.ndarray) -> np.ndarray:
    """Parametric angles ``t`` (N,) in ``(-pi, pi]`` with ``ellipse.point_at(t)`` on the ray to each point."""
    return np.asarray(wrap_to_pi(dial_angle(ellipse, points) - ellipse.theta))


def polar_angle(ellipse: Ellipse, points: np.ndarray) -> np.ndarray:
    """Raw image angles (N,) ``atan2(y - cy, x - cx)`` about the ellipse centre (not the dial angle)."""
    points = as_points(points)
    return np.asarray(wrap_to_pi(np.arctan2(points[:, 1] - ellipse.cy, points[:, 0] - ellipse.cx)))


def point_at_dial_angle(
    ellipse: Ellipse, angle: np.ndarray | float, centre: Point | np.ndarray | None = None
) -> np.ndarray:
    """Points (N, 2) px on the ellipse at dial angles ``angle`` (N,) radians (inverse of :func:`dial_angle`)."""
    angle = np.atleast_1d(np.asarray(angle, dtype=float))
    return from_unit_circle(ellipse, np.stack([np.cos(angle), np.sin(angle)], axis=1), centre)


def normalized_radius(ellipse: Ellipse, points: np.ndarray) -> np.ndarray:
    """Radius (N,) in the affine dial frame: < 1 inside the ellipse, 1 on it, > 1 outside."""
    return np.linalg.norm(apply_homography(_affine_frame(ellipse), points), axis=1)
