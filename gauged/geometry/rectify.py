"""Warping the dial to a frontal, upright view: the ellipse becomes a centred circle, the gap goes down.

:func:`rectifying_homography` builds the 3x3 matrix (in gauged pixel coordinates, see
:mod:`gauged.types`)

    H = T(size/2, size/2) . radius R(pi/2 - zero) . G

with ``G`` the image-to-dial-frame map of :func:`gauged.geometry.dial_frame.dial_homography`. It
sends the ellipse exactly onto the circle of ``radius`` px centred in a ``size`` x ``size`` square,
and a dial angle ``phi`` to the rectified image angle ``phi + pi/2 - zero``, so the gap midpoint
(``zero``, :func:`gauged.geometry.angles.wrap_angle`) points straight down and the scale reads
clockwise from lower left over the top to lower right, the way an upright gauge does.

Without the dial centre ``G`` is **affine** (last row ``0 0 1``): exact for the ellipse itself and
for the whole dial under weak perspective, but under real perspective the printed scale comes out
slightly bent (up to ~3.7 degrees at radius/distance 0.1 and a 40 degree tilt, docs/geometry.md).
With the image of the dial centre (the needle pivot) ``G`` is projective and exact.

OpenCV samples at integer pixel centres while gauged puts pixel ``(i, j)``'s centre at
``(i + 0.5, j + 0.5)``; :func:`cv2_matrix` converts, and :func:`warp_rectified` uses it.

Example:
    >>> from gauged.types import Ellipse, Point
    >>> h = rectifying_homography(Ellipse(300.0, 200.0, 120.0, 80.0, 0.2), zero=0.0, size=256, radius=100.0)
    >>> apply_homography(h, np.array([[300.0, 200.0]])).round(6).tolist()   # centre -> middle of the square
    [[128.0, 128.0]]
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from gauged.geometry.angles import wrap_to_pi
from gauged.geometry.dial_frame import apply_homography, dial_homography
from gauged.types import Ellipse, Point

DEFAULT_RADIUS_FRACTION = 0.4  # leaves a margin for numbers printed outside the scale ring


def _translation(dx: float, dy: float) -> np.ndarray:
    return np.array([[1.0, 0.0, dx], [0.0, 1.0, dy], [0.0, 0.0, 1.0]])


def rectifying_homography(
    ellipse: Ellipse,
    zero: float,
    size: int,
    radius: float | None = None,
    centre: Point | np.ndarray | None = None,
) -> np.ndarray:
    """3x3 float64 homography: ``ellipse`` -> circle of ``radius`` px centred in a ``size`` square.

    ``zero`` (radians, a dial angle) is sent straight down (+y). ``radius`` defaults to
    ``0.4 * size``. ``centre`` (2,) px, the image of the dial's true centre (the needle pivot), makes
    the map projective and exact under perspective (:func:`gauged.geometry.dial_frame.dial_homography`);
    without it the map is affine. The matrix maps gauged pixel coordinates to gauged pixel
    coordinates; :func:`cv2_matrix` converts it for ``cv2.warpPerspective``.
    """
    if size <= 0:
        raise ValueError(f"size must be positive, got {size}")
    radius = DEFAULT_RADIUS_FRACTION * size if radius is None else float(radius)
    turn = 0.5 * math.pi - zero
    c, s = math.cos(turn), math.sin(turn)
    place = np.eye(3)
    place[:2, :2] = radius * np.array([[c, -s], [s, c]])
    return _translation(0.5 * size, 0.5 * size) @ place @ dial_homography(ellipse, centre)


def rectified_angle(dial_angle: np.ndarray | float, zero: float) -> np.ndarray | float:
    """Image angle in the rectified view (radians) of a dial angle, for :func:`rectifying_homography`."""
    return wrap_to_pi(np.asarray(dial_angle, dtype=float) + 0.5 * math.pi - zero)


def unrectify_points(matrix: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Map points (N, 2) from the rectified view back to the source image (the inverse homography)."""
    return apply_homography(np.linalg.inv(np.asarray(matrix, dtype=float)), points)


def cv2_matrix(matrix: np.ndarray) -> np.ndarray:
    """The same homography in OpenCV's pixel convention (integer pixel centres): ``T(-.5) H T(.5)``."""
    return _translation(-0.5, -0.5) @ np.asarray(matrix, dtype=float) @ _translation(0.5, 0.5)


def warp_rectified(
    image: np.ndarray, matrix: np.ndarray, size: int, *, interpolation: int = cv2.INTER_LINEAR
) -> np.ndarray:
    """Warp ``image`` (H, W[, C]) uint8 into the ``size`` x ``size`` rectified view of ``matrix``."""
    return cv2.warpPerspective(
        image, cv2_matrix(matrix), (int(size), int(size)), flags=interpolation, borderMode=cv2.BORDER_CONSTANT
    )
