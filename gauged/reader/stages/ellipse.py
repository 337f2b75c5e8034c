"""The scale arc of one gauge: an ellipse through its notches, and where the scale starts and ends.

Reitsma et al. (Sec. 3.3) fit an ellipse through the detected notches. Detected notches include
false peaks (a printed logo, a screw head), so this fits robustly: fit, drop notches whose orthogonal
distance is far beyond the others', refit. With fewer than five notches, or when the data cannot tell
an ellipse from a circle, a circle is used (:func:`gauged.geometry.ellipse_fit.fit_ellipse` "auto").

The start and end notches come from their own heatmaps; when one is missing it is inferred from the
major notches as the two ends of the largest angular gap between them (a scale never wraps around
its gap).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from gauged.geometry.angles import scale_span, unwrap, wrap_angle, wrap_to_pi
from gauged.geometry.dial_frame import dial_angle, normalized_radius
from gauged.geometry.ellipse_distance import orthogonal_distance
from gauged.geometry.ring_search import (
    _centred_fit,
    _coverage,
    _robust_fit,
    _scale_ring,
)
from gauged.reader.ocr.regions import NUMBER_BAND
from gauged.reader.stages.keypoints import CropKeypoints
from gauged.types import Ellipse, StageFailure

STAGE = "ellipse"
NUMBERS_OUTSIDE_SCALE = "numbers_outside_scale"
POOR_FIT = "poor_fit"
NO_SCALE_ENDS = "no_scale_ends"
REASONS = ("too_few_notches", "degenerate_conic", POOR_FIT, "too_oblique", NO_SCALE_ENDS, "implausible_span",
           NUMBERS_OUTSIDE_SCALE)

TOLERANCE = 0.012  # of the crop side: a notch farther than this from the ellipse is an outlier
RMS_FRACTION = 0.02  # of the ring's radius: the notch RMS a fit may have (with a floor of TOLERANCE / 2)
RING_SEARCH_BELOW = 0.6  # share of the notch peaks: a first ring explaining fewer is searched for a better one
RING_MIN_SHARE = 0.45  # ... and a ring kept with both ends and the pivot on it this many (else RING_SEARCH_BELOW):
# the crop model's peaks off the ring are 22% of its peaks, 38% on far gauges (see _share_needed)
PIVOT_SURE = 0.5  # pivot peak score above which the pivot is trusted to check the ring
SHORT_ARC = np.radians(150.0)  # notches covering less than this are fitted about a confident pivot
PIVOT_OFF_CENTRE = 0.2  # radii; on 300 synthetic renders the true pivot is within 0.12 of the ring centre
OBLIQUE_AXIS_RATIO = 0.92  # b/a below this: about 23 degrees off-axis
MIN_SPAN = np.radians(60.0)
MAX_SPAN = np.radians(350.0)


@dataclass(frozen=True)
class ScaleArc:
    """The scale's ellipse and its ends, in the crop's pixel coordinates.

    ``centre`` is the dial centre the angles are measured from: the needle pivot when the crop
    model found one inside the ellipse (under perspective the imaged centre of the dial is not the
    centre of the imaged ellipse), else the ellipse centre. Angles are dial angles
    (:func:`gauged.geometry.dial_frame.dial_angle`), radians.
    """

    ellipse: Ellipse
    centre: tuple[float, float]
    start_angle: float
    end_angle: float
    zero_angle: float
    notches: np.ndarray  # (N, 2) inlier notch points
    rms_px: float
    ends_inferred: bool
    rms_limit_px: float | None = None  # the notch RMS the fit was allowed (None: RMS_FRACTION of the radius)

    @property
    def fit_share(self) -> float:
        """The notch RMS as a share of what the fit was allowed: 0 a perfect ring, 1 the most
        scattered ring :func:`fit_scale_arc` accepts."""
        limit = self.rms_limit_px if self.rms_limit_px is not None else RMS_FRACTION * self.ellipse.a
        return self.rms_px / limit

    @property
    def span(self) -> float:
        return scale_span(self.start_angle, self.end_angle)

    @cached_property
    def notch_grid(self) -> tuple[np.ndarray, np.ndarray] | None:
        """(measured, even) unwrapped dial angles of the major notches, or None; see :meth:`linear`."""
        if len(self.notches) == 0:
            return None
        angles = dial_angle(self.ellipse, self.notches, self.centre)
        return notch_grid(unwrap(angles, self.zero_angle), float(unwrap(self.start_angle, self.zero_angle)),
                          float(unwrap(self.end_angle, self.zero_angle)))

    def linear(self, angle: float | np.ndarray) -> float | np.ndarray:
        """Dial angle(s) corrected so that the major notches are evenly spaced between the ends.

        The major notches of a linear scale are evenly spaced in value, but their fitted dial
        angles are not quite even: an ellipse fitted to part of a ring, or perspective on a dial
        whose pivot was not used, bends the angles by a degree or more (a percent of the reading).
        Mapping angles piecewise-linearly from the measured notch angles to evenly spaced ones
        reads the needle against its neighbouring notches, as a person does. Identity when the
        notches do not form a regular grid (:func:`notch_grid`) and outside the scale.
        """
        grid = self.notch_grid
        if grid is None:
            return angle
        u = unwrap(np.asarray(angle, float), self.zero_angle)
        inside = (u >= grid[0][0]) & (u <= grid[0][-1])
        corrected = np.where(inside, np.interp(u, grid[0], grid[1]), u)
        out = wrap_to_pi(corrected)
        return float(out) if np.ndim(angle) == 0 else np.asarray(out)

    def number_angles(self, points: np.ndarray) -> np.ndarray:
        """Dial angles of scale numbers at ``points`` (N, 2) px: :meth:`linear`, then :meth:`on_notches`,
        the frame the needle's angle is read in."""
        return self.on_notches(self.linear(dial_angle(self.ellipse, points, self.centre)))

    def on_notches(self, angle: np.ndarray) -> np.ndarray:
        """:meth:`linear` angles of scale numbers moved onto the major notch each one labels.

        A printed number labels a major notch, but its box centre, seen from the dial centre, sits a
        few degrees off it: upright text is not centred on its radius (a real 0..100 dial's "40" reads
        6.6 degrees off, beyond the scale fit's tolerance). On a regular notch grid (:func:`notch_grid`)
        each angle within :data:`SNAP_TOLERANCE` of a step of a grid position, missed notches included,
        takes that position; others, and all when there is no grid, are returned as they are.
        """
        angle = np.asarray(angle, float)
        grid = self.notch_grid
        if grid is None:
            return angle
        start, end = grid[1][0], grid[1][-1]
        step = float(np.min(np.diff(grid[1])))
        u = unwrap(angle, self.zero_angle)
        k = np.rint((u - start) / step)
        node = start + k * step
        snap = (np.abs(u - node) <= SNAP_TOLERANCE * step) & (node >= start - 1e-9) & (node <= end + 1e-9)
        return np.where(snap, wrap_to_pi(node), angle)


