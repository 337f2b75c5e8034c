"""Camera geometry of the renderer: dial poses, homographies and exact images of circles.

A dial is modelled in its own *face units*: the dial plane is ``z = 0``, the pivot is the origin,
``x`` runs right and ``y`` down (as on a frontal photo), ``z`` points away from the viewer (into the
wall), and the face radius is 1. A :class:`Pose` places that plane in front of a pinhole camera;
:func:`pose_homography` is the 3x3 map from face units to frame pixels (the project's convention,
``gauged.types``), and :func:`project_circle` gives the exact ellipse that a circle of the dial
becomes in the frame (the image of its conic, not the projection of its centre).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gauged.types import Box, Ellipse


@dataclass(frozen=True, slots=True)
class Pose:
    """Where a dial sits in front of the camera.

    ``center`` is the frame pixel where the pivot appears; ``diameter_px`` the face diameter in
    frame pixels for a frontal view; ``tilt`` (radians, 0 = frontal, up to ~1.05 = 60 degrees) turns
    the dial plane about the in-plane axis at angle ``tilt_axis``; ``roll`` (radians) turns the dial
    in its own plane (positive = clockwise on screen); ``focal_px`` is the focal length, so
    ``diameter_px / focal_px`` sets how strong the perspective is.
    """

    center: tuple[float, float]
    diameter_px: float
    tilt: float = 0.0
    tilt_axis: float = 0.0
    roll: float = 0.0
    focal_px: float = 2000.0

    @property
    def distance(self) -> float:
        """Depth of the pivot in face units (face radius 1)."""
        return 2.0 * self.focal_px / self.diameter_px


def _rot_z(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _rot_x(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def pose_rotation(pose: Pose) -> np.ndarray:
    """Rotation (3, 3) from face units to camera axes: roll in the plane, then tilt about the axis."""
    tilt = _rot_z(pose.tilt_axis) @ _rot_x(pose.tilt) @ _rot_z(-pose.tilt_axis)
    return tilt @ _rot_z(pose.roll)


def _intrinsics(pose: Pose) -> np.ndarray:
    # The principal point sits on the pivot's image: a gauge off the optical axis is then modelled by
    # its tilt, which is the part of the geometry that matters to a reader.
    cx, cy = pose.center
    return np.array([[pose.focal_px, 0.0, cx], [0.0, pose.focal_px, cy], [0.0, 0.0, 1.0]])


def pose_homography(pose: Pose) -> np.ndarray:
    """The (3, 3) homography from face units (plane z = 0) to frame pixels."""
    r = pose_rotation(pose)
    t = np.array([0.0, 0.0, pose.distance])
    h = _intrinsics(pose) @ np.column_stack([r[:, 0], r[:, 1], t])
    return h / h[2, 2]


def project_points3d(pose: Pose, points: np.ndarray) -> np.ndarray:
    """Project (N, 3) face-unit points (z away from the viewer) to (N, 2) frame pixels."""
    p = np.asarray(points, dtype=float) @ pose_rotation(pose).T + np.array([0.0, 0.0, pose.distance])
    uvw = p @ _intrinsics(pose).T
    return uvw[:, :2] / uvw[:, 2:3]


def apply_homography(h: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Map (N, 2) points through the (3, 3) homography ``h``; returns (N, 2) float64."""
    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    uvw = pts @ h[:, :2].T + h[:, 2]
    return uvw[:, :2] / uvw[:, 2:3]


def scaling(sx: float, sy: float | None = None) -> np.ndarray:
    """Homography scaling about the origin (corner of the top-left pixel)."""
    return np.diag([sx, sx if sy is None else sy, 1.0])


def translation(tx: float, ty: float) -> np.ndarray:
    return np.array([[1.0, 0.0, tx], [0.0, 1.0, ty], [0.0, 0.0, 1.0]])


def to_cv(h: np.ndarray) -> np.ndarray:
    """Convert a homography between project-convention pixels into OpenCV's index convention.

    OpenCV puts the centre of pixel ``(i, j)`` at ``(i, j)``; the project puts it at ``(i + 0.5,
    j + 0.5)``. ``cv2.warpPerspective`` with the returned matrix then matches ``h`` exactly.
    """
    return translation(-0.5, -0.5) @ h @ translation(0.5, 0.5)


def circle_conic(cx: float, cy: float, r: float) -> np.ndarray:
    """Symmetric (3, 3) conic matrix of the circle: ``[x y 1] C [x y 1]^T = 0``."""
    return np.array([[1.0, 0.0, -cx], [0.0, 1.0, -cy], [-cx, -cy, cx * cx + cy * cy - r * r]])


def conic_to_ellipse(c: np.ndarray) -> Ellipse:
    """The :class:`~gauged.types.Ellipse` of a real ellipse's (3, 3) conic matrix.

    Raises ``ValueError`` when the conic is not a real ellipse (a caller's mistake here: a circle
    of a dial in front of the camera always projects to one).
    """
    c = 0.5 * (c + c.T)
    m, d = c[:2, :2], c[:2, 2]
    centre = -np.linalg.solve(m, d)
    value = float(centre @ m @ centre + 2.0 * d @ centre + c[2, 2])
    lam, vec = np.linalg.eigh(m)  # ascending: the smaller eigenvalue is the major axis
    if lam[0] * lam[1] <= 0 or value * lam[0] >= 0:
        raise ValueError("conic is not a real ellipse")
    a = math.sqrt(-value / lam[0])
    b = math.sqrt(-value / lam[1])
    theta = math.atan2(vec[1, 0], vec[0, 0]) % math.pi
    return Ellipse(float(centre[0]), float(centre[1]), a, b, theta)


def project_circle(h: np.ndarray, cx: float, cy: float, r: float) -> Ellipse:
    """The exact image under homography ``h`` of the circle ``(cx, cy, r)``."""
    hinv = np.linalg.inv(h)
    return conic_to_ellipse(hinv.T @ circle_conic(cx, cy, r) @ hinv)


def points_box(points: np.ndarray) -> Box:
    """Axis-aligned box ``(x0, y0, x1, y1)`` of (N, 2) points."""
    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    x0, y0 = pts.min(axis=0)
    x1, y1 = pts.max(axis=0)
    return (float(x0), float(y0), float(x1), float(y1))


def ellipse_box(e: Ellipse) -> Box:
    """Tight axis-aligned box of an ellipse."""
    c, s = math.cos(e.theta), math.sin(e.theta)
    hx = math.hypot(e.a * c, e.b * s)
    hy = math.hypot(e.a * s, e.b * c)
    return (e.cx - hx, e.cy - hy, e.cx + hx, e.cy + hy)


def local_scale(h: np.ndarray, point: tuple[float, float] = (0.0, 0.0)) -> float:
    """Largest stretch (output px per input unit) of ``h`` near ``point``: the Jacobian's norm."""
    x, y = point
    w = h[2, 0] * x + h[2, 1] * y + h[2, 2]
    u = (h[0, 0] * x + h[0, 1] * y + h[0, 2]) / w
    v = (h[1, 0] * x + h[1, 1] * y + h[1, 2]) / w
    jac = np.array([[h[0, 0] - u * h[2, 0], h[0, 1] - u * h[2, 1]],
                    [h[1, 0] - v * h[2, 0], h[1, 1] - v * h[2, 1]]]) / w
    return float(np.linalg.norm(jac, 2))
