"""Scales that run all the way round the dial (dial indicators, revolution counters).

Such a dial has no gap: its numbers (0, 1, ..., 9 with 10 back at 0) are evenly spaced over the whole
circle, so the ellipse stage's ends, inferred from the largest gap between notches, fall inside the
scale and cut its numbers in two. The numbers themselves say when a dial is one: a run of them on one
line whose full turn is a whole number of their steps. Its model reads values in
``[min - step / 2, max - step / 2)``, so a needle resting a hair before the zero reads a small
negative value, not nearly the maximum.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from gauged.geometry.angles import wrap_to_pi
from gauged.geometry.scale_fit import DEFAULT_ANGLE_TOL as ANGLE_TOL
from gauged.reader.ocr.numbers import read_as_digits
from gauged.reader.stages.ellipse import ScaleArc
from gauged.types import ScaleMarker, ScaleModel

MIN_NUMBERS = 6  # agreeing numbers read as digits a full-circle scale needs
MIN_STEPS = 6  # steps per turn: fewer is a sector scale whose gap went unseen, not a full circle
TURN_TOLERANCE = 0.03  # of a step: how far a turn may be from a whole number of steps


def fit_full_circle(arc: ScaleArc, markers: Sequence[ScaleMarker], unit: str | None) -> ScaleModel | None:
    """The full-circle scale of ``markers`` (dial angles set, as :func:`gauged.reader.stages.scale.fit_scales`
    sets them), or None when they do not make one.

    Only a dial whose ends were inferred can be one (found end notches mean a gap). Every pair of
    numbers read as digits proposes a line, value per radian clockwise; the line with the most
    agreeing numbers (within :data:`ANGLE_TOL`, angles compared modulo a turn) must hold
    :data:`MIN_NUMBERS` numbers with distinct values in steps of one common step, its turn must be a
    whole number of steps (at least :data:`MIN_STEPS`), and the numbers must cover the turn but for
    the one at the seam and one more.
    """
    if not arc.ends_inferred:
        return None
    usable = [m for m in markers if m.angle is not None and read_as_digits(m.text)]
    if len(usable) < MIN_NUMBERS:
        return None
    theta = np.array([m.angle for m in usable], float)
    value = np.array([m.value for m in usable], float)
    best, best_slope = np.zeros(len(usable), bool), 0.0
    for i in range(len(usable)):
        for j in range(len(usable)):
            turned = (theta[j] - theta[i]) % (2 * math.pi)
            if value[j] <= value[i] or turned < 1e-3:
                continue
            slope = (value[j] - value[i]) / turned
            inliers = np.abs(wrap_to_pi(theta - (theta[i] + (value - value[i]) / slope))) <= ANGLE_TOL
            if inliers.sum() > best.sum():
                best, best_slope = inliers, slope
    kept = np.sort(value[best])
    if len(kept) < MIN_NUMBERS or len(np.unique(kept)) < len(kept):
        return None
    step = float(np.min(np.diff(kept)))
    if np.abs((kept - kept[0]) / step - np.round((kept - kept[0]) / step)).max() > TURN_TOLERANCE:
        return None
    # Refit on the agreeing numbers, their angles unwrapped along the line.
    anchor = int(np.flatnonzero(best)[0])
    predicted = theta[anchor] + (value[best] - value[anchor]) / best_slope
    along = predicted + wrap_to_pi(theta[best] - predicted)
    fitted = float(np.polyfit(along, value[best], 1)[0])
    steps = round(2 * math.pi * fitted / step)
    if steps < MIN_STEPS or abs(2 * math.pi * fitted / step - steps) > TURN_TOLERANCE * steps:
        return None
    # A turn is exactly that many steps: the slope follows from it, and only the phase is fitted.
    turn = steps * step
    slope = turn / (2 * math.pi)
    intercept = float(np.mean(value[best] - slope * along))
    # 0..9 span 9 steps of a 10-step turn; the one at the seam and one more unread leave 7.
    if not (steps - 3) * step - TURN_TOLERANCE * step <= kept[-1] - kept[0] < turn - 0.5 * step:
        return None
    low = math.floor(kept[0] / turn + 1e-9) * turn  # 0 on a 0..10 dial whose "0" went unread
    residual = value[best] - (slope * along + intercept)
    agreeing = {id(m) for m, ok in zip(usable, best, strict=True) if ok}
    return ScaleModel(ellipse=arc.ellipse, slope=slope, intercept=intercept,
                      zero_angle=(low - 0.5 * step - intercept) / slope,  # the seam, half a step before the minimum
                      min_value=low, max_value=low + turn, unit=unit, inliers=len(kept),
                      rms_value=float(np.sqrt(np.mean(residual**2))),
                      markers=tuple(replace(m, inlier=id(m) in agreeing) for m in markers), full_circle=True)