GAP_MIN_NOTCHES = 4  # notches needed to infer the ends from their largest gap (with three, any gap could be it)
GAP_NUMBERS = 2  # confident number peaks in the gap that mean found ends are wrong (1 for inferred ends)
NUMBER_SCORE = 0.5


def _numbers_in_gap(keypoints: CropKeypoints, ellipse: Ellipse, centre, start: float, span: float,
                    min_score: float = NUMBER_SCORE) -> int:
    """How many confident number peaks near the scale ring lie in the gap between the scale ends.

    Scale numbers sit beside the scale, never in its gap: several there mean the ends are wrong
    (typically notches the model missed made a false gap). One alone is more often the accuracy
    class or a maker's mark printed in the gap, and peaks far from the ring are not scale numbers.
    """
    numbers = keypoints.numbers
    if not len(numbers):
        return 0
    margin = np.radians(12.0)
    radius = normalized_radius(ellipse, numbers.points)
    near = (radius >= NUMBER_BAND[0]) & (radius <= NUMBER_BAND[1]) & (numbers.scores >= min_score)
    offset = np.mod(dial_angle(ellipse, numbers.points, centre) - start, 2 * np.pi)  # 0 at start, span at end
    return int((near & (offset > span + margin) & (offset < 2 * np.pi - margin)).sum())


GRID_TOLERANCE = 0.3  # of the notch step: how far a gap may be from a whole number of steps
SNAP_TOLERANCE = 0.3  # of the notch step: how far a number may sit from the notch it labels


