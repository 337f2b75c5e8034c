"""Construct crop-model outputs (keypoint peaks and needle mask) for a dial at a known truth.

The reader's stages after the crop model work on these maps; drawing them from a known ellipse,
scale and needle angle lets the stages be tested without a trained model.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from gauged.geometry.dial_frame import point_at_dial_angle
from gauged.reader.stages.keypoints import (
    CROP_CHANNELS,
    CropKeypoints,
    Peaks,
    find_peaks,
)
from gauged.training.targets import gaussian_heatmap
from gauged.types import Ellipse

CROP = 256
STRIDE = 2


@dataclass(frozen=True)
class Dial:
    ellipse: Ellipse = Ellipse(128.0, 128.0, 100.0, 100.0, 0.0)
    start_deg: float = 135.0  # dial angle of the start notch (image convention, clockwise positive)
    span_deg: float = 270.0
    majors: int = 11
    needle_deg: float = 300.0  # dial angle of the needle

    @property
    def start(self) -> float:
        return math.radians(self.start_deg)

    @property
    def end(self) -> float:
        return math.radians(self.start_deg + self.span_deg)

    def notch_angles(self) -> np.ndarray:
        return np.radians(self.start_deg + np.linspace(0, self.span_deg, self.majors))

    def notch_points(self) -> np.ndarray:
        return point_at_dial_angle(self.ellipse, self.notch_angles())


def needle_prob(dial: Dial, width_px: float = 4.0, length: float = 0.85, tail: float = 0.15) -> np.ndarray:
    """(H, W) mask probability at stride 2 of a straight needle from the centre at ``dial.needle_deg``."""
    tip = point_at_dial_angle(dial.ellipse.scaled(length), math.radians(dial.needle_deg))[0]
    back = point_at_dial_angle(dial.ellipse.scaled(tail), math.radians(dial.needle_deg + 180))[0]
    mask = np.zeros((CROP, CROP), np.uint8)
    cv2.line(mask, tuple(np.round((back - 0.5) * 16).astype(int)), tuple(np.round((tip - 0.5) * 16).astype(int)),
             1, max(1, int(width_px)), cv2.LINE_AA, shift=4)
    return cv2.resize(mask.astype(np.float32), (CROP // STRIDE, CROP // STRIDE), interpolation=cv2.INTER_AREA).clip(0, 1)


def keypoints_for(dial: Dial, *, start: bool = True, end: bool = True, majors: np.ndarray | None = None,
                  pivot: bool = True, needle: np.ndarray | None = None) -> CropKeypoints:
    """Keypoints as the crop model would give them for ``dial`` (peaks extracted from drawn maps)."""
    shape = (CROP // STRIDE, CROP // STRIDE)

    def peaks(points: np.ndarray) -> Peaks:
        return find_peaks(gaussian_heatmap(points, shape, STRIDE, 1.5), STRIDE, 0.3, 64, 1)

    notches = dial.notch_points() if majors is None else majors
    empty = Peaks(np.zeros((0, 2)), np.zeros(0))
    centre = np.array([dial.ellipse.center])
    return CropKeypoints(
        start=peaks(dial.notch_points()[:1]) if start else empty,
        end=peaks(dial.notch_points()[-1:]) if end else empty,
        major=peaks(notches),
        tip=empty,
        pivot=peaks(centre) if pivot else empty,
        numbers=empty,
        needle_prob=needle_prob(dial) if needle is None else needle,
        stride=STRIDE,
    )


assert CROP_CHANNELS[-1] == "needle"
