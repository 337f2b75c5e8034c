"""Every (stage, reason) a reader failure can carry: the fixed label set of the failure metrics."""

from __future__ import annotations

from gauged.reader.stages import (
    crop,
    detect,
    ellipse,
    keypoints,
    needle,
    ocr,
    reading,
    scale,
)

OCR_UNAVAILABLE = "ocr_unavailable"  # the pipeline's own: no OCR engine and no configured scale


_STAGE_MODULES = (detect, crop, keypoints, ellipse, needle, ocr, scale, reading)
STAGE_ORDER = tuple(module.STAGE for module in _STAGE_MODULES)  # the stages in pipeline order


def failure_pairs() -> tuple[tuple[str, str], ...]:
    """All pairs, in pipeline order, so counters can be created at zero before the first failure."""
    pairs = [(module.STAGE, reason) for module in _STAGE_MODULES for reason in module.REASONS]
    return (*pairs, (ocr.STAGE, OCR_UNAVAILABLE))
