"""Where the gauges of an image are: the one place that turns the detector's output into the boxes read.

The daemon (:class:`gauged.daemon.camera_worker.CameraWorker`, for gauges configured without an ROI)
and ``gauged read`` / ``gauged eval readings`` (:meth:`gauged.reader.pipeline.GaugeReader.read_image`)
both locate gauges here and read each box with :meth:`~gauged.reader.pipeline.GaugeReader.read_box`
(``located=True``), so the evaluation scores the path the daemon runs.

Rules, in order:

- no detector, or the detector finds nothing: the whole image is one gauge (a photo cropped to a dial;
  the later stages refuse honestly when it is not a dial);
- a detection covering :data:`CLOSE_UP` of the image or more: a close-up, the whole image is the gauge;
- else every detection, best first.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from gauged.types import Box, GaugeDetection, StageFailure

GROW = 5.0  # a detection whose box holds no scale ring is read again in a box this many times larger
PHOTO_MARGIN = 0.06  # of the photo's sides: added around a photo read whole (a close-up), read again
CLOSE_UP = 0.35  # a detection covering this share of the image makes it a close-up of one gauge


class Detector(Protocol):
    def detect(self, image: np.ndarray) -> list[GaugeDetection] | StageFailure: ...


def whole_image(image: np.ndarray) -> Box:
    height, width = image.shape[:2]
    return (0.0, 0.0, float(width), float(height))


def _area(box: Box) -> float:
    return max(0.0, box[2] - box[0]) * max(0.0, box[3] - box[1])


def locate_gauges(detector: Detector | None, image: np.ndarray
                  ) -> tuple[list[GaugeDetection], StageFailure | None]:
    """The gauge boxes of (H, W, 3) ``image`` to read, best first (never empty), and the detector's
    failure when it found nothing (reported when the image read whole shows no dial either)."""
    whole = whole_image(image)
    if detector is None:
        return [GaugeDetection(whole, 1.0)], None
    detections = detector.detect(image)
    if isinstance(detections, StageFailure):
        return [GaugeDetection(whole, 0.0)], detections
    if not detections:
        return [GaugeDetection(whole, 0.0)], StageFailure("detect", "no_gauge", "the detector found no gauge")
    if any(_area(d.box) >= CLOSE_UP * _area(whole) for d in detections):
        return [GaugeDetection(whole, max(d.score for d in detections))], None
    return sorted(detections, key=lambda d: -d.score), None


def wider_boxes(image: np.ndarray, box: Box) -> list[Box]:
    """The larger boxes a located box with no scale ring is read in, in order: a box :data:`GROW`
    times larger (clipped to the image), the whole image, the whole image with a :data:`PHOTO_MARGIN`
    around it (as the crop model saw dials in training)."""
    height, width = image.shape[:2]
    whole = whole_image(image)
    m = PHOTO_MARGIN
    around = (-m * width, -m * height, (1 + m) * width, (1 + m) * height)
    if tuple(box) == whole:
        return [around]
    cx, cy = (box[0] + box[2]) / 2, (box[1] + box[3]) / 2
    half = GROW * max(box[2] - box[0], box[3] - box[1]) / 2
    grown = (max(0.0, cx - half), max(0.0, cy - half), min(float(width), cx + half), min(float(height), cy + half))
    return [b for b in (grown, whole, around) if b != tuple(box)]
