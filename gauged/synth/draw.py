"""Raster primitives of the renderer, in the project's pixel convention (``gauged.types``).

OpenCV draws in its index convention (pixel centre at integers) with integer vertices; these helpers
take float points in the project convention and pass them to OpenCV with 4 fractional bits, so
shapes land where the ground truth says to within 1/16 px. All drawing is anti-aliased.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from gauged.synth.projection import apply_homography, to_cv

SHIFT = 4
_ONE = 1 << SHIFT


def cv_points(points: np.ndarray) -> np.ndarray:
    """(N, 2) project-convention points as int32 OpenCV vertices with :data:`SHIFT` fractional bits."""
    pts = (np.asarray(points, dtype=float).reshape(-1, 2) - 0.5) * _ONE
    return np.round(pts).astype(np.int32)


def fill_polygon(img: np.ndarray, points: np.ndarray, color: tuple | float) -> None:
    """Fill one polygon (N, 2) in place; ``color`` is BGR or a scalar for single-channel images."""
    cv2.fillPoly(img, [cv_points(points)], color, cv2.LINE_AA, SHIFT)


def fill_polygons(img: np.ndarray, polygons: list[np.ndarray], color: tuple | float) -> None:
    if polygons:
        cv2.fillPoly(img, [cv_points(p) for p in polygons], color, cv2.LINE_AA, SHIFT)


def fill_circle(img: np.ndarray, center: tuple[float, float], radius: float, color: tuple | float) -> None:
    c = cv_points(np.array(center))[0]
    cv2.circle(img, (int(c[0]), int(c[1])), max(1, int(round(radius * _ONE))), color, -1, cv2.LINE_AA, SHIFT)


def stroke_polyline(img: np.ndarray, points: np.ndarray, color: tuple | float, width: float,
                    closed: bool = False) -> None:
    """Anti-aliased polyline; OpenCV thickness is integer, so widths below 1 px draw as 1 px."""
    cv2.polylines(img, [cv_points(points)], closed, color, max(1, int(round(width))), cv2.LINE_AA, SHIFT)


def circle_polygon(center: tuple[float, float], radius: float, n: int = 48) -> np.ndarray:
    """(n, 2) vertices of a regular polygon inscribed in the circle."""
    t = np.linspace(0.0, 2.0 * math.pi, n, endpoint=False)
    return np.column_stack([center[0] + radius * np.cos(t), center[1] + radius * np.sin(t)])


def annular_sector(center: tuple[float, float], r0: float, r1: float, a0: float, a1: float,
                   step: float = 0.02) -> np.ndarray:
    """Polygon of the ring sector ``r0 <= r <= r1``, ``a0 <= angle <= a1`` (radians, a1 > a0)."""
    n = max(2, int(math.ceil((a1 - a0) / step)) + 1)
    t = np.linspace(a0, a1, n)
    outer = np.column_stack([center[0] + r1 * np.cos(t), center[1] + r1 * np.sin(t)])
    inner = np.column_stack([center[0] + r0 * np.cos(t[::-1]), center[1] + r0 * np.sin(t[::-1])])
    return np.vstack([outer, inner])


def blend(img: np.ndarray, alpha: np.ndarray, color: tuple | np.ndarray, x0: int = 0, y0: int = 0) -> None:
    """Blend ``color`` into ``img`` (uint8, H x W x 3) through ``alpha`` (h, w) float32 in [0, 1]
    placed with its top-left pixel at ``(x0, y0)``; parts outside ``img`` are ignored."""
    h, w = alpha.shape
    ih, iw = img.shape[:2]
    ax0, ay0 = max(0, -x0), max(0, -y0)
    bx0, by0 = max(0, x0), max(0, y0)
    bx1, by1 = min(iw, x0 + w), min(ih, y0 + h)
    if bx1 <= bx0 or by1 <= by0:
        return
    a = alpha[ay0:ay0 + by1 - by0, ax0:ax0 + bx1 - bx0][..., None]
    roi = img[by0:by1, bx0:bx1].astype(np.float32)
    col = np.asarray(color, dtype=np.float32).reshape(1, 1, -1)
    # a convex combination of two values in [0, 255] needs no clipping
    img[by0:by1, bx0:bx1] = (roi + (col - roi) * a + 0.5).astype(np.uint8)


def paste_mask(img: np.ndarray, mask: np.ndarray, affine: np.ndarray, color: tuple) -> np.ndarray:
    """Draw a glyph mask (h, w) float32 into ``img`` through ``affine`` (2, 3) mask px -> image px.

    Returns the (4, 2) image-pixel corners of the whole mask (top-left, top-right, bottom-right,
    bottom-left in mask orientation).
    """
    h, w = mask.shape
    m3 = np.vstack([affine, [0.0, 0.0, 1.0]])
    corners = apply_homography(m3, np.array([[0, 0], [w, 0], [w, h], [0, h]], dtype=float))
    x0 = int(math.floor(corners[:, 0].min())) - 1
    y0 = int(math.floor(corners[:, 1].min())) - 1
    x1 = int(math.ceil(corners[:, 0].max())) + 1
    y1 = int(math.ceil(corners[:, 1].max())) + 1
    ih, iw = img.shape[:2]
    cx0, cy0, cx1, cy1 = max(0, x0), max(0, y0), min(iw, x1), min(ih, y1)
    if cx1 > cx0 and cy1 > cy0:
        shift = np.array([[1.0, 0.0, -cx0], [0.0, 1.0, -cy0], [0.0, 0.0, 1.0]])
        m_roi = to_cv(shift @ m3)[:2]
        a = cv2.warpAffine(mask, m_roi, (cx1 - cx0, cy1 - cy0), flags=cv2.INTER_LINEAR, borderValue=0.0)
        blend(img, a, color, cx0, cy0)
    return corners


def value_noise(rng: np.random.Generator, height: int, width: int, cell: float,
                interpolation: int = cv2.INTER_CUBIC) -> np.ndarray:
    """Smooth random field (height, width) float32, roughly in [0, 1], with features ``cell`` px wide.

    Drawn on a coarse grid and resized, so its cost is that of one resize.
    """
    gh = max(2, int(math.ceil(height / cell)) + 1)
    gw = max(2, int(math.ceil(width / cell)) + 1)
    coarse = rng.random((gh, gw), dtype=np.float32)
    return cv2.resize(coarse, (width, height), interpolation=interpolation)


def fractal_noise(rng: np.random.Generator, height: int, width: int, cell: float, octaves: int = 3) -> np.ndarray:
    """Sum of :func:`value_noise` octaves (halving cell and amplitude), normalised to [0, 1].

    Summed at a reduced resolution where the finest octave allows it, then resized once.
    """
    finest = cell / 2 ** (octaves - 1)
    f = max(1.0, finest / 2.0)
    h, w = max(2, int(math.ceil(height / f))), max(2, int(math.ceil(width / f)))
    total = np.zeros((h, w), np.float32)
    amp, norm = 1.0, 0.0
    for _ in range(octaves):
        total += amp * value_noise(rng, h, w, max(1.0, cell / f))
        norm += amp
        amp *= 0.5
        cell *= 0.5
    total /= norm
    if (h, w) != (height, width):
        total = cv2.resize(total, (width, height), interpolation=cv2.INTER_LINEAR)
    lo, hi = float(total.min()), float(total.max())
    return (total - lo) / max(hi - lo, 1e-6)
