"""The needle: a line through the crop model's needle mask, and the dial angle where it meets the scale.

As in Reitsma et al. (Sec. 3.4), a line is fitted through the segmented needle pixels and intersected
with the scale ellipse on the tip side. The line is a total-least-squares fit weighted by the mask
probability; the pivot (dial centre) decides which end is the tip. Only the mask's connected
component nearest the pivot is used, so a red zone or a second hand elsewhere does not bend the line.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from gauged.geometry.needle_line import fit_needle_line, needle_dial_angle
from gauged.reader.stages.ellipse import ScaleArc
from gauged.types import NeedleLine, StageFailure

STAGE = "needle"
REASONS = ("no_needle", "too_few_pixels", "degenerate_line", "needle_off_centre", "no_intersection",
           "intersection_behind", "two_needles")


@dataclass(frozen=True)
class NeedleReading:
    """The fitted needle (crop pixels), its dial angle on the scale (radians), and fit quality."""

    line: NeedleLine
    angle: float
    mask_score: float  # mean probability of the pixels used, in [0, 1]
    offset: float  # distance of the line from the dial centre, in radii


MIN_PIXELS = 6  # mask cells a needle line needs; a smaller component is a speck, not the needle
RIVAL_SHARE = 0.5  # of the needle's cells: a second component this large may be a needle of its own
RIVAL_DEG = 20.0  # degrees between the two strokes' scale angles that make them two needles


def mask_components(needle_prob: np.ndarray, stride: int, centre: tuple[float, float], threshold: float = 0.5
                    ) -> list[tuple[np.ndarray, np.ndarray]]:
    """The mask's connected components of at least :data:`MIN_PIXELS` cells (all of them, when none is
    that large) as (cell centres (N, 2) in crop pixels, probabilities (N,)), nearest ``centre`` first:
    the first is the needle. The size floor keeps a speck from being taken for it (a one-cell speck of
    the counterweight beside the hub of a real oil gauge was)."""
    mask = (needle_prob >= threshold).astype(np.uint8)
    count, labels = cv2.connectedComponents(mask, connectivity=8)
    if count <= 1:
        return []
    sizes = np.bincount(labels.ravel(), minlength=count)
    large = sizes >= MIN_PIXELS
    large[0] = False  # the background
    kept = np.flatnonzero(large) if large.any() else np.arange(1, count)
    out = []
    for label in kept:
        ys, xs = np.nonzero(labels == label)
        points = np.stack([stride * (xs + 0.5), stride * (ys + 0.5)], axis=1)
        out.append((float(np.hypot(points[:, 0] - centre[0], points[:, 1] - centre[1]).min()), points,
                    needle_prob[ys, xs].astype(np.float64)))
    out.sort(key=lambda item: item[0])
    return [(points, probs) for _, points, probs in out]


def fit_needle(needle_prob: np.ndarray, stride: int, arc: ScaleArc, threshold: float = 0.5,
               max_offset: float = 0.2) -> NeedleReading | StageFailure:
    """Fit the needle line in the (H, W) mask probability map and read its dial angle on ``arc``.

    Failures: ``no_needle`` (no mask pixel above ``threshold``), ``too_few_pixels`` and
    ``degenerate_line`` (from the line fit), ``needle_off_centre`` (the line passes farther than
    ``max_offset`` radii from the dial centre: not a needle turning about the pivot),
    ``no_intersection``/``intersection_behind`` (from the ellipse intersection).
    """
    components = mask_components(needle_prob, stride, arc.centre, threshold)
    if not components:
        return StageFailure(STAGE, "no_needle", f"no needle pixel above {threshold:g}")
    points, probs = components[0]
    line = fit_needle_line(points, arc.centre, weights=probs, min_pixels=MIN_PIXELS)
    if isinstance(line, StageFailure):
        return line
    offset = _offset(line, arc)
    if offset > max_offset:
        return StageFailure(STAGE, "needle_off_centre", f"needle line passes {offset:.2f} radii from the centre")
    angle = needle_dial_angle(arc.ellipse, line, arc.centre)
    if isinstance(angle, StageFailure):
        return angle
    rival = _rival_needle(components[1:], arc, max_offset, len(points), angle)
    if rival is not None:
        return rival
    return NeedleReading(line, angle, float(probs.mean()), float(offset))


def _offset(line: NeedleLine, arc: ScaleArc) -> float:
    """Distance of ``line`` from the dial centre, in radii (the ellipse's minor semi-axis)."""
    direction = np.asarray(line.direction)
    rel = np.asarray(arc.centre) - np.asarray(line.point)
    return float(abs(rel[0] * direction[1] - rel[1] * direction[0]) / arc.ellipse.b)


def _rival_needle(others: list[tuple[np.ndarray, np.ndarray]], arc: ScaleArc, max_offset: float,
                  size: int, angle: float) -> StageFailure | None:
    """A failure when one of the ``others`` mask components (beside the chosen one, of ``size`` cells),
    at least :data:`RIVAL_SHARE` of that size, is a
    needle of its own: its line passes within ``max_offset`` radii of the centre too and points at a
    place of the scale more than :data:`RIVAL_DEG` away (and not the opposite way, where a counterweight
    lies). A cable across the face of a -30..50 degC dial made a component as large as the needle's,
    nearer the hub, and was read 10.1 for -31.3 (a synthetic render); a dial with two
    hands has two needles as well. Which one is the needle the mask cannot tell, so the reader refuses."""
    for points, probs in others:
        if len(points) < max(MIN_PIXELS, RIVAL_SHARE * size):
            continue
        line = fit_needle_line(points, arc.centre, weights=probs, min_pixels=MIN_PIXELS)
        if isinstance(line, StageFailure) or _offset(line, arc) > max_offset:
            continue
        other = needle_dial_angle(arc.ellipse, line, arc.centre)
        if isinstance(other, StageFailure):
            continue
        apart = abs(math.degrees(math.remainder(other - angle, 2 * math.pi)))
        if RIVAL_DEG < apart < 180.0 - RIVAL_DEG:
            return StageFailure(STAGE, "two_needles", f"a second needle-like stroke ({len(points)} cells against "
                                f"{size}) points {apart:.0f} degrees away from the first")
    return None
