"""The scale of one gauge: angle -> value, from OCR'd scale numbers or from a configured prior.

From OCR (Reitsma et al., Sec. 3.5-3.6): the centres of the recognised numbers are projected onto the
scale ellipse, and a RANSAC line maps unwrapped dial angle to value
(:func:`gauged.geometry.scale_fit.fit_scale_model`). Markers inside and outside the scale ellipse are
grouped by the radius they are printed at and fitted separately (dials with a bar and a psi scale); the
primary scale is the configured unit's, else the outer one: a dual-scale dial prints its main scale
outside, and answering with the inner scale's value would be a wrong reading in the wrong unit.

From a prior (``scale: {min, max}`` in the config): the value runs linearly from ``min`` at the start
notch to ``max`` at the end notch, no OCR needed.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from gauged.geometry.angles import unwrap, wrap_angle, wrap_to_pi
from gauged.geometry.dial_frame import dial_angle, normalized_radius
from gauged.geometry.scale_fit import (
    RING_GAP,
    marker_centres,
    number_rings,
)
from gauged.reader.ocr.numbers import round_step
from gauged.reader.ocr.scale_units import label_scales
from gauged.reader.ocr.units import PrintedUnit
from gauged.reader.stages.ellipse import MAX_SPAN, MIN_SPAN, ScaleArc
from gauged.reader.stages.full_circle import fit_full_circle
from gauged.reader.stages.scale_direction import fit_ring
from gauged.types import ScaleMarker, ScaleModel, StageFailure

STAGE = "scale"
REASONS = ("too_few_markers", "degenerate_fit", "wrong_slope_sign", "too_few_inliers", "scale_not_covered",
           "dropped_decimal_point", "irregular_numbers", "numbers_off_grid",
           "secondary_scale_only", "ambiguous_numbers", "numbers_past_ends", "numbers_not_round", "numbers_outvoted")
INNER_RING = 0.8  # ring radii: read numbers inside this may be an inner scale if printed numbers lie further out
SECONDARY_RADIUS = 0.62  # ring radii; main-scale numbers on 300 synthetic renders sit at >= 0.69 (1st pct)
GRID_MIN_HINTS = 5  # confident number centres needed for the grid check
GRID_OFF_SHARE = 0.3  # more than this share of them between grid lines refutes the scale (300 synthetic
# renders: correct reads <= 0.25, the one wrong read that passed every other check 0.33)
ROUND_END = 0.25  # of the number step: how near whole multiples the numbers' line must put both scale ends
END_WEIGHT = 2.0  # how many numbers each end counts as in the line fitted again through them (0.5, 1, 2 gave
# 300 dev renders a mean error of 0.327, 0.329, 0.330%, the 21 real photos 0.55, 0.50, 0.46%)
RETRY_ZERO_MARGIN = 0.05  # of the span: a fitted end this far past zero is on the other side of it


def scale_from_prior(arc: ScaleArc, min_value: float, max_value: float, unit: str | None,
                     direction: int = 1) -> ScaleModel:
    """Linear scale from ``min_value`` at the start notch (the first clockwise) to ``max_value`` at the
    end notch; with ``direction`` -1 (values rising counter-clockwise) from ``max_value`` at the start
    to ``min_value`` at the end."""
    start = unwrap(arc.start_angle, arc.zero_angle)
    end = unwrap(arc.end_angle, arc.zero_angle)
    at_start = min_value if direction > 0 else max_value
    slope = (max_value - min_value) / (end - start) * (1 if direction > 0 else -1)
    return ScaleModel(arc.ellipse, slope, at_start - slope * start, arc.zero_angle, min_value, max_value, unit)


def fit_scales(arc: ScaleArc, markers: Sequence[ScaleMarker], units: Sequence[PrintedUnit] = (),
               min_inliers: int = 3, hints: np.ndarray | None = None, direction: int = 1
               ) -> list[ScaleModel] | StageFailure:
    """Fit one scale per ring of numbers (:func:`number_rings`), outer ring first, each in the unit
    printed for it (:func:`gauged.reader.ocr.scale_units.label_scales`; ``units`` are the units read on
    the dial, best first).

    A scale must have ``min_inliers`` consistent numbers, rise in ``direction`` (+1 clockwise, -1
    counter-clockwise) and reach both scale ends. When the outer ring of a dual-scale dial yields no scale, its failure is returned even
    if the inner ring fits: the inner scale is the secondary one. ``hints`` (N, 2) crop px are the
    crop model's confident number centres: the primary scale must put them on its number grid.
    """
    # Number angles in the same corrected frame as the needle's (ScaleArc.linear), on their notches.
    markers = list(markers)
    if markers:
        angles = arc.number_angles(marker_centres(markers))
        markers = [replace(m, angle=float(a)) for m, a in zip(markers, angles, strict=True)]
    rings = number_rings(arc.ellipse, markers)
    if not rings:
        return StageFailure(STAGE, "too_few_markers", "no scale number was read")
    whole: ScaleModel | StageFailure | None = None
    if len(rings) == 2:
        whole = fit_ring(arc, markers, min_inliers, direction)
        if not isinstance(whole, StageFailure) and _spans_both(whole, rings):
            # one scale whose numbers only looked like two rings (a skewed ellipse)
            return _finished(arc, [whole], units)
    lone = len(rings) == 1
    outer = fit_ring(arc, rings[0], min_inliers, direction)
    if isinstance(outer, StageFailure):
        rescued = _rescue(arc, markers, rings, whole)
        if rescued is None:
            return outer if lone else replace(outer, detail=f"outer scale: {outer.detail}")
        scales, lone = [rescued], True  # checked as a lone ring is
    else:
        scales = [outer]
        inner = None if lone else fit_ring(arc, rings[1], min_inliers, direction)
        if inner is not None and not isinstance(inner, StageFailure):
            scales.append(inner)
    if lone:  # a lone ring must be the main scale, and the printed numbers must agree
        failure = _secondary_only(arc, scales[0], hints)
        if failure is None and hints is not None:
            failure = _off_grid(arc, scales[0], hints)
        if failure is not None:
            return failure
    return _finished(arc, scales, units)


def _finished(arc: ScaleArc, scales: list[ScaleModel], units: Sequence[PrintedUnit]) -> list[ScaleModel]:
    """The accepted scales (main one first) as returned: the main one with its round ends
    (:func:`with_round_ends`), each in the unit printed for it (:func:`label_scales`)."""
    return label_scales([with_round_ends(arc, scales[0])] + scales[1:], units)


def with_round_ends(arc: ScaleArc, model: ScaleModel) -> ScaleModel:
    """``model``'s line fitted again with the scale's ends as evidence, when the line puts both ends
    within :data:`ROUND_END` of a number step from whole multiples of the step.

    A linear scale starts and ends on its number grid (0..1000 kPa numbered by 200), and its end
    notches are where the crop model finds them. On real photos the numbers' line alone lands off
    those values (a 0..1000 kPa dial: 13.3..998.7, reading 15.7 at rest for 0): printed numbers sit
    a degree or two off their notches, and the line extrapolates that to the ends. Each end counts
    as :data:`END_WEIGHT` numbers, a hedge between the numbers and the ends: on renders the numbers
    sit on their notches and the end peaks carry their own error (docs/accuracy.md). Not
    for ends inferred from a notch gap (a guess, or the edge of what is visible) nor for a full-circle
    scale, which has no ends.
    """
    agreeing = [m for m in model.markers if m.inlier and m.angle is not None]
    if arc.ends_inferred or model.full_circle or len(agreeing) < 2:
        return model
    step = round_step(np.unique([m.value for m in agreeing]))
    if step <= 0:
        return model
    ends = np.array([model.unwrap(arc.start_angle), model.unwrap(arc.end_angle)])
    fitted = model.slope * ends + model.intercept
    rounded = np.round(fitted / step) * step
    if np.any(np.abs(fitted - rounded) > ROUND_END * step) or (rounded[1] - rounded[0]) * model.slope <= 0:
        return model
    angles = np.concatenate([[model.unwrap(m.angle) for m in agreeing], ends])
    values = np.concatenate([[m.value for m in agreeing], rounded])
    weights = np.sqrt(np.concatenate([np.ones(len(agreeing)), [END_WEIGHT, END_WEIGHT]]))
    design = np.stack([angles, np.ones_like(angles)], axis=1) * weights[:, None]
    (slope, intercept), *_ = np.linalg.lstsq(design, values * weights, rcond=None)
    low, high = sorted(round(float(v), 12) + 0.0 for v in slope * ends + intercept)  # no float noise: 0..16, not 1e-14..16
    return replace(model, slope=float(slope), intercept=float(intercept), min_value=low, max_value=high)


def _rescue(arc: ScaleArc, markers: list[ScaleMarker], rings: list[list[ScaleMarker]],
            whole: ScaleModel | StageFailure | None) -> ScaleModel | None:
    """A scale for numbers whose outer ring gave none, or None.

    A lone ring may be a full-circle scale: ends inferred inside a scale that has none cut its
    numbers in two (:func:`gauged.reader.stages.full_circle.fit_full_circle`). Two outer numbers too few for
    a scale of their own make one with a number of the inner ring on their line (a "0" printed
    nearer the centre than "100, 200" on a synthetic render).
    """
    if len(rings) == 1:
        return fit_full_circle(arc, markers, None)
    if whole is not None and not isinstance(whole, StageFailure) and _from_ring(whole, rings[0]) >= 2:
        return whole
    return None


def _secondary_only(arc: ScaleArc, model: ScaleModel, hints: np.ndarray | None = None) -> StageFailure | None:
    """A failure when the numbers read are a dual-scale dial's inner (secondary) scale and its main
    scale went unread: they sit deep inside the scale ring, or the crop model sees printed numbers
    further out that no read number explains. Answering with the inner scale would be a reading in
    another unit (a synthetic render read 11.0 on its 0..35 inner scale for 0.78 on its 0..2.5 main
    one; another read 323.7 on its 0..350 inner scale for 3.28 of 0..4)."""
    inliers = [m for m in model.markers if m.inlier]
    radius = float(np.median(normalized_radius(arc.ellipse, marker_centres(inliers))))
    if radius < SECONDARY_RADIUS:
        return StageFailure(STAGE, "secondary_scale_only",
                            f"the read numbers sit at {radius:.2f} of the scale ring's radius: an inner scale")
    if hints is not None and len(hints) and radius < INNER_RING:
        further = normalized_radius(arc.ellipse, np.asarray(hints, float).reshape(-1, 2)) > radius + RING_GAP
        if further.sum() >= 2:
            return StageFailure(STAGE, "secondary_scale_only",
                                f"{int(further.sum())} printed numbers further out than the read ones "
                                f"(at {radius:.2f} of the ring) were not read: the read scale is an inner one")
    return None


def _off_grid(arc: ScaleArc, model: ScaleModel, hints: np.ndarray) -> StageFailure | None:
    """A failure when the printed numbers the crop model sees do not sit on the scale's number grid.

    Numbers are printed at the values of the progression, so at the fitted scale each confident
    number centre must read (close to) a whole step, or a half, third or quarter step where numbers
    in between went unread. Misread numbers that happen to agree on a line ("-0.9" read "0", "-0.3"
    read "3" on a -1..0 vacuum dial) give a step that puts many printed numbers between grid lines.
    """
    values = np.unique([m.value for m in model.markers if m.inlier])
    if len(values) < 2 or len(hints) < GRID_MIN_HINTS:
        return None
    step = float(np.diff(values).min())
    angles = np.atleast_1d(arc.linear(dial_angle(arc.ellipse, np.asarray(hints, float).reshape(-1, 2), arc.centre)))
    read = np.array([model.value_at(float(a)) for a in angles])
    read = read[(read >= model.min_value - step / 4) & (read <= model.max_value + step / 4)]
    if len(read) < GRID_MIN_HINTS:
        return None
    shares = []
    for sub in step / np.arange(1, 5):  # up to three unread numbers between two read ones
        position = (read - values[0]) / sub
        shares.append(float(np.mean(np.abs(position - np.round(position)) > 0.25)))
    if min(shares) > GRID_OFF_SHARE:
        return StageFailure(STAGE, "numbers_off_grid",
                            f"{min(shares):.0%} of {len(read)} printed numbers fall between the steps of "
                            f"{step:g} the read numbers give")
    return None


def _spans_both(model: ScaleModel, rings: list[list[ScaleMarker]]) -> bool:
    """Whether at least two agreeing numbers of ``model`` come from each of the two rings."""
    from_outer = _from_ring(model, rings[0])
    return from_outer >= 2 and sum(m.inlier for m in model.markers) - from_outer >= 2


def _from_ring(model: ScaleModel, ring: list[ScaleMarker]) -> int:
    """How many agreeing numbers of ``model`` come from ``ring``."""
    boxes = {m.box for m in ring}
    return sum(m.box in boxes for m in model.markers if m.inlier)


def arc_at_values(arc: ScaleArc, scale: ScaleModel, low: float, high: float) -> ScaleArc | None:
    """``arc`` with its ends moved to the dial angles where ``scale``'s line gives ``low`` and ``high``
    (a configured range), or None when that span is implausible."""
    if scale.slope == 0:
        return None
    start, end = ((v - scale.intercept) / scale.slope for v in (low, high))
    if scale.slope < 0:
        start, end = end, start  # the arc's ends run clockwise; the values then fall
    if not MIN_SPAN <= end - start <= MAX_SPAN:
        return None
    start, end = float(wrap_to_pi(start)), float(wrap_to_pi(end))
    return replace(arc, start_angle=start, end_angle=end, zero_angle=wrap_angle(start, end), ends_inferred=True)


def primary_first(scales: list[ScaleModel], primary_unit: str | None) -> None:
    """Put the scale in ``primary_unit`` first (in place) when a dial has more than one."""
    if primary_unit and len(scales) > 1:
        scales.sort(key=lambda s: s.unit != primary_unit)


def across_zero(scale: ScaleModel) -> bool:
    """Whether ``scale`` runs from clearly below zero to clearly above it (a fit's 0 end lands a
    little off zero: -0.28 on a 0..300 dial)."""
    margin = RETRY_ZERO_MARGIN * (scale.max_value - scale.min_value)
    return scale.min_value < -margin and scale.max_value > margin
