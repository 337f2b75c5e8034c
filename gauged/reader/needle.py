"""The needle: a line through the crop model's needle mask, and the dial angle where it meets the scale.

As in Reitsma et al. (Sec. 3.4), a line is fitted through the segmented needle pixels and intersected
with the scale ellipse on the tip side. The line is a total-least-squares fit weighted by the mask
probability; the pivot (dial centre) decides which end is the tip. Only the mask's connected
component nearest the pivot is used, so a red zone or a second hand elsewhere does not bend the line.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from gauged.geometry.needle_line import fit_needle_line, needle_dial_angle
from gauged.reader.ellipse import ScaleArc
from gauged.types import NeedleLine, StageFailure

STAGE = "needle"
REASONS = ("no_needle", "too_few_pixels", "degenerate_line", "needle_off_centre", "no_intersection",
           "intersection_behind")


@dataclass(frozen=True)
class NeedleReading:
    """The fitted needle (crop pixels), its dial angle on the scale (radians), and fit quality."""

    line: NeedleLine
    angle: float
    mask_score: float  # mean probability of the pixels used, in [0, 1]
    offset: float  # distance of the line from the dial centre, in radii


MIN_PIXELS = 6  # mask cells a needle line needs; a smaller component is a speck, not the needle


def needle_pixels(needle_prob: np.ndarray, stride: int, centre: tuple[float, float], threshold: float = 0.5
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Cell centres (N, 2) in crop pixels and probabilities (N,) of the mask component nearest ``centre``
    among those of at least :data:`MIN_PIXELS` cells (any, when none is that large): a one-cell speck
    of the counterweight beside the hub of a real oil gauge was taken for its needle."""
    mask = (needle_prob >= threshold).astype(np.uint8)
    count, labels = cv2.connectedComponents(mask, connectivity=8)
    if count <= 1:
        return np.zeros((0, 2)), np.zeros(0)
    sizes = np.bincount(labels.ravel(), minlength=count)
    large = sizes >= MIN_PIXELS
    large[0] = False  # the background
    ys, xs = np.nonzero(np.isin(labels, np.flatnonzero(large)) if large.any() else labels)
    points = np.stack([stride * (xs + 0.5), stride * (ys + 0.5)], axis=1)
    distances = np.hypot(points[:, 0] - centre[0], points[:, 1] - centre[1])
    label = labels[ys[np.argmin(distances)], xs[np.argmin(distances)]]
    chosen = labels[ys, xs] == label
    return points[chosen], needle_prob[ys[chosen], xs[chosen]].astype(np.float64)


def fit_needle(needle_prob: np.ndarray, stride: int, arc: ScaleArc, threshold: float = 0.5,
               max_offset: float = 0.2) -> NeedleReading | StageFailure:
    """Fit the needle line in the (H, W) mask probability map and read its dial angle on ``arc``.

    Failures: ``no_needle`` (no mask pixel above ``threshold``), ``too_few_pixels`` and
    ``degenerate_line`` (from the line fit), ``needle_off_centre`` (the line passes farther than
    ``max_offset`` radii from the dial centre: not a needle turning about the pivot),
    ``no_intersection``/``intersection_behind`` (from the ellipse intersection).
    """
    points, probs = needle_pixels(needle_prob, stride, arc.centre, threshold)
    if len(points) == 0:
        return StageFailure(STAGE, "no_needle", f"no needle pixel above {threshold:g}")
    line = fit_needle_line(points, arc.centre, weights=probs, min_pixels=MIN_PIXELS)
    if isinstance(line, StageFailure):
        return line
    direction = np.asarray(line.direction)
    rel = np.asarray(arc.centre) - np.asarray(line.point)
    offset = abs(rel[0] * direction[1] - rel[1] * direction[0]) / arc.ellipse.b
    if offset > max_offset:
        return StageFailure(STAGE, "needle_off_centre", f"needle line passes {offset:.2f} radii from the centre")
    angle = needle_dial_angle(arc.ellipse, line, arc.centre)
    if isinstance(angle, StageFailure):
        return angle
    return NeedleReading(line, angle, float(probs.mean()), float(offset))
