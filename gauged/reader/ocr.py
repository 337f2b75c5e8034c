"""OCR of scale numbers and unit on the crop warped so the scale is a circle with its gap at the bottom.

As in Reitsma et al. (Sec. 3.5), the crop is rectified first: the scale ellipse becomes a circle and
the midpoint of the gap between the scale ends is turned to the bottom, so numbers printed upright on
the dial are upright for the recogniser. The engine is RapidOCR (PP-OCRv4 detection + recognition as
ONNX files inside the ``rapidocr-onnxruntime`` wheel: nothing is downloaded). Texts are kept as scale
numbers only where numbers can be — in a ring around the scale circle — and mapped back to crop
pixels; the RANSAC scale fit then keeps those consistent with a linear scale.

Better than the paper's one pass: when the first pass finds fewer than three numbers, the rectified
image is read again rotated by +-90 degrees (radially printed numbers), keeping what parses.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from gauged.geometry.rectify import rectifying_homography, unrectify_points, warp_rectified
from gauged.reader.ellipse import ScaleArc
from gauged.reader.numbers import parse_number, parse_unit
from gauged.types import ScaleMarker, StageFailure

STAGE = "ocr"
REASONS = ("no_text", "no_numbers")
RECTIFIED_SIZE = 320
RING = (0.45, 1.45)  # radii (in scale radii) where scale numbers are accepted


@dataclass(frozen=True)
class TextBox:
    """One recognised text: its quad (4, 2) in the rectified image, text and recogniser score."""

    quad: np.ndarray
    text: str
    score: float

    @property
    def centre(self) -> np.ndarray:
        return self.quad.mean(axis=0)


class ScaleTextReader:
    """RapidOCR, created once; ``read_markers`` is the pipeline's OCR stage."""

    def __init__(self, threads: int = 2, min_score: float = 0.5):
        from rapidocr_onnxruntime import RapidOCR  # imported here: optional for gauges with a known scale

        self.engine = RapidOCR(intra_op_num_threads=threads, inter_op_num_threads=1)
        self.min_score = min_score

    def read_text(self, image: np.ndarray) -> list[TextBox]:
        """Every text RapidOCR finds in (H, W, 3) uint8 ``image``, with its quad in that image."""
        result, _ = self.engine(image, use_cls=False)
        boxes = []
        for quad, text, score in result or []:
            if float(score) >= self.min_score:
                boxes.append(TextBox(np.asarray(quad, float) + 0.5, str(text), float(score)))  # to pixel-centre coords
        return boxes

    def read_markers(self, crop: np.ndarray, arc: ScaleArc, hints: np.ndarray
                     ) -> tuple[list[ScaleMarker], str | None] | StageFailure:
        """Scale numbers (as markers in crop pixels) and the unit of the crop's dial."""
        size = RECTIFIED_SIZE
        radius = 0.36 * size
        matrix = rectifying_homography(arc.ellipse, arc.zero_angle, size, radius=radius)
        rectified = warp_rectified(crop, matrix, size)
        texts = self.read_text(rectified)
        markers, unit = _markers(texts, matrix, size, radius)
        if len(markers) < 3:
            for turn in (cv2.ROTATE_90_CLOCKWISE, cv2.ROTATE_90_COUNTERCLOCKWISE):
                rotated = cv2.rotate(rectified, turn)
                extra = [_unrotate(t, turn, size) for t in self.read_text(rotated)]
                more, more_unit = _markers(extra, matrix, size, radius)
                markers = _merge(markers, more)
                unit = unit or more_unit
        if not texts and not markers:
            return StageFailure(STAGE, "no_text", "no text found on the rectified dial")
        if not markers:
            return StageFailure(STAGE, "no_numbers", f"{len(texts)} text(s) read, none a scale number: "
                                + ", ".join(repr(t.text) for t in texts[:6]))
        return markers, unit


def _unrotate(text: TextBox, turn: int, size: int) -> TextBox:
    """Map a quad read on the rotated image back to the rectified image."""
    x, y = text.quad[:, 0], text.quad[:, 1]
    if turn == cv2.ROTATE_90_CLOCKWISE:  # rotated (u, v) = (size - y, x)  => x = v, y = size - u
        quad = np.stack([y, size - x], axis=1)
    else:  # rotated (u, v) = (y, size - x) => x = size - v, y = u
        quad = np.stack([size - y, x], axis=1)
    return TextBox(quad, text.text, text.score)


def _markers(texts: list[TextBox], matrix: np.ndarray, size: int, radius: float
             ) -> tuple[list[ScaleMarker], str | None]:
    markers, unit = [], None
    centre = np.array([size / 2, size / 2])
    for text in texts:
        candidate_unit = parse_unit(text.text)
        if candidate_unit and unit is None:
            unit = candidate_unit
        value = parse_number(text.text)
        if value is None:
            continue
        r = float(np.linalg.norm(text.centre - centre)) / radius
        if not RING[0] <= r <= RING[1]:
            continue  # accuracy class, serial numbers and the like sit elsewhere on the face
        quad = unrectify_points(matrix, text.quad)
        box = (float(quad[:, 0].min()), float(quad[:, 1].min()), float(quad[:, 0].max()), float(quad[:, 1].max()))
        markers.append(ScaleMarker(text.text, value, box, score=text.score))
    return markers, unit


def _merge(first: list[ScaleMarker], second: list[ScaleMarker]) -> list[ScaleMarker]:
    """Add markers of a second pass unless one of the first lies at (nearly) the same place."""
    def centre(m: ScaleMarker) -> tuple[float, float]:
        return ((m.box[0] + m.box[2]) / 2, (m.box[1] + m.box[3]) / 2)

    merged = list(first)
    for marker in second:
        if all(math.dist(centre(marker), centre(other)) > 6 for other in merged):
            merged.append(marker)
    return merged
