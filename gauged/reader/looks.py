"""Looks at a dial whose scale ends the ellipse stage could not settle, as methods of the reader.

:meth:`EndsLooks._between_numbers` reads a dial whose ends are hidden or not found between the numbers
read (or, with its scale configured, on the configured range placed by those numbers);
:meth:`EndsLooks._about_pivot` fits the arc again about the needle's pivot when the scale fails on it.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from gauged.reader.gauge_read import (
    GaugeRead,
    KnownScale,
    _Timer,
)
from gauged.reader.stages.crop import Crop
from gauged.reader.stages.ellipse import (
    GAP_CLEARLY_LARGER,
    ScaleArc,
    arc_about_pivot,
    fit_scale_arc,
)
from gauged.reader.stages.keypoints import CropKeypoints, sure_numbers
from gauged.reader.stages.needle import NeedleReading, fit_needle
from gauged.reader.stages.reading import read_value
from gauged.reader.stages.scale import (
    arc_at_values,
    fit_scales,
    scale_from_prior,
)
from gauged.types import ScaleModel, StageFailure

BETWEEN_NUMBERS = 4  # agreeing numbers a dial with hidden ends needs, the needle between them
KNOWN_NUMBERS = 3  # ... and with its scale configured, the needle anywhere in the configured range


class EndsLooks:
    """Mixed into :class:`gauged.reader.pipeline.GaugeReader`, whose models, OCR and reads these use."""

    def _about_pivot(self, image: np.ndarray, crop: Crop, keypoints: CropKeypoints, arc: ScaleArc, result: GaugeRead,
                     timer: _Timer) -> tuple[ScaleArc, NeedleReading, list[ScaleModel]] | None:
        """The arc, needle and scales of a dial whose scale was refused, read again about the needle's
        pivot, or None.

        Angles are measured about the ellipse's centre unless the view is oblique, since a pixel of
        pivot error costs a degree on a small dial. But under a close camera's perspective the dial's
        centre projects away from its scale ellipse's centre even when the ellipse is nearly round
        (a held-out render: axis ratio 0.97, the pivot 0.06 radii off), and the numbers' angles about the
        wrong centre then bend by 5-10% from one number to the next, past the scale line's 3-degree
        tolerance ("100, 200, 300" read right, two on a line). So a refused scale gets its ring measured
        about the pivot (:func:`gauged.reader.stages.ellipse.arc_about_pivot`, no new fit), the needle against
        it, and the scale fitted to the markers read, then to markers read again on the dial rectified
        about the pivot. The refusal stands unless the scale stage accepts them.
        """
        if not result.markers:
            return None  # nothing read to fit again
        with timer("ellipse"):
            pivoted = arc_about_pivot(arc, keypoints)
        if pivoted is None or isinstance(pivoted, StageFailure):
            return None  # measured about the pivot already, no pivot inside the ring, or no arc about it
        with timer("needle"):
            needle = fit_needle(keypoints.needle_prob, keypoints.stride, pivoted)
        if isinstance(needle, StageFailure):
            return None
        with timer("scale"):
            scales = fit_scales(pivoted, result.markers, result.units, hints=sure_numbers(keypoints.numbers))
        if isinstance(scales, StageFailure):
            again = self._read_on(image, crop, keypoints, pivoted, timer)
            if again is None:
                return None
            (result.markers, result.units), scales = again
        return pivoted, needle, scales

    def _between_numbers(self, image: np.ndarray, crop: Crop, keypoints: CropKeypoints, result: GaugeRead,
                         timer: _Timer, known: KnownScale | None = None) -> None:
        """Read a dial refused for numbers in the gap between its scale ends only between the numbers
        read, into ``result``; or leave the refusal standing.

        Such a dial's ends are often hidden (a box or a pipe across the dial, as on a held-out render): the
        largest gap between the notches is the hidden part, and a number half seen at its edge lies
        in it. Without its ends the scale's extent is unknown, but a value between two agreeing
        numbers does not depend on it. So the arc takes the gap's ends (``ends_from_gap``), the scale
        needs :data:`BETWEEN_NUMBERS` agreeing numbers, and the needle must read between the lowest
        and highest of them. The scale's ``min`` and ``max`` are then the values at the ends of the
        visible arc, not the printed range.

        With a configured scale (``known``) the configured range is the prior the numbers are checked
        against: :data:`KNOWN_NUMBERS` agreeing numbers suffice, all must lie in the configured range,
        the needle may read anywhere in it, and the scale takes the configured ends and unit (a dial
        whose end notches the crop model misses is read so)."""
        with timer("ellipse"):
            arc = fit_scale_arc(keypoints, self.crop_size, ends_from_gap=True, gap_clearly=1.0 if known else GAP_CLEARLY_LARGER)
        if isinstance(arc, StageFailure):
            return
        with timer("needle"):
            needle = fit_needle(keypoints.needle_prob, keypoints.stride, arc)
        if isinstance(needle, StageFailure):
            return
        again = self._read_on(image, crop, keypoints, arc, timer,
                              min_inliers=BETWEEN_NUMBERS if known is None else KNOWN_NUMBERS)
        if again is None:
            return
        read, scales = again
        agreeing = [m.value for m in scales[0].markers if m.inlier]
        if known is None:
            low, high = min(agreeing), max(agreeing)
        else:
            low, high = known.min_value, known.max_value
            if not all(low <= v <= high for v in agreeing) or (scales[0].slope > 0) != (known.direction > 0):
                return  # numbers outside the configured range, or rising the other way
            arc = arc_at_values(arc, scales[0], low, high)  # the ends where the numbers' line puts the configured range
            if arc is None:
                return
            scales = [replace(scale_from_prior(arc, low, high, known.unit, known.direction), markers=scales[0].markers,
                              inliers=scales[0].inliers, rms_value=scales[0].rms_value)]
        with timer("reading"):
            value = read_value(needle, arc, scales[0], self.min_confidence)
        if isinstance(value, StageFailure):
            return
        if not low <= value.value <= high:
            return
        result.arc, result.needle, result.scales, result.value, result.failure = arc, needle, scales, value, None
        result.look = "between_numbers"
        result.markers, result.units = read
