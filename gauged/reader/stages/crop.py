"""Cut a square, resized crop of one gauge out of a frame, keeping the map back to the frame."""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from gauged.types import Box, StageFailure

STAGE = "crop"
REASONS = ("gauge_too_small",)
MIN_GAUGE_PX = 24  # below this a dial has too few pixels for notches and needle


@dataclass(frozen=True)
class Crop:
    """A (size, size, 3) uint8 BGR crop and the 3x3 affine map from crop pixels to frame pixels."""

    image: np.ndarray
    to_frame: np.ndarray  # (3, 3): frame_xy1 = to_frame @ crop_xy1
    box: Box  # the square region of the frame, before clipping to the frame

    @property
    def scale(self) -> float:
        """Frame pixels per crop pixel."""
        return float(self.to_frame[0, 0])

    def points_to_frame(self, points: np.ndarray) -> np.ndarray:
        pts = np.asarray(points, float).reshape(-1, 2)
        return pts * self.to_frame[0, 0] + self.to_frame[:2, 2]

    def points_to_crop(self, points: np.ndarray) -> np.ndarray:
        """Inverse of :meth:`points_to_frame`: frame pixels (N, 2) -> crop pixels."""
        return (np.asarray(points, float).reshape(-1, 2) - self.to_frame[:2, 2]) / self.to_frame[0, 0]


def square_box(box: Box, pad: float) -> Box:
    """The square of side ``max(w, h) * (1 + 2 pad)`` centred on ``box``."""
    x0, y0, x1, y1 = box
    half = max(x1 - x0, y1 - y0) * (0.5 + pad)
    cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
    return (cx - half, cy - half, cx + half, cy + half)


def crop_gauge(image: np.ndarray, box: Box, size: int, pad: float = 0.08) -> Crop | StageFailure:
    """Crop the padded square around ``box`` from (H, W, 3) ``image`` and resize it to ``size`` px.

    Parts of the square outside the frame are filled by edge replication (a dial cut by the frame
    edge is still read where its scale is visible). The map to the frame is exact in the project's
    pixel convention: crop point ``p`` lies at ``box0 + p * side / size`` in the frame.
    """
    x0, y0, x1, y1 = box
    if not (x1 > x0 and y1 > y0):
        raise ValueError(f"box must have x1 > x0 and y1 > y0, got {box}")
    if min(x1 - x0, y1 - y0) < MIN_GAUGE_PX:
        return StageFailure(STAGE, "gauge_too_small", f"gauge box is {x1 - x0:.0f}x{y1 - y0:.0f} px, need {MIN_GAUGE_PX}")
    sx0, sy0, sx1, sy1 = square_box(box, pad)
    scale = (sx1 - sx0) / size
    # Affine crop -> frame in pixel-edge coordinates; warpAffine works on pixel centres, so shift by 0.5.
    to_frame = np.array([[scale, 0.0, sx0], [0.0, scale, sy0], [0.0, 0.0, 1.0]])
    centre_map = np.array([[scale, 0.0, sx0 + 0.5 * scale - 0.5], [0.0, scale, sy0 + 0.5 * scale - 0.5]])
    interpolation = cv2.INTER_AREA if scale > 1.5 else cv2.INTER_LINEAR
    if interpolation == cv2.INTER_AREA:
        # INTER_AREA only works through resize: cut the integer region first, then resize.
        ix0, iy0 = int(np.floor(sx0)), int(np.floor(sy0))
        side = int(np.ceil(sx1)) - ix0
        region = _padded_region(image, ix0, iy0, side)
        crop = cv2.resize(region, (size, size), interpolation=cv2.INTER_AREA)
        scale = side / size
        to_frame = np.array([[scale, 0.0, ix0], [0.0, scale, iy0], [0.0, 0.0, 1.0]])
        return Crop(crop, to_frame, (ix0, iy0, ix0 + side, iy0 + side))
    crop = cv2.warpAffine(image, centre_map, (size, size), flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                          borderMode=cv2.BORDER_REPLICATE)
    return Crop(crop, to_frame, (sx0, sy0, sx1, sy1))


def _padded_region(image: np.ndarray, x0: int, y0: int, side: int) -> np.ndarray:
    height, width = image.shape[:2]
    top, left = max(0, -y0), max(0, -x0)
    bottom, right = max(0, y0 + side - height), max(0, x0 + side - width)
    region = image[max(0, y0):min(height, y0 + side), max(0, x0):min(width, x0 + side)]
    if top or left or bottom or right:
        region = cv2.copyMakeBorder(region, top, bottom, left, right, cv2.BORDER_REPLICATE)
    return region
