"""Where to look for scale text besides the detector's boxes: the unwrapped ring, the ink at a point.

:func:`polar_strip` unwraps the ring of a rectified dial into a strip whose columns run clockwise
round the dial and whose rows run inward, so radially printed numbers (tops outward) stand upright.
:func:`ink_box` finds the printed characters at a predicted number centre by Otsu thresholding, for
print too faint or small for the text detector.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import NamedTuple

import cv2
import numpy as np

from gauged.types import Box

RING = (0.35, 1.45)  # radii (in scale radii) where scale numbers are looked for
TURNED_GAP = 0.5  # of a glyph's height: a glyph of its size this near, not level with it, is its turned neighbour
TURNED_SIZE = (0.6, 1.6)  # the neighbour's height, in the glyph's heights

NUMBER_BAND = (0.55, 1.45)  # normalised radii where scale numbers sit


class Ink(NamedTuple):
    """The printed characters at a point: their ``box`` (x0, y0, x1, y1) px, and whether they are a
    single glyph with a glyph of its size beside it, not level with it: one character of a number
    printed turned (the "4" of a "40" at 60 degrees), which reads as a number of its own."""

    box: Box
    turned_part: bool


def ink_box(window: np.ndarray, point: tuple[float, float], r: float) -> Ink | None:
    """The printed characters at ``point`` (their box in ``window`` px), or None.

    Otsu splits the (H, W, 3) window into ink and face (ink is the smaller class); the ink blob
    nearest ``point`` (within 0.1 ``r``) is grown by blobs level with it and at most 0.8 of its height
    away (the other characters, a decimal point or a minus sign), and padded by a quarter height.
    (A turned rectangle around the blobs' pixels, for radially printed numbers, read 7 fewer of the
    295 rendered numbers: turned text is left to the re-reads and the polar fallback.)
    """
    gray = cv2.GaussianBlur(cv2.cvtColor(window, cv2.COLOR_BGR2GRAY), (3, 3), 0)
    _, mask = cv2.threshold(gray, 0, 255, cv2.THRESH_BINARY + cv2.THRESH_OTSU)
    if np.count_nonzero(mask) > mask.size / 2:
        mask = 255 - mask
    n, _, stats, _ = cv2.connectedComponentsWithStats(mask, connectivity=8)
    # characters, and the small marks beside them (a decimal point, a minus sign)
    blobs = [tuple(map(float, stats[i, :4])) for i in range(1, n)
             if 0.015 * r <= max(stats[i, 2], stats[i, 3]) and stats[i, 3] <= 0.35 * r and stats[i, 2] <= 0.5 * r]
    digits = [b for b in blobs if b[3] >= 0.03 * r]
    if not digits:
        return None

    def gap(b: tuple[float, float, float, float]) -> float:
        dx = max(b[0] - point[0], 0.0, point[0] - b[0] - b[2])
        dy = max(b[1] - point[1], 0.0, point[1] - b[1] - b[3])
        return math.hypot(dx, dy)

    seed = min(digits, key=gap)
    if gap(seed) > 0.1 * r:
        return None
    x0, y0, x1, y1 = seed[0], seed[1], seed[0] + seed[2], seed[1] + seed[3]
    grown = True
    while grown:
        grown = False
        h = y1 - y0
        for bx, by, bw, bh in blobs:
            if bx >= x0 and by >= y0 and bx + bw <= x1 and by + bh <= y1:
                continue
            level = by >= y0 - 0.3 * h and by + bh <= y1 + 0.3 * h and bh <= 1.4 * h
            near = max(bx - x1, x0 - bx - bw) <= 0.8 * h
            if level and near:
                x0, y0, x1, y1 = min(x0, bx), min(y0, by), max(x1, bx + bw), max(y1, by + bh)
                grown = True
    pad = 0.25 * (y1 - y0)
    lone = (x0, y0, x1, y1) == (seed[0], seed[1], seed[0] + seed[2], seed[1] + seed[3])
    return Ink((x0 - pad, y0 - pad, x1 + pad, y1 + pad), lone and _turned_neighbour(digits, seed))


def _turned_neighbour(digits: list[tuple[float, float, float, float]], glyph: tuple[float, float, float, float]) -> bool:
    """Whether a glyph of ``glyph``'s size lies within :data:`TURNED_GAP` of its height in any
    direction (blobs as (x, y, w, h); a level neighbour would have been grown into it)."""
    gx, gy, gw, gh = glyph
    for bx, by, bw, bh in digits:
        if (bx, by, bw, bh) == glyph or not TURNED_SIZE[0] * gh <= bh <= TURNED_SIZE[1] * gh:
            continue
        dx = max(bx - gx - gw, 0.0, gx - bx - bw)
        dy = max(by - gy - gh, 0.0, gy - by - bh)
        if math.hypot(dx, dy) <= TURNED_GAP * gh:
            return True
    return False


def polar_strip(image_bgr: np.ndarray, circle: tuple[float, float, float], gap_angle: float = math.pi / 2,
                ring: tuple[float, float] = RING) -> tuple[np.ndarray, Callable[[np.ndarray], np.ndarray]]:
    """The ``ring`` (radii, in units of ``circle``'s r) of ``circle = (cx, cy, r)`` px unwrapped.

    Returns ``(strip, to_image)``: ``strip`` is (H, W, 3) uint8 with ``W = 2 pi 0.8 r`` (text near
    the scale keeps its size) and ``H = (ring[1] - ring[0]) r``; ``to_image`` maps (N, 2) strip px to
    image px. Column ``x`` is the image angle ``gap_angle + 2 pi x / W`` (clockwise from the gap, so
    no scale number is cut at the seam), row ``y`` the radius ``ring[1] r`` down to ``ring[0] r``.
    """
    cx, cy, r = circle
    w = max(32, int(2 * math.pi * 0.8 * r))
    h = max(16, int((ring[1] - ring[0]) * r))

    def polar(x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        theta = gap_angle + 2 * math.pi * x / w
        rho = (ring[1] - (ring[1] - ring[0]) * y / h) * r
        return cx + rho * np.cos(theta), cy + rho * np.sin(theta)

    xs, ys = np.meshgrid(np.arange(w, dtype=np.float64) + 0.5, np.arange(h, dtype=np.float64) + 0.5)
    mx, my = polar(xs, ys)
    strip = cv2.remap(image_bgr, (mx - 0.5).astype(np.float32), (my - 0.5).astype(np.float32),
                      cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)

    def to_image(points: np.ndarray) -> np.ndarray:
        px, py = polar(np.asarray(points, float)[:, 0], np.asarray(points, float)[:, 1])
        return np.stack([px, py], axis=1).astype(np.float32)

    return strip, to_image