def notch_grid(notch_angles: np.ndarray, start: float, end: float) -> tuple[np.ndarray, np.ndarray] | None:
    """Knots (measured, even) of the piecewise-linear angle correction of :meth:`ScaleArc.linear`.

    ``notch_angles`` (N,), ``start`` and ``end`` are unwrapped dial angles (radians, start < end).
    The notches between the ends (plus the ends) are sorted; the median gap is one step; every gap
    must be within :data:`GRID_TOLERANCE` of a whole number of steps (a missed notch makes a gap
    of two). The knots' even angles then run from ``start`` to ``end`` by equal steps. None when
    the notches are too few (under 4 with the ends) or irregular (minor ticks or false peaks taken
    for majors): the angles are then used as measured.
    """
    if not end > start:
        return None
    step_guess = (end - start) / 40.0  # notches closer than this are one notch seen twice
    inside = np.sort(np.asarray(notch_angles, float)[(notch_angles > start + step_guess) & (notch_angles < end - step_guess)])
    knots = np.concatenate([[start], inside, [end]])
    knots = knots[np.concatenate([[True], np.diff(knots) > step_guess])]
    if len(knots) < 4 or knots[-1] != end:
        return None
    gaps = np.diff(knots)
    steps = np.rint(gaps / np.median(gaps))
    if np.any(steps < 1) or np.any(np.abs(gaps / np.median(gaps) - steps) > GRID_TOLERANCE):
        return None
    even = start + (end - start) * np.concatenate([[0.0], np.cumsum(steps)]) / steps.sum()
    return knots, even


GAP_CLEARLY_LARGER = 1.4  # the scale's gap must exceed the notch spacing by this factor to be recognised


def _ends_from_gap(angles: np.ndarray, clearly: float = GAP_CLEARLY_LARGER) -> tuple[float, float] | None:
    """Start and end angles around the largest clockwise gap between sorted notch angles.

    None when that gap is not clearly larger than the spacing of the notches: on a dial whose gap is
    about one notch step wide, every gap looks alike and guessing would put the scale anywhere.
    """
    order = np.sort(np.mod(angles, 2 * np.pi))
    gaps = np.diff(np.concatenate([order, order[:1] + 2 * np.pi]))
    k = int(np.argmax(gaps))
    others = np.delete(gaps, k)
    if len(others) and gaps[k] < clearly * float(np.median(others)):
        return None
    end, start = order[k], order[(k + 1) % len(order)]
    return float(start), float(end)


SNAP_RADIANS = np.radians(3.0)


def _snap(angle: float, notch_angles: np.ndarray) -> float:
    """The angle of the major notch nearest ``angle`` when one is within 3 degrees, else ``angle``.

    The end-notch heatmaps say which notch is an end; the many major notches locate it more exactly
    (an end peak a few pixels off is a percent of the reading).
    """
    if len(notch_angles) == 0:
        return angle
    diff = np.abs(np.remainder(notch_angles - angle + np.pi, 2 * np.pi) - np.pi)
    k = int(np.argmin(diff))
    return float(notch_angles[k]) if diff[k] <= SNAP_RADIANS else angle


