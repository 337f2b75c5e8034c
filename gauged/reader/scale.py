"""The scale of one gauge: angle -> value, from OCR'd scale numbers or from a configured prior.

From OCR (Reitsma et al., Sec. 3.5-3.6): the centres of the recognised numbers are projected onto the
scale ellipse, and a RANSAC line maps unwrapped dial angle to value
(:func:`gauged.geometry.scale_fit.fit_scale_model`). Markers inside and outside the scale ellipse are
fitted separately (dials with a bar and a psi scale); the primary scale is the configured unit's, else
the one with more inliers.

From a prior (``scale: {min, max}`` in the config): the value runs linearly from ``min`` at the start
notch to ``max`` at the end notch, no OCR needed.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from gauged.geometry.angles import unwrap
from gauged.geometry.dial_frame import dial_angle
from gauged.geometry.scale_fit import fit_scale_model, marker_centres, split_markers
from gauged.reader.ellipse import ScaleArc
from gauged.types import ScaleMarker, ScaleModel, StageFailure

STAGE = "scale"
REASONS = ("too_few_markers", "degenerate_fit", "wrong_slope_sign", "too_few_inliers", "scale_not_covered")
COVER_STEPS = 1.5  # the read numbers must reach within this many number steps of both scale ends


def scale_from_prior(arc: ScaleArc, min_value: float, max_value: float, unit: str | None) -> ScaleModel:
    """Linear scale from ``min_value`` at the start notch to ``max_value`` at the end notch."""
    start = unwrap(arc.start_angle, arc.zero_angle)
    end = unwrap(arc.end_angle, arc.zero_angle)
    slope = (max_value - min_value) / (end - start)
    return ScaleModel(arc.ellipse, slope, min_value - slope * start, arc.zero_angle, min_value, max_value, unit)


def fit_scales(arc: ScaleArc, markers: Sequence[ScaleMarker], unit: str | None = None,
               min_inliers: int = 3) -> list[ScaleModel] | StageFailure:
    """Fit one scale per marker group (inside / outside the scale ellipse), best first.

    A scale must have ``min_inliers`` consistent numbers and increase clockwise. Returns the failure of
    the larger group when no group yields a scale.
    """
    # Number angles in the same corrected frame as the needle's (ScaleArc.linear).
    markers = list(markers)
    if markers:
        angles = arc.linear(dial_angle(arc.ellipse, marker_centres(markers), arc.centre))
        markers = [replace(m, angle=float(a)) for m, a in zip(markers, angles, strict=True)]
    groups = sorted((g for g in split_markers(arc.ellipse, list(markers)) if g), key=len, reverse=True)
    if not groups:
        return StageFailure(STAGE, "too_few_markers", "no scale number was read")
    scales: list[ScaleModel] = []
    first_failure: StageFailure | None = None
    for group in groups:
        model = fit_scale_model(arc.ellipse, group, arc.start_angle, arc.end_angle, unit=unit, centre=arc.centre,
                                min_inliers=min(min_inliers, max(2, len(group))), expected_sign=1)
        if isinstance(model, StageFailure):
            first_failure = first_failure or model
            continue
        if model.inliers < min_inliers:
            first_failure = first_failure or StageFailure(
                STAGE, "too_few_inliers", f"{model.inliers} consistent numbers, need {min_inliers}")
            continue
        uncovered = _uncovered(model)
        if uncovered is not None:
            first_failure = first_failure or uncovered
            continue
        scales.append(model)
    if not scales:
        assert first_failure is not None
        return first_failure
    return sorted(scales, key=lambda s: s.inliers, reverse=True)


def _uncovered(model: ScaleModel) -> StageFailure | None:
    """A failure when the consistent numbers leave an end of the scale far from any of them.

    Printed numbers run from one end of a scale to the other, so the values the fit gives at the two
    end notches lie within a number step or so of a read number. When they do not, the ends or the
    numbers are wrong (a false gap taken for the scale's, misread digits that happen to agree):
    extrapolating would answer with a wild value, so the scale is refused instead.
    """
    values = sorted({m.value for m in model.markers if m.inlier})
    if len(values) < 2:
        return None
    step = float(np.median(np.diff(values)))
    low_gap, high_gap = values[0] - model.min_value, model.max_value - values[-1]
    if max(low_gap, high_gap) > COVER_STEPS * step:
        return StageFailure(STAGE, "scale_not_covered",
                            f"numbers {values[0]:g}..{values[-1]:g} (step {step:g}) do not reach the scale ends "
                            f"{model.min_value:.4g}..{model.max_value:.4g}")
    return None
