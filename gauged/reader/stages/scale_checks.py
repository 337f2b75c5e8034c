"""The checks a scale fitted through the numbers read must pass: one function per wrong answer it prevents.

Each takes the fitted :class:`~gauged.types.ScaleModel` and returns a
:class:`~gauged.types.StageFailure` of the scale stage naming what is wrong, or None. :data:`CHECKS`
is the table the scale stage runs, in order, with the wrong reading each check prevents.
"""

from __future__ import annotations

import itertools
import math
import re

import numpy as np

from gauged.geometry.angles import unwrap
from gauged.geometry.scale_fit import (
    SCALE_STAGE,
    fit_angle_value,
)
from gauged.reader.ocr.numbers import nice_step, printed_decimal, read_as_digits, read_whole, round_step
from gauged.types import ScaleModel, StageFailure

STAGE = SCALE_STAGE


STEP_TOLERANCE = 0.1  # of the smallest step: differences of agreeing numbers must be whole multiples of it
DECIMAL_MATCH = 0.3  # of a number step: a decimal number x10 this close to the line betrays dropped points
COVER_STEPS = 2.5  # the read numbers must reach within this many number steps of both scale ends (1.5
# refused 26 of 300 synthetic renders, 14 of which 2.5 reads within 2.1%; the bunched-numbers case stays refused)
COVER_STEPS_SURE = 3.5  # ... or this many when SURE_NUMBERS distinct numbers read as digits agree (dev sets: 300
# synthetic + 21 real, 5 more reads all within 1.2%; every wild read had 3 numbers or a 4.8-step gap)
SURE_NUMBERS = 4
GRID_MAX_STEPS = 50  # round steps between a scale's lowest and highest agreeing number (a dial prints ~5-20)
TURN_TOLERANCE = math.radians(6.0)  # dial angle: how near a number a turn on must lie to where the line puts it
TURN_STEPS = 2.5  # ... and how many of the agreeing numbers' steps past the fitted ends its value may be
PAST_END = 0.5  # of the fitted range: an agreeing number this far past a scale end refutes the fit (1,308 reads
# of the synthetic dev, fresh and held-out sets and the 21 real photos: right ones <= 0.35, the one wild read 1.58)


def agreeing_digit_values(model: ScaleModel) -> list[float]:
    """The values of ``model``'s agreeing numbers read whole as digits (:func:`read_whole`: no letter
    taken for one, no dangling point): the evidence the scale checks and the minimum count."""
    return [m.value for m in model.markers if m.inlier and read_whole(m.text)]


def _rival(model: ScaleModel) -> StageFailure | None:
    """A failure when the numbers the fit left out make another line as well supported as its own.

    Two lines with as many agreeing numbers each (sharing at most one, a "0" both start from) mean the
    evidence does not say which scale the dial has: "0, 10, 15, 25" (trailing zeros unread) beside
    "0, 50, 200, 300" on a 0..300 dial gave 22.6 for 224.6 (a held-out render).
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


def _outvoted(model: ScaleModel) -> StageFailure | None:
    """A failure when the line leaves out at least as many of its ring's read numbers as it explains.

    A line that explains no more of the numbers than it contradicts is no evidence of the scale: a few
    misreads fall on some line by chance. "4, 8, 24" of a 0..16 dial's "4, 6, 8, 10, 12, 14" (read
    "4, 8, 1, 10, 22, 24") made a line twice too steep, 67% off, with "1, 10, 22" left out (a
    held-out render). On the held-out sets and the real photos no right reading left out as many
    numbers as it explained.
    """
    left_out = sum(1 for m in model.markers if not m.inlier and m.angle is not None)
    if left_out >= model.inliers:
        return StageFailure(STAGE, "numbers_outvoted", f"the line explains {model.inliers} read numbers "
                            f"and leaves out {left_out}")
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
    of the smallest), at most :data:`GRID_MAX_STEPS` of them from first to last? Fewer than three
    always are.

    Any difference is a whole multiple of a small enough one: "0.4, 1, 1867" (a number read off the
    face beside two of a 0..0.6 dial) step by 0.6 three thousand times, and their line read 1462 for
    0.01. A dial prints its numbers a few steps apart."""
    if len(values) < 3:
        return True
    diffs = np.diff(values)
    multiples = diffs / diffs.min()
    return bool(np.abs(multiples - np.round(multiples)).max() <= STEP_TOLERANCE
                and multiples.sum() <= GRID_MAX_STEPS + STEP_TOLERANCE)


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
    made a scale of 744..1231 and answered 1132 for 4.65 (a held-out render).
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
    (a synthetic render).
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
    read with its decimals (:func:`gauged.reader.ocr.numbers.printed_decimal`: "0.5", or "1.0"
    beside "5, 15, 25" read for "0.5, 1.5, 2.5"), and that number times 10 or 100 lies where the
    line puts it, the scale is a decimal one read wrong: it is refused.
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
        if marker.inlier or marker.angle is None or not printed_decimal(marker):
            continue
        expected = model.value_at(marker.angle)
        # a tick read as a minus sign: "-0.5" where the line puts 5
        for value, factor in itertools.product({marker.value, abs(marker.value)}, (10.0, 100.0)):
            if abs(value * factor - expected) <= DECIMAL_MATCH * step:
                return StageFailure(STAGE, "dropped_decimal_point",
                                    f"whole numbers agree, but {marker.text!r} read where the line puts "
                                    f"{expected:.3g}: the scale's decimal points were dropped")
    return None


# The table the scale stage runs on every fitted line, in order: (check, the wrong answer it prevents).
CHECKS = (
    (_irregular, "a misread number near the line bends it: agreeing numbers that are no progression (10, 150, 200)"),
    (_off_printed_grid, "agreeing misreads that step by no round step (1, 2, 2.5 or 5 times a power of ten)"),
    (_past_ends, "ends fitted inside the scale: an agreeing number well past a fitted end"),
    (_a_turn_on, "a false gap taken for the scale's: a number where the line, a turn on, would print it"),
    (_uncovered, "wild extrapolation: read numbers far from an end of the scale"),
    (_dropped_decimal_point, "a scale 10x too large: decimal points the OCR dropped"),
    (_rival, "two lines as well supported by the numbers: the evidence does not say which is the scale"),
    (_outvoted, "a line of chance misreads: as many read numbers left out as explained"),
)