def fit_scale_arc(keypoints: CropKeypoints, crop_size: int, min_notches: int = 4,
                  max_rms_fraction: float = RMS_FRACTION, min_axis_ratio: float = 0.35,
                  ends_from_gap: bool = False, gap_clearly: float = GAP_CLEARLY_LARGER) -> ScaleArc | StageFailure:
    """Fit the scale arc to the crop model's notches (crop pixels). See the module docstring.

    Failures: ``too_few_notches`` (fewer than ``min_notches`` notch points), ``degenerate_conic``,
    ``poor_fit`` (inlier RMS above ``max_rms_fraction`` of the radius or half :data:`TOLERANCE` of the
    crop, whichever is larger, or too few notches on the ring, :func:`_share_needed`), ``too_oblique`` (axis ratio
    below ``min_axis_ratio``, a dial seen more than ~70 degrees off-axis), ``no_scale_ends`` (start or
    end notch missing and not inferable), ``implausible_span`` (scale span outside 60-350 degrees).

    With a confident pivot peak, a ring whose notches cover less than :data:`SHORT_ARC` about the
    pivot, or whose centre lies more than :data:`PIVOT_OFF_CENTRE` radii from it, is fitted again
    about the pivot (:func:`_centred_fit`); ``poor_fit`` when that finds no ring either.

    Angles are measured about a pivot peak inside the ring when the view is oblique
    (:data:`OBLIQUE_AXIS_RATIO`); :func:`arc_about_pivot` measures them so on any view.

    ``ends_from_gap`` takes the ends from the notches' largest gap whatever the end peaks and the
    number peaks in that gap say: for a dial whose ends are hidden, read only between its numbers
    (the pipeline's look after ``numbers_outside_scale``). ``gap_clearly`` is how much larger than
    the notch spacing that gap must be (1: any largest gap; for a configured scale, whose ends the
    pipeline then takes from the numbers, not from the gap).
    """
    parts = [keypoints.major.points]
    for peaks in (keypoints.start, keypoints.end):
        if len(peaks):
            parts.append(peaks.points[:1])
    points = np.concatenate(parts).reshape(-1, 2)
    if len(points) < min_notches:
        return StageFailure(STAGE, "too_few_notches", f"{len(points)} notch points, need {min_notches}")
    fitted = _robust_fit(points, tol_px=TOLERANCE * crop_size)
    if isinstance(fitted, StageFailure):
        return fitted
    ellipse, inliers = fitted
    explained = int(inliers.sum())
    ends = np.zeros(len(points), bool)
    ends[len(keypoints.major.points):] = True
    if explained < max(min_notches, RING_SEARCH_BELOW * len(points)) or (ends.any() and not (inliers & ends).any()):
        ellipse, inliers, explained = _scale_ring(points, ellipse, inliers, ends, TOLERANCE * crop_size, min_notches)
    if len(keypoints.pivot) and keypoints.pivot.scores[0] >= PIVOT_SURE:
        pivot = keypoints.pivot.points[0]
        off = float(normalized_radius(ellipse, pivot[None])[0])
        if off > PIVOT_OFF_CENTRE or _coverage(points[inliers], pivot) < SHORT_ARC:
            # A free ellipse through the notches of a short arc (a 90-degree sector scale) bends to
            # any centre; the scale is centred on the needle's pivot, so it is fitted about that.
            centred = _centred_fit(points, pivot, TOLERANCE * crop_size)
            if centred is None:
                return StageFailure(STAGE, POOR_FIT, f"the needle pivot lies {off:.2f} radii from the ring's centre")
            ellipse, inliers = centred
            explained = int(inliers.sum())
    if ellipse.b / ellipse.a < min_axis_ratio:
        return StageFailure(STAGE, "too_oblique", f"axis ratio {ellipse.b / ellipse.a:.2f} < {min_axis_ratio}")
    if explained < max(min_notches, _share_needed(keypoints, ellipse, inliers, ends) * len(points)):
        return StageFailure(STAGE, POOR_FIT, f"only {explained} of {len(points)} notches lie on the scale ring(s)")
    rms = float(np.sqrt(np.mean(orthogonal_distance(ellipse, points[inliers]) ** 2)))
    # The notch peaks themselves are good to about a pixel, so a small ring gets an absolute floor.
    rms_limit = max(max_rms_fraction * ellipse.a, 0.5 * TOLERANCE * crop_size)
    if rms > rms_limit:
        return StageFailure(STAGE, POOR_FIT, f"notch RMS {rms:.1f} px on a radius of {ellipse.a:.0f} px")
    centre = ellipse.center
    # Under perspective the dial's centre (the pivot) is not the ellipse's centre, and only a frame
    # through the pivot reads angles right; but a pixel of pivot error costs ~1 degree on a small
    # dial, so the pivot is used only when the view is oblique enough for perspective to matter.
    if ellipse.b / ellipse.a < OBLIQUE_AXIS_RATIO:
        centre = _pivot_inside(keypoints, ellipse) or centre
    return _arc_about(keypoints, ellipse, points[inliers], rms, rms_limit, centre, ends_from_gap, gap_clearly)


def arc_about_pivot(arc: ScaleArc, keypoints: CropKeypoints) -> ScaleArc | StageFailure | None:
    """``arc``'s ring with its angles measured about the pivot peak of ``keypoints`` (ends, gap and
    their checks again), or None when the arc is measured about it already or there is no pivot
    peak inside the ring. :func:`fit_scale_arc` does so only on oblique views; the pipeline's second
    look at a refused scale (:meth:`gauged.reader.pipeline.GaugeReader._about_pivot`) on any."""
    pivot = _pivot_inside(keypoints, arc.ellipse)
    if pivot is None or pivot == arc.centre:
        return None
    return _arc_about(keypoints, arc.ellipse, arc.notches, arc.rms_px, arc.rms_limit_px, pivot)


def _pivot_inside(keypoints: CropKeypoints, ellipse: Ellipse) -> tuple[float, float] | None:
    """The first pivot peak when it lies within a quarter of the minor semi-axis of the ring's centre."""
    if not len(keypoints.pivot):
        return None
    pivot = keypoints.pivot.points[0]
    if np.hypot(pivot[0] - ellipse.cx, pivot[1] - ellipse.cy) >= 0.25 * ellipse.b:
        return None
    return (float(pivot[0]), float(pivot[1]))


