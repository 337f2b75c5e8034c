"""A last look at a dial whose text the OCR could not read: the number net at the crop model's number peaks.

On blurred, dim or noisy dials the PP-OCR text detector finds no box around the scale numbers (or
one box over the whole face), and the ink boxes cut at the crop model's number peaks come apart,
so the OCR stage reads too few numbers. Yet the crop model still knows where the numbers are: on the
held-out renders refused at `ocr/no_text` or `scale/too_few_markers` whose numbers were captured at
5 px or more, 82% of the printed numbers have a number peak on them, and there are about as many
peaks as numbers. What is missing is a box to read.

So this look reads a window at every number peak near the scale ring, with the number net
(:mod:`gauged.reader.ocr.number_net`), for one guess of the numbers' size and orientation at a time:
one dial prints its numbers at one height, either upright or turned radially. Each guess reads a
value or nothing at each peak, and the values must fall on a line against the peaks' dial angles
(:func:`gauged.geometry.scale_fit.fit_angle_value`, the scale stage's own fit), rising either way
round the dial. The guess whose
line holds the most peaks wins; on a tie, the one whose numbers have more characters (a window too
small cuts "200" to "20", a scale ten times too flat, while a window too large adds ticks and
neighbours, which break the line), then the smaller angle residuals.

At least :data:`MIN_NUMBERS` numbers must agree, one more than the first reading needs: a retry is
another chance for misread numbers to make a line. The markers then go through every check of the
scale stage (:func:`gauged.reader.stages.scale.fit_scales`). Nothing here reads the numbers' boxes from
the text detector, so it sees text the detector misses, and it never runs on a dial read before.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from gauged.geometry.angles import unwrap
from gauged.geometry.dial_frame import normalized_radius
from gauged.geometry.scale_fit import AngleValueFit, fit_angle_value
from gauged.reader.ocr.minus_sign import shows_minus
from gauged.reader.ocr.number_net import NumberNet
from gauged.reader.ocr.numbers import parse_number
from gauged.reader.ocr.regions import NUMBER_BAND
from gauged.reader.ocr.text import crop_quad
from gauged.types import ScaleMarker, StageFailure

if TYPE_CHECKING:  # the stages' types, named for the reader only: gauged.reader.ocr imports no stage
    from gauged.reader.stages.crop import Crop
    from gauged.reader.stages.ellipse import ScaleArc
    from gauged.reader.stages.keypoints import Peaks

HEIGHTS = (0.06, 0.075, 0.095, 0.12, 0.15)  # number heights tried, in radii of the scale ellipse
ORIENTATIONS = ("upright", "radial")
WINDOW_HEIGHT = 1.5  # in number heights: the net's lines have a margin above and below
WIDTHS = (3.3,)  # window widths tried, in number heights
MIN_NUMBERS = 4  # agreeing numbers the look needs (the first reading's scale needs 3)
RING_WIDTH = 0.15  # normalised radii: one scale's numbers are printed at one radius
# A number as printed: no stray minus before a lone 0 ("-0": a tick or the needle beside it), no
# decimal point without digits after it ("0.": a speck), no leading zeros.
WELL_FORMED = re.compile(r"0|0[.,]0+|-?[1-9][0-9]*([.,][0-9]+)?|-?0[.,][0-9]*[1-9][0-9]*")


@dataclass(frozen=True)
class _Guess:
    """The numbers read at the peaks under one guess of size and orientation, and their line."""

    markers: list[ScaleMarker]
    characters: int
    rms_angle: float
    quads: list[np.ndarray]  # the markers' windows, frame px

    @property
    def agreeing(self) -> int:
        return len(self.markers)

    def rank(self) -> tuple[int, int, float]:
        return self.agreeing, self.characters, -self.rms_angle


def window_quad(centre: np.ndarray, height: float, width: float, up: np.ndarray) -> np.ndarray:
    """(4, 2) float32 corners, top-left first, of the ``height`` x ``width`` window about ``centre``
    whose top points along ``up`` (image coordinates, y down)."""
    up = np.asarray(up, float) / np.linalg.norm(up)
    right = np.array([-up[1], up[0]])
    h, w = up * height / 2, right * width / 2
    return np.float32([centre - w + h, centre + w + h, centre + w - h, centre - w - h])


def hint_markers(frame: np.ndarray, crop: Crop, arc: ScaleArc, numbers: Peaks, net: NumberNet) -> list[ScaleMarker] | None:
    """The markers (boxes in crop pixels) of the best line of numbers read at the number peaks of
    ``numbers`` (crop pixels) in ``frame``, the image the crop was cut from; None when no guess
    makes :data:`MIN_NUMBERS` of them agree."""
    if not len(numbers):
        return None
    radius = normalized_radius(arc.ellipse, numbers.points)
    near = (radius >= NUMBER_BAND[0]) & (radius <= NUMBER_BAND[1])
    peaks, radius = numbers.points[near], radius[near]
    if len(peaks) < MIN_NUMBERS:
        return None
    angles = np.asarray(unwrap(arc.number_angles(peaks), arc.zero_angle))
    at = crop.points_to_frame(peaks)
    centre = crop.points_to_frame(np.asarray([arc.centre], float))[0]
    scale_radius = math.sqrt(arc.ellipse.a * arc.ellipse.b) * crop.scale
    outward = (at - centre) / np.maximum(np.linalg.norm(at - centre, axis=1, keepdims=True), 1e-9)
    guesses = []  # the windows of every guess, read by the net in one batch
    for orientation in ORIENTATIONS:
        ups = outward if orientation == "radial" else np.tile([0.0, -1.0], (len(at), 1))
        for height in HEIGHTS:
            size = height * scale_radius
            for width in WIDTHS:
                guesses.append([window_quad(p, WINDOW_HEIGHT * size, width * size, up) for p, up in zip(at, ups, strict=True)])
    texts = net.read([crop_quad(frame, q) for quads in guesses for q in quads])
    best: _Guess | None = None
    for k, quads in enumerate(guesses):
        guess = _read_guess(texts[k * len(at): (k + 1) * len(at)], quads, angles, radius, crop)
        if guess is not None and (best is None or guess.rank() > best.rank()):
            best = guess
    if best is None or best.agreeing < MIN_NUMBERS:
        return None
    return [_with_seen_minus(m, frame, quad) for m, quad in zip(best.markers, best.quads, strict=True)]


def _with_seen_minus(marker: ScaleMarker, frame: np.ndarray, quad: np.ndarray) -> ScaleMarker:
    """``marker`` made negative when its window (``quad``, frame px) shows a minus the net did not
    read (:func:`gauged.reader.ocr.minus_sign.shows_minus`): the net reads few signs, and without
    them a -1..0 scale rising counter-clockwise is a 0..1 one rising clockwise."""
    if marker.value <= 0 or marker.text.startswith("-") or not shows_minus(crop_quad(frame, quad)):
        return marker
    return replace(marker, text="-" + marker.text, value=-marker.value)


def _read_guess(texts: list[str], quads: list[np.ndarray], angles: np.ndarray, radii: np.ndarray, crop: Crop
                ) -> _Guess | None:
    """The line through the numbers ``texts`` read at the peaks (dial ``angles``, normalised
    ``radii``), its markers: only well-formed numbers (:data:`WELL_FORMED`) count, and of the
    line's numbers only those printed at one radius (:data:`RING_WIDTH`), one scale's."""
    read = []
    for k, text in enumerate(texts):
        parsed = parse_number(text) if WELL_FORMED.fullmatch(text) else None
        if parsed is not None and not isinstance(parsed, StageFailure):
            read.append((k, text, parsed.value))
    if len(read) < 2:
        return None
    fit = _line(angles[[k for k, _, _ in read]], np.array([v for _, _, v in read]))
    if fit is None:
        return None
    ring = float(np.median([radii[k] for (k, _, _), inlier in zip(read, fit.inliers, strict=True) if inlier]))
    markers, characters, windows = [], 0, []
    for (k, text, value), inlier in zip(read, fit.inliers, strict=True):
        if inlier and abs(radii[k] - ring) <= RING_WIDTH / 2:
            quad = crop.points_to_crop(quads[k])
            (x0, y0), (x1, y1) = quad.min(axis=0), quad.max(axis=0)
            markers.append(ScaleMarker(text, value, (float(x0), float(y0), float(x1), float(y1))))
            windows.append(quads[k])
            characters += len(text)
    return _Guess(markers, characters, fit.rms_angle, windows)


def _line(angles: np.ndarray, values: np.ndarray) -> AngleValueFit | None:
    """The line through the most of the numbers, rising clockwise or counter-clockwise (a tie stays
    clockwise): the net reads no minus signs, so a 0..X scale rising counter-clockwise has its
    numbers falling clockwise, and a clockwise-only line held two or three of its misreads at best
    (the look read 1 of 6 counter-clockwise held-out renders it answered right). The scale stage
    then takes the direction from the signs (:func:`gauged.reader.stages.scale.fit_scales`)."""
    fits = [fit_angle_value(angles, values, min_inliers=2, expected_sign=sign) for sign in (1, -1)]
    fits = [f for f in fits if not isinstance(f, StageFailure)]
    return max(fits, key=lambda f: int(np.sum(f.inliers))) if fits else None
