"""The rectified views of a dial the OCR reads: the scale ellipse made a circle, turned gap-down or the
image's way up."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from gauged.geometry.angles import wrap_to_pi
from gauged.geometry.dial_frame import dial_angle
from gauged.geometry.rectify import (
    rectifying_homography,
    warp_rectified,
)
from gauged.reader.ocr.dial_text import (
    Circle,
    _progression_size,
)
from gauged.reader.ocr.text import TextBox

if TYPE_CHECKING:  # gauged.reader.ocr imports no stage
    from gauged.reader.stages.ellipse import ScaleArc

RECTIFIED_SIZE = 512  # px; larger (the crop's own scale) or a larger detector input measured no better
RECTIFIED_RADIUS = 0.34  # of RECTIFIED_SIZE: leaves room for numbers printed outside the scale
UPRIGHT_TURN = math.radians(120.0)  # a dial is read the image's way up too when that turns its gap-down view by
# more than this: text upright on the face of a dial whose gap is not at the bottom (12% of the engine's dials)
# then stands nearly on its head, beyond the +-90 degree re-reads, and upside-down digits still parse.
# 30 degrees: p75 read 395 ms, not 277


@dataclass(frozen=True)
class _View:
    """The texts read on one rectified view of a dial: ``matrix`` maps crop px to the view, whose
    scale circle is ``circle`` and whose scale gap lies at image angle ``gap``."""

    texts: list[TextBox]
    matrix: np.ndarray
    circle: Circle
    gap: float
    image: np.ndarray  # the rectified view itself

    def agreeing(self) -> int:
        """How many of the numbers read form the best arithmetic progression."""
        return _progression_size(self.texts, self.circle, self.gap)


def _view_downs(arc: ScaleArc) -> list[float]:
    """The dial angles put at the bottom of the rectified views: the scale's gap, and the image's
    down when that turns the view by more than :data:`UPRIGHT_TURN`."""
    upright = _image_down(arc)
    return [arc.zero_angle] + ([upright] if abs(wrap_to_pi(upright - arc.zero_angle)) > UPRIGHT_TURN else [])


def _rectified(crop: np.ndarray, arc: ScaleArc, detail: np.ndarray | None, down: float
               ) -> tuple[np.ndarray, np.ndarray, Circle]:
    """The dial rectified with dial angle ``down`` at the bottom: the view, the homography crop px ->
    view px, and the scale circle in the view. Sampled from ``detail`` (the crop's square at a higher
    resolution) when given."""
    size = RECTIFIED_SIZE
    radius = RECTIFIED_RADIUS * size
    matrix = rectifying_homography(arc.ellipse, down, size, radius=radius, centre=arc.centre)
    if detail is None:
        rectified = warp_rectified(crop, matrix, size)
    else:  # detail px -> crop px is a pure scaling of the same square
        to_crop = np.diag([crop.shape[1] / detail.shape[1], crop.shape[0] / detail.shape[0], 1.0])
        rectified = warp_rectified(detail, matrix @ to_crop, size)
    return rectified, matrix, (size / 2.0, size / 2.0, radius)


def _image_down(arc: ScaleArc) -> float:
    """The dial angle that points down the image from the dial centre: a view with it at the bottom
    shows text printed upright on an upright dial upright, wherever the scale's gap is."""
    cx, cy = arc.centre
    return float(dial_angle(arc.ellipse, np.array([[cx, cy + arc.ellipse.b]]), arc.centre)[0])