def _arc_about(keypoints: CropKeypoints, ellipse: Ellipse, notches: np.ndarray, rms: float, rms_limit: float | None,
               centre: tuple[float, float], ends_from_gap: bool = False,
               gap_clearly: float = GAP_CLEARLY_LARGER) -> ScaleArc | StageFailure:
    """The scale arc of the ring ``ellipse`` through its inlier ``notches``, with dial angles measured
    about ``centre``: the ends (found, else inferred from the notches' largest gap) and their checks;
    with ``ends_from_gap``, the gap's ends and no check of the numbers in it."""
    found_start, found_end = (False, False) if ends_from_gap else (len(keypoints.start) > 0, len(keypoints.end) > 0)
    inferred = not (found_start and found_end)
    if inferred:
        if len(notches) < GAP_MIN_NOTCHES:
            return StageFailure(STAGE, NO_SCALE_ENDS, "start/end notch missing and too few notches to infer them")
        ends = _ends_from_gap(dial_angle(ellipse, notches, centre), gap_clearly)
        if ends is None:
            return StageFailure(STAGE, NO_SCALE_ENDS, "start/end notch missing and no gap between the notches "
                                "stands out as the scale's")
        gap_start, gap_end = ends
    notch_angles = dial_angle(ellipse, notches, centre)
    start = (_snap(float(dial_angle(ellipse, keypoints.start.points[:1], centre)[0]), notch_angles)
             if found_start else gap_start)
    end = (_snap(float(dial_angle(ellipse, keypoints.end.points[:1], centre)[0]), notch_angles)
           if found_end else gap_end)
    span = scale_span(start, end)
    if not MIN_SPAN <= span <= MAX_SPAN:
        return StageFailure(STAGE, "implausible_span", f"scale spans {np.degrees(span):.0f} degrees")
    if ends_from_gap:
        return ScaleArc(ellipse, centre, start, end, wrap_angle(start, end), notches, rms, True, rms_limit)
    # Ends inferred from the largest gap between notches are only a guess (missed notches make a
    # gap too): then a single number peak of any score in that gap refutes it.
    in_gap = _numbers_in_gap(keypoints, ellipse, centre, start, span, 0.0 if inferred else NUMBER_SCORE)
    if in_gap >= (1 if inferred else GAP_NUMBERS):
        gap = None if inferred or len(notches) < GAP_MIN_NOTCHES else _ends_from_gap(notch_angles)
        if gap is not None and _plausible_gap(keypoints, ellipse, centre, *gap):
            # The found end notches are refuted by numbers in their gap (the model took a notch
            # mid-scale for an end: a real 0..160 dial's "start" at 120); the largest gap between
            # the notches holds no number at all, so it is taken as the scale's, as when no end is found.
            start, end = gap
            return ScaleArc(ellipse, centre, start, end, wrap_angle(start, end), notches, rms, True, rms_limit)
        return StageFailure(STAGE, NUMBERS_OUTSIDE_SCALE, f"{in_gap} scale numbers lie in the gap between the scale ends")
    return ScaleArc(ellipse, centre, start, end, wrap_angle(start, end), notches, rms, inferred, rms_limit)


def _share_needed(keypoints: CropKeypoints, ellipse: Ellipse, inliers: np.ndarray, ends: np.ndarray) -> float:
    """The share of the notch peaks a ring must explain: :data:`RING_SEARCH_BELOW`, or only
    :data:`RING_MIN_SHARE` when other evidence vouches for it (both scale ends found and on it, and a
    confident pivot peak at its centre). Any five peaks lie on some ellipse, so a ring of few of
    them needs that evidence: 7 of 14 peaks strewn over a face fit one to 0.3 px."""
    both_ends = len(keypoints.start) > 0 and len(keypoints.end) > 0 and bool(inliers[ends].all())
    pivot = keypoints.pivot
    centred = (len(pivot) > 0 and pivot.scores[0] >= PIVOT_SURE
               and float(normalized_radius(ellipse, pivot.points[:1])[0]) <= PIVOT_OFF_CENTRE)
    return RING_MIN_SHARE if both_ends and centred else RING_SEARCH_BELOW


def _plausible_gap(keypoints: CropKeypoints, ellipse: Ellipse, centre, start: float, end: float) -> bool:
    """Whether ends inferred from a gap span a plausible scale with no number peak of any score in the gap."""
    span = scale_span(start, end)
    return MIN_SPAN <= span <= MAX_SPAN and _numbers_in_gap(keypoints, ellipse, centre, start, span, 0.0) == 0
