"""The picture a person looks at to see why a gauge was read as it was (``--debug-dir``, annotated MCAP).

Drawn on the gauge crop, enlarged: the scale ellipse, start (green) and end (red) notches, major
notches, the needle line and its hit on the scale, each OCR number with its parsed value (inliers
green, outliers red), and the final value or the failing stage and reason.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from gauged.geometry.dial_frame import point_at_dial_angle
from gauged.reader.gauge_read import GaugeRead

GREEN, RED, BLUE, YELLOW, WHITE, BLACK = (60, 200, 60), (40, 40, 230), (230, 120, 30), (0, 220, 255), (255, 255, 255), (0, 0, 0)


def _pt(point, scale: float) -> tuple[int, int]:
    return (int(round(point[0] * scale * 16)), int(round(point[1] * scale * 16)))


def _text(image: np.ndarray, text: str, origin: tuple[int, int], color, size: float = 0.5) -> None:
    cv2.putText(image, text, origin, cv2.FONT_HERSHEY_SIMPLEX, size, BLACK, 3, cv2.LINE_AA)
    cv2.putText(image, text, origin, cv2.FONT_HERSHEY_SIMPLEX, size, color, 1, cv2.LINE_AA)


def annotate(read: GaugeRead, out_size: int = 512) -> np.ndarray:
    """(out_size, out_size + footer, 3) uint8 BGR picture of ``read`` on its crop."""
    if read.crop is None:
        canvas = np.zeros((out_size, out_size, 3), np.uint8)
        scale = 1.0
    else:
        scale = out_size / read.crop.image.shape[0]
        canvas = cv2.resize(read.crop.image, (out_size, out_size), interpolation=cv2.INTER_LINEAR)
    shift = 4  # cv2 drawing with sub-pixel precision: coordinates are multiplied by 16
    if read.keypoints is not None:
        for point in read.keypoints.major.points:
            cv2.circle(canvas, _pt(point, scale), 4 * 16, YELLOW, 1, cv2.LINE_AA, shift)
        for peaks, color in ((read.keypoints.start, GREEN), (read.keypoints.end, RED)):
            if len(peaks):
                cv2.circle(canvas, _pt(peaks.points[0], scale), 7 * 16, color, 2, cv2.LINE_AA, shift)
    if read.arc is not None:
        e = read.arc.ellipse
        ts = np.linspace(0, 2 * math.pi, 120)
        ring = point_at_dial_angle(e, ts, read.arc.centre) * scale
        cv2.polylines(canvas, [np.round(ring * 16).astype(np.int32)], True, BLUE, 1, cv2.LINE_AA, shift)
    if read.needle is not None and read.arc is not None:
        hit = point_at_dial_angle(read.arc.ellipse, read.needle.angle, read.arc.centre)[0]
        cv2.line(canvas, _pt(read.arc.centre, scale), _pt(hit, scale), RED, 2, cv2.LINE_AA, shift)
        cv2.circle(canvas, _pt(hit, scale), 5 * 16, RED, -1, cv2.LINE_AA, shift)
    for marker in read.markers:
        x0, y0, x1, y1 = (v * scale for v in marker.box)
        color = GREEN if marker.inlier else RED if marker.inlier is False else WHITE
        cv2.rectangle(canvas, (int(x0), int(y0)), (int(x1), int(y1)), color, 1)
        _text(canvas, f"{marker.value:g}", (int(x0), int(y0) - 3), color, 0.45)
    for scale_model in read.scales:
        for marker in scale_model.markers:
            if marker.inlier is not None:
                x0, y0, x1, y1 = (v * scale for v in marker.box)
                cv2.rectangle(canvas, (int(x0), int(y0)), (int(x1), int(y1)), GREEN if marker.inlier else RED, 2)
    footer = np.zeros((48, out_size, 3), np.uint8)
    if read.value is not None:
        unit = read.unit or ""
        _text(footer, f"{read.value.value:.4g} {unit}  conf {read.value.confidence:.2f}", (8, 30), GREEN, 0.7)
    elif read.failure is not None:
        _text(footer, f"refused: {read.failure.stage}/{read.failure.reason}", (8, 20), RED, 0.55)
        _text(footer, read.failure.detail[:70], (8, 40), WHITE, 0.4)
    return np.vstack([canvas, footer])
