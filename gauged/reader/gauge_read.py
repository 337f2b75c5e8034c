"""What one read of one gauge gives (:class:`GaugeRead`: every stage's result, the failure, the time per
stage), the scale it may be given (:class:`KnownScale`), and the OCR stage's interface to the pipeline."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from gauged.reader.failures import STAGE_ORDER
from gauged.reader.ocr.units import PrintedUnit
from gauged.reader.stages.crop import Crop
from gauged.reader.stages.ellipse import (
    ScaleArc,
)
from gauged.reader.stages.keypoints import CropKeypoints, Peaks
from gauged.reader.stages.needle import NeedleReading
from gauged.reader.stages.reading import Value, value_on
from gauged.types import Box, ScaleMarker, ScaleModel, StageFailure

MarkersRead = tuple[list[ScaleMarker], tuple[PrintedUnit, ...]]  # the OCR stage's numbers and the units printed


def _progress(read: "GaugeRead") -> int:
    """How far a read got: the index of its failing stage in :data:`STAGE_ORDER`, past the end when read."""
    if read.failure is None:
        return len(STAGE_ORDER)
    return STAGE_ORDER.index(read.failure.stage) if read.failure.stage in STAGE_ORDER else 0


class ScaleTextReader(Protocol):
    """The OCR stage as the pipeline sees it (implemented in :mod:`gauged.reader.stages.ocr`)."""

    def read_markers(self, crop: np.ndarray, arc: ScaleArc, hints: np.ndarray, detail: np.ndarray | None = None
                     ) -> MarkersRead | StageFailure:
        """Scale numbers (crop pixels, parsed values) and the units printed on the dial, or a failure
        of stage ``ocr``.
        ``detail`` is the crop's region at a higher resolution, for the text to be read from."""

    def reread_markers(self, crop: np.ndarray, arc: ScaleArc, hints: np.ndarray, detail: np.ndarray | None = None
                       ) -> list[ScaleMarker] | None:
        """A second look after the scale stage refused ``read_markers``' numbers: other markers, or None."""

    @property
    def has_number_net(self) -> bool:
        """Whether the number net is there (:meth:`hint_markers` and the retry need it)."""

    def hint_markers(self, frame: np.ndarray, crop: Crop, arc: ScaleArc, numbers: Peaks) -> list[ScaleMarker] | None:
        """A last look: the numbers the number net reads at the number peaks, or None."""


@dataclass(frozen=True)
class KnownScale:
    """A scale that needs no OCR: a configured prior (``min``/``max``/``unit``) or a locked scale."""

    min_value: float
    max_value: float
    unit: str | None
    direction: int = 1  # +1: the values rise clockwise (min at the start notch), -1 counter-clockwise


@dataclass
class GaugeRead:
    """Everything the pipeline learnt about one gauge in one image; ``failure`` is set when it refused."""

    box: Box
    score: float
    crop: Crop | None = None
    keypoints: CropKeypoints | None = None
    arc: ScaleArc | None = None
    needle: NeedleReading | None = None
    markers: list[ScaleMarker] = field(default_factory=list)
    scales: list[ScaleModel] = field(default_factory=list)
    units: tuple[PrintedUnit, ...] = ()  # the units read on the dial, best first
    value: Value | None = None
    failure: StageFailure | None = None
    seconds: dict[str, float] = field(default_factory=dict)
    look: str = "first"  # how the scale was found (gauged.reader.evidence.LOOKS)
    checked_notches: bool = False  # read on the notch check's peaks (the last look at a ring refused)

    @property
    def scale(self) -> ScaleModel | None:
        return self.scales[0] if self.scales else None

    @property
    def other_readings(self) -> list[tuple[float, ScaleModel]]:
        """The needle's value on each of the dial's other scales (a dual-scale dial's inner one, in its
        own unit) with that scale, when the dial was read."""
        if self.value is None or self.needle is None or self.arc is None:
            return []
        return [(value_on(self.needle, self.arc, scale), scale) for scale in self.scales[1:]]

    @property
    def unit(self) -> str | None:
        """The primary scale's unit; without a scale, the unit read best on the dial."""
        if self.scales:
            return self.scales[0].unit
        return self.units[0].unit if self.units else None


class _Timer:
    """Per-stage wall time for metrics and benchmarks; never feeds a result."""

    def __init__(self, sink: dict[str, float]):
        self.sink = sink

    def __call__(self, stage: str):
        return _Span(self.sink, stage)


class _Span:
    def __init__(self, sink: dict[str, float], stage: str):
        self.sink, self.stage = sink, stage

    def __enter__(self) -> None:
        self.start = time.perf_counter()

    def __exit__(self, *exc: object) -> None:
        self.sink[self.stage] = self.sink.get(self.stage, 0.0) + time.perf_counter() - self.start
