"""The needle of a locked dial without the crop model: a radial scan of the rectified dial.

Once a gauge's scale is locked (:mod:`gauged.tracking.scale_lock`) its ellipse, pivot and ends are
known and only the needle moves. How the needle looks (darker or brighter than the face, the colour
channel that shows it best, its width, the circles on which it shows against a plain face) is learnt
from a crop the crop model read (:func:`learn_needle_look`). :func:`scan_needle` then samples the crop
on rays from the pivot over the scale arc in the dial frame (:func:`gauged.geometry.dial_frame.dial_homography`:
the ellipse is the unit circle there, the pivot its centre), keeps what stands out from the face along
each circle (a white top-hat, Serra, *Image Analysis and Mathematical Morphology*, 1982, ch. XII),
scores each ray by the median over the circles, and fits the needle line through each circle's
centroid of the stroke by total least squares on the largest consistent set (every pair of circles
tried, a deterministic RANSAC: Fischler & Bolles, CACM 24(6), 1981).

Two corrections turn the line into an angle. A fixed camera shakes: the dial moves a pixel or so
against the locked arc from frame to frame, which moves where the needle crosses the locked ring but
not the needle's direction. So the angle is the line's direction plus the offset of the true pivot
from the locked one (:func:`pivot_offset`, a least-squares fit over the last scans, in which the shake
averages out). And the locked scale was fitted on the crop model's notches, on which the model errs
by a degree or so as it does on the needle: the angle is moved into the model's frame by the offsets
of the crop model's reads near it (:func:`anchor_offset`).

A scan that cannot tell fails, and the caller reads the frame with the crop model: ``no_clear_peak``
(no ray stands out as the learnt needle did), ``two_peaks`` (a second stroke nearly as strong: a
shadow, a cable, a reflection), ``unsupported_jump`` (far from the last angle and weaker than the
learnt needle), ``needle_off_centre`` (the line misses the pivot), ``pivot_moved`` (it passes far
from where the scans before it turned: the dial may have moved, which the crop model's pivot
checks), ``no_anchor`` (no crop-model read near this angle yet). Learning fails with
``faint_needle``, ``short_needle`` (too few plain circles) or ``scan_disagrees`` (a scan of the crop
learnt from does not find the crop model's needle).

Example:
    >>> look = learn_needle_look(crop.image, arc, read.needle)  # doctest: +SKIP
    >>> scanned = scan_needle(next_crop.image, arc, look)       # doctest: +SKIP
    >>> look = follow_needle(look, scanned)                     # doctest: +SKIP
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from functools import lru_cache

import cv2
import numpy as np

from gauged.geometry.angles import wrap_to_pi
from gauged.geometry.dial_frame import apply_homography, dial_homographies
from gauged.geometry.needle_line import fit_needle_line
from gauged.reader.stages.ellipse import ScaleArc
from gauged.reader.stages.needle import NeedleReading
from gauged.types import Ellipse, NeedleLine, StageFailure

STAGE = "needle_scan"
REASONS = ("no_clear_peak", "two_peaks", "unsupported_jump", "needle_off_centre", "pivot_moved", "no_anchor",
           "faint_needle", "short_needle", "scan_disagrees")

STEP = math.radians(0.5)  # between rays
MARGIN = 0.06  # of the scale span, scanned past each end (read_value refuses a needle 4% past one)
CHANNELS = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0), (0.114, 0.587, 0.299))  # BGR weights: B, G, R, grey
LEARN_RADII = np.round(np.arange(0.1, 0.951, 0.025), 3)  # circles the needle's look is learnt on
LEARN_HALF = math.radians(30.0)  # rays either side of the needle seen when learning ...
FACE_FROM = math.radians(15.0)  # ... of which those this far from it show the face
INNER_MIN, OUTER_MAX = 0.3, 0.9  # radii: inside lie the hub and the tail, outside the ticks
TIP_MARGIN = 0.05  # radii kept off the needle's tapering tip
MIN_CONTRAST = 20.0  # grey levels between needle and face; a fainter needle is left to the crop model
CLUTTER_SHARE = 0.35  # of the needle's top-hat: a circle whose other rays reach it at their 90th percentile
MIN_ROWS, MIN_BAND = 6, 0.2  # plain circles a scan needs, and radii between its innermost and outermost
CLEAR_SHARE = 0.5  # of the learnt needle's score: the least a scanned needle shows
RIVAL_SHARE = 0.6  # of the best ray's score: a second stroke this strong makes the scan ambiguous
JUMP, SUPPORT_SHARE = math.radians(30.0), 0.8  # a needle this far from the last angle must show this share
ROW_SHARE = 0.5  # of the best ray's score: a circle crossing the needle more faintly is not fitted
CORE_SHARE = 0.7  # of a circle's maximum: the part of the stroke whose centroid is the needle's (no shadow)
INLIER_SHARE, INLIER_MIN = 0.1, 0.004  # of the width, and radii: a centroid farther off the line is not the needle's
MAX_OFFSET = 0.2  # radii, as the needle stage allows
AGREE = math.radians(2.0)  # how far a learning scan may read from the crop model's angle
ANCHORS, ANCHOR_NEAR = 16, math.radians(20.0)  # crop-model reads kept, and how near an angle one aligns it
LINES = 16  # scans the pivot's offset is fitted on
PIVOT_PRIOR = 0.01  # ridge weight pulling that offset towards the locked pivot (one scan weighs 1)
MOVED = 0.06  # radii: a needle this far from where the scans before it turned (a shake is 0.01-0.02) moved


@dataclass(frozen=True)
class NeedleLook:
    """How the needle of one locked dial looks, and what the scans of it have learnt since.

    ``channel`` indexes :data:`CHANNELS`; ``polarity`` is +1 for a needle darker than the face, -1 for
    a brighter one; ``width`` (ring radii) its width; ``radii`` the circles it is scanned on;
    ``strength`` the score of its ray when learnt; ``mask_score`` the crop model's needle score then
    (a scanned needle's confidence); ``angle`` the dial angle (radians) last read; ``lines`` the last
    scans' (direction, signed offset) (:func:`pivot_offset`); ``anchors`` the last crop-model reads'
    (angle, model angle less scanned crossing) (:func:`anchor_offset`).
    """

    channel: int
    polarity: float
    width: float
    radii: tuple[float, ...]
    strength: float
    mask_score: float
    angle: float | None = None
    lines: tuple[tuple[float, float], ...] = ()
    anchors: tuple[tuple[float, float], ...] = ()

    @property
    def kernel(self) -> int:
        """Top-hat length in rays: twice the needle's angular width on the innermost circle, odd."""
        return 2 * int(self.width / self.radii[0] / STEP) + 5


@dataclass(frozen=True)
class ScannedNeedle(NeedleReading):
    """A scanned needle: the needle stage's reading, and its line in the dial frame (radians, radii)."""

    direction: float = 0.0  # dial angle the line points at, from the pivot side
    signed_offset: float = 0.0  # of the line from the locked pivot: direction x (a point on the line)
    crossing: float = 0.0  # dial angle where the line meets the ring (the crop model's reading of it)


def scan_needle(crop: np.ndarray, arc: ScaleArc, look: NeedleLook) -> ScannedNeedle | StageFailure:
    """The needle of (S, S, 3) uint8 BGR ``crop`` on the locked ``arc`` (crop pixels), found by its look.

    Its ``angle`` is the line's direction corrected by :func:`pivot_offset` and :func:`anchor_offset`;
    ``line`` is in crop pixels, ``offset`` in radii, ``mask_score`` the look's. A failure (module
    docstring) means the caller reads the crop with the crop model instead.
    """
    needle = _scan_line(crop, arc, look)
    if isinstance(needle, StageFailure):
        return needle
    normal = np.array([-math.sin(needle.direction), math.cos(needle.direction)])
    if look.lines and abs(needle.signed_offset - pivot_offset(look.lines) @ normal) > MOVED:
        return StageFailure(STAGE, "pivot_moved", f"the needle passes {abs(needle.signed_offset):.3f} radii from the "
                            f"locked pivot, the scans before it {abs(pivot_offset(look.lines) @ normal):.3f}")
    pivot = pivot_offset((*look.lines, (needle.direction, needle.signed_offset)))
    angle = needle.direction + math.asin(float(np.clip(pivot @ normal, -MAX_OFFSET, MAX_OFFSET)))
    offset = anchor_offset(look.anchors, angle)
    if offset is None:
        return StageFailure(STAGE, "no_anchor", f"no crop-model read within {math.degrees(ANCHOR_NEAR):.0f} degrees "
                            "of the scanned needle to align it with")
    return replace(needle, angle=float(wrap_to_pi(angle + offset)))


def follow_needle(look: NeedleLook, needle: ScannedNeedle) -> NeedleLook:
    """``look`` after a scan read ``needle``: its angle and line kept for the next scan."""
    return replace(look, angle=needle.angle, lines=(*look.lines, (needle.direction, needle.signed_offset))[-LINES:])


def pivot_offset(lines: tuple[tuple[float, float], ...]) -> np.ndarray:
    """(2,) dial-frame offset ``e`` of the true pivot from the locked one, from scanned lines
    (direction ``t``, signed offset ``d``): ridge least squares of ``d = e . (-sin t, cos t)``.

    Each frame's shake adds its own shift to ``d``; over several frames it averages out, and what stays
    is where the needle really turns. With the needle still, only the component across it is known,
    which is the one its angle needs.
    """
    normals = np.array([(-math.sin(t), math.cos(t)) for t, _ in lines]).reshape(-1, 2)
    offsets = np.array([d for _, d in lines])
    return np.linalg.solve(normals.T @ normals + PIVOT_PRIOR * np.eye(2), normals.T @ offsets)


def anchor_offset(anchors: tuple[tuple[float, float], ...], angle: float) -> float | None:
    """Radians to add to a scanned ``angle``: the median offset of the ``anchors`` within
    :data:`ANCHOR_NEAR` of it, or None when none is. An anchor's offset is the crop model's angle less
    the scanned crossing on the same crop, so the shake of that frame, which both see, cancels."""
    near = [offset for at, offset in anchors if abs(wrap_to_pi(at - angle)) <= ANCHOR_NEAR]
    return float(np.median(near)) if near else None


@lru_cache(maxsize=64)
def _ray_maps(ellipse: Ellipse, centre: tuple[float, float], first: float, count: int,
              radii: tuple[float, ...]) -> tuple[np.ndarray, np.ndarray]:
    """cv2.remap maps (len(radii), count) float32 of the rays ``first + STEP * k`` at ``radii``."""
    phis = first + STEP * np.arange(count)
    rhos = np.asarray(radii)[:, None]
    dial = np.stack([rhos * np.cos(phis), rhos * np.sin(phis)], axis=-1).reshape(-1, 2)
    pixels = apply_homography(dial_homographies(ellipse, centre)[1], dial).reshape(len(radii), count, 2) - 0.5  # cv2 centres
    return pixels[..., 0].astype(np.float32), pixels[..., 1].astype(np.float32)


def _polar(crop: np.ndarray, arc: ScaleArc, first: float, count: int, radii) -> np.ndarray:
    """(len(radii), count, 3) float32: the crop on rays from ``first`` radians, ``STEP`` apart."""
    maps = _ray_maps(arc.ellipse, tuple(map(float, arc.centre)), float(first), int(count), tuple(map(float, radii)))
    return cv2.remap(crop, *maps, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE).astype(np.float32)


def _scan(crop: np.ndarray, arc: ScaleArc, look: NeedleLook) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Ray angles (K,) over the scale arc and :data:`MARGIN` past its ends, top-hat (R, K) on the
    look's circles with the needle bright, and ray scores (K,)."""
    if crop.ndim != 3 or crop.shape[2] != 3:
        raise ValueError(f"crop must be (S, S, 3), got {crop.shape}")
    margin = min(MARGIN * arc.span, 0.5 * (2 * math.pi - arc.span))
    first, count = arc.start_angle - margin, int((arc.span + 2 * margin) / STEP) + 1
    grey = _polar(crop, arc, first, count, look.radii) @ np.asarray(CHANNELS[look.channel], np.float32)
    bright = np.ascontiguousarray(255.0 - grey if look.polarity > 0 else grey)
    tophat = cv2.morphologyEx(bright, cv2.MORPH_TOPHAT, np.ones((1, look.kernel), np.uint8))
    # a ray a sample or two beside the needle on some circles (an off-centre line) still counts it there
    scores = np.median(cv2.dilate(tophat, np.ones((1, 5), np.uint8)), axis=0)
    return first + STEP * np.arange(count), tophat, scores


def _scan_line(crop: np.ndarray, arc: ScaleArc, look: NeedleLook) -> ScannedNeedle | StageFailure:
    """The scanned needle line, its angle where it meets the locked ring (before the corrections)."""
    phis, tophat, scores = _scan(crop, arc, look)
    best = int(np.argmax(scores))
    peak = float(scores[best])
    if peak < CLEAR_SHARE * look.strength:
        return StageFailure(STAGE, "no_clear_peak", f"best ray scores {peak:.0f}, the needle learnt "
                            f"{look.strength:.0f}")
    apart = np.abs(wrap_to_pi(phis - phis[best]))
    others = apart > look.kernel // 2 * STEP
    if others.any() and scores[others].max() >= RIVAL_SHARE * peak:
        rival = math.degrees(apart[others][np.argmax(scores[others])])
        return StageFailure(STAGE, "two_peaks", f"a second ray {rival:.0f} degrees away scores "
                            f"{scores[others].max() / peak:.0%} of the best")
    jump = 0.0 if look.angle is None else abs(wrap_to_pi(phis[best] - look.angle))
    if jump > JUMP and peak < SUPPORT_SHARE * look.strength:
        return StageFailure(STAGE, "unsupported_jump", f"needle {math.degrees(jump):.0f} degrees from the last angle, "
                            f"scoring {peak / look.strength:.0%} of the needle learnt")
    radii = np.asarray(look.radii)
    line = _robust_line(*_centroids(tophat, phis, radii, np.full(len(radii), float(best)), peak, look.width, 3),
                        look.width)
    if isinstance(line, StageFailure):
        return line
    # again about where that line crosses each circle, so that a number beside the needle is not taken
    point, direction = np.asarray(line.point), np.asarray(line.direction)
    along = point @ direction
    ends = point + (np.sqrt(np.maximum(along ** 2 - point @ point + radii ** 2, 0.0)) - along)[:, None] * direction
    at = np.mod(np.arctan2(ends[:, 1], ends[:, 0]) - phis[0], 2 * math.pi) / STEP
    line = _robust_line(*_centroids(tophat, phis, radii, at, peak, look.width, 1), look.width, through=line)
    if isinstance(line, StageFailure):
        return line
    point, direction = np.asarray(line.point), np.asarray(line.direction)
    signed = float(direction[0] * point[1] - direction[1] * point[0])
    if abs(signed) > MAX_OFFSET:
        return StageFailure(STAGE, "needle_off_centre", f"scanned needle passes {abs(signed):.2f} radii from the pivot")
    heading = math.atan2(direction[1], direction[0])
    to_crop = dial_homographies(arc.ellipse, arc.centre)[1]
    start, tip = apply_homography(to_crop, np.array([line.point, line.tip]))
    along_px = (tip - start) / max(float(np.linalg.norm(tip - start)), 1e-9)
    line_px = NeedleLine(tuple(map(float, start)), tuple(map(float, along_px)), tuple(map(float, tip)),
                         line.rms_px * arc.ellipse.b, line.support)
    crossing = float(wrap_to_pi(heading + math.asin(signed)))  # where the line leaves the unit circle
    return ScannedNeedle(line_px, crossing, look.mask_score, abs(signed), heading, signed, crossing)


def _centroids(tophat: np.ndarray, phis: np.ndarray, radii: np.ndarray, at: np.ndarray, peak: float,
               width: float, reach: int) -> tuple[np.ndarray, np.ndarray]:
    """Dial-frame points (N, 2) and weights (N,): per circle crossing the needle clearly, the centroid
    of its stroke's core (the run at or above :data:`CORE_SHARE` of its maximum) within half the
    needle's width and ``reach`` rays of ray ``at``."""
    half = (0.5 * width / radii / STEP).astype(int) + reach  # (R,)
    offsets = np.arange(-half.max(), half.max() + 1)
    index = np.rint(at).astype(int)[:, None] + offsets  # (R, W)
    inside = (np.abs(offsets) <= half[:, None]) & (index >= 0) & (index < tophat.shape[1])
    values = np.where(inside, np.take_along_axis(tophat, index.clip(0, tophat.shape[1] - 1), axis=1), 0.0)
    top = values.argmax(axis=1)
    height = values.max(axis=1)
    below = values < CORE_SHARE * height[:, None]
    column = np.arange(len(offsets))
    left = np.where(below & (column < top[:, None]), column, -1).max(axis=1)[:, None]
    right = np.where(below & (column > top[:, None]), column, len(offsets)).min(axis=1)[:, None]
    mass = np.where((column > left) & (column < right), values - CORE_SHARE * height[:, None], 0.0)
    clear = height >= ROW_SHARE * peak
    phi = phis[0] + STEP * (index[:, 0] + (mass @ column) / np.maximum(mass.sum(axis=1), 1e-9))
    points = np.stack([radii * np.cos(phi), radii * np.sin(phi)], axis=1)
    return points[clear], height[clear].astype(float)


def _robust_line(points: np.ndarray, weights: np.ndarray, width: float,
                 through: NeedleLine | None = None) -> NeedleLine | StageFailure:
    """TLS line through the ``points`` within :data:`INLIER_SHARE` of the needle's ``width`` (at least
    :data:`INLIER_MIN`) of the line ``through``, or without it of the line through the two of them that
    the most (then the heaviest) points lie near."""
    tolerance = max(INLIER_SHARE * width, INLIER_MIN)
    keep = np.zeros(len(points), bool)
    if through is not None:
        rel = points - np.asarray(through.point)
        keep = np.abs(rel[:, 0] * through.direction[1] - rel[:, 1] * through.direction[0]) <= tolerance
    elif len(points) >= MIN_ROWS:
        first, second = np.triu_indices(len(points), 1)
        direction = points[second] - points[first]
        direction /= np.maximum(np.linalg.norm(direction, axis=1, keepdims=True), 1e-12)
        rel = points[None, :, :] - points[first][:, None, :]  # (pairs, points, 2)
        inliers = np.abs(rel[..., 0] * direction[:, None, 1] - rel[..., 1] * direction[:, None, 0]) <= tolerance
        keep = inliers[int(np.argmax(inliers.sum(axis=1) + inliers @ weights / (weights.sum() + 1e-9)))]
    if keep.sum() < MIN_ROWS:
        return StageFailure(STAGE, "no_clear_peak", f"the stroke crosses {int(keep.sum())} circles in line, "
                            f"a needle {MIN_ROWS}")
    line = fit_needle_line(points[keep], (0.0, 0.0), weights=weights[keep], min_pixels=MIN_ROWS)
    return StageFailure(STAGE, "no_clear_peak", line.detail) if isinstance(line, StageFailure) else line


def _run(values: np.ndarray, top: int, level: float) -> tuple[int, int]:
    """First and last index of the run of ``values`` at or above ``level`` through index ``top``."""
    left = right = top
    while left > 0 and values[left - 1] >= level:
        left -= 1
    while right < len(values) - 1 and values[right + 1] >= level:
        right += 1
    return left, right


def learn_needle_look(crop: np.ndarray, arc: ScaleArc, needle: NeedleReading,
                      previous: NeedleLook | None = None) -> NeedleLook | StageFailure:
    """The look of the needle the crop model found in (S, S, 3) uint8 BGR ``crop`` on ``arc``.

    Of the colour channels and both polarities, the one where the needle differs most from the face
    beside it; the circles (0.3-0.9 radii, short of its tip) where it shows at least half that contrast
    and the face round the dial is plain; its width at half contrast. Returned only when a scan with
    it finds the needle within :data:`AGREE` of the crop model's ``needle`` on this crop; that read
    joins the lines and anchors of ``previous`` (the look learnt before on this lock).
    """
    half = int(LEARN_HALF / STEP)
    polar = _polar(crop, arc, needle.angle - half * STEP, 2 * half + 1, LEARN_RADII)
    apart = np.abs(np.arange(-half, half + 1)) * STEP
    # the rays near the crop model's needle on each circle: about its angle, and beside it as far as
    # a line passing ``offset`` radii from the pivot strays on that circle
    near = apart <= 3 * STEP + np.arcsin(np.minimum(needle.offset / LEARN_RADII, 1.0))[:, None]  # (radii, rays)
    mid = (LEARN_RADII >= INNER_MIN) & (LEARN_RADII <= 0.7)
    best = None
    for channel, weights in enumerate(CHANNELS):
        grey = polar @ np.asarray(weights, np.float32)
        for polarity in (1.0, -1.0):
            above_face = polarity * (np.median(grey[:, apart >= FACE_FROM], axis=1, keepdims=True) - grey)
            contrast = np.where(near, above_face, -np.inf).max(axis=1)  # (radii,)
            if best is None or np.median(contrast[mid]) > best[0]:
                best = (float(np.median(contrast[mid])), channel, polarity, above_face, contrast)
    level, channel, polarity, above_face, contrast = best
    if level < MIN_CONTRAST:
        return StageFailure(STAGE, "faint_needle", f"the needle differs from the face by {level:.0f} grey levels")
    shows = contrast >= 0.5 * level
    reach = int(np.argmin(np.abs(LEARN_RADII - 0.5)))
    while shows[reach] and reach < len(shows) - 1 and shows[reach + 1]:
        reach += 1
    shows &= (LEARN_RADII >= INNER_MIN) & (LEARN_RADII <= min(OUTER_MAX, LEARN_RADII[reach] - TIP_MARGIN))
    if shows.sum() < MIN_ROWS:
        return StageFailure(STAGE, "short_needle", f"the needle shows on {int(shows.sum())} circles, a scan "
                            f"needs {MIN_ROWS}")
    tops = np.where(near, above_face, -np.inf).argmax(axis=1)
    widths = [np.subtract(*_run(row, top, 0.5 * c)[::-1]) + 1 for row, top, c in zip(above_face, tops, contrast)]
    widths = np.asarray(widths)[shows]
    width = max(float(np.median(widths * STEP * LEARN_RADII[shows])), 1.0 / arc.ellipse.b)
    look = NeedleLook(channel, polarity, width, tuple(map(float, LEARN_RADII[shows])), 1.0, float(needle.mask_score))
    phis, tophat, _ = _scan(crop, arc, look)
    at_needle = np.abs(wrap_to_pi(phis - needle.angle)) <= look.kernel // 2 * STEP
    if not at_needle.any() or at_needle.all():
        return StageFailure(STAGE, "scan_disagrees", "the crop model's needle lies outside the scanned arc")
    # circles where the face shows as much as the needle on many rays (numbers, ticks, an inner scale) are left out
    plain = np.percentile(tophat[:, ~at_needle], 90, axis=1) <= CLUTTER_SHARE * tophat[:, at_needle].max(axis=1)
    kept = np.asarray(look.radii)[plain]
    if len(kept) < MIN_ROWS or kept[-1] - kept[0] < MIN_BAND:
        return StageFailure(STAGE, "short_needle", f"the needle shows on {len(kept)} plain circles, a scan needs "
                            f"{MIN_ROWS} over {MIN_BAND:g} radii")
    look = replace(look, radii=tuple(map(float, kept)))
    phis, _, scores = _scan(crop, arc, look)
    look = replace(look, strength=max(float(scores[at_needle].max()), 1e-6))
    check = _scan_line(crop, arc, look)
    if isinstance(check, StageFailure):
        return StageFailure(STAGE, "scan_disagrees", f"a scan of the crop learnt from fails: {check.reason}")
    off = float(wrap_to_pi(needle.angle - check.crossing))
    if abs(off) > AGREE:
        return StageFailure(STAGE, "scan_disagrees", f"a scan reads {math.degrees(abs(off)):.1f} degrees from "
                            "the crop model")
    lines, anchors = ((), ()) if previous is None else (previous.lines, previous.anchors)
    return replace(look, angle=float(needle.angle), lines=(*lines, (check.direction, check.signed_offset))[-LINES:],
                   anchors=(*anchors, (float(needle.angle), off))[-ANCHORS:])
