"""The core value types of gauged, and its one coordinate convention.

Coordinate convention (used by every module; nothing else restates it):

- Images are ``numpy.ndarray`` of shape ``(H, W, 3)`` and dtype ``uint8`` in **BGR** order (OpenCV's),
  or ``(H, W)`` uint8 for single-channel maps.
- Pixel coordinates are ``(x, y)`` floats: ``x`` to the right, ``y`` **down**, origin at the top-left
  corner of the top-left pixel, so the centre of pixel ``(i, j)`` (row ``j``, column ``i``) is at
  ``(i + 0.5, j + 0.5)``. Arrays of points have shape ``(N, 2)`` with columns ``x, y``.
- Angles are radians. An image angle is ``atan2(dy, dx)`` in these coordinates, so with ``y`` down a
  *positive* angle turns **clockwise** on screen. Gauge scales run clockwise on almost every dial,
  so angle and value grow together.
- Boxes are ``(x0, y0, x1, y1)`` with ``x0 < x1`` and ``y0 < y1``, in pixels.
- Times are integer nanoseconds taken from the frame (``stamp_ns``), never the wall clock inside the
  reader, so replaying a recording reproduces the same readings bit for bit.

Expected algorithmic failures are values, not exceptions: a stage returns its result or a
:class:`StageFailure`, which is falsy and names the stage and a machine-readable reason.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

Box = tuple[float, float, float, float]
Point = tuple[float, float]


class Quality(str, enum.Enum):
    """Quality of a published reading (the DESIGN contract's four values)."""

    GOOD = "good"  # fresh and plausible
    UNCERTAIN = "uncertain"  # held or recovering: last valid value with reasons
    BAD = "bad"  # recent frames fail; value is null
    STALE = "stale"  # no frame or no valid reading for stale_after_s


@dataclass(frozen=True, slots=True)
class StageFailure:
    """An expected failure of one reader stage. Falsy, so ``if not result:`` catches it.

    ``stage`` names the stage (``detect``, ``keypoints``, ``ellipse``, ``needle``, ``ocr``, ``scale``,
    ``reading``, ...), ``reason`` is a short machine-readable token from a fixed set per stage (it is
    used as a metric label), and ``detail`` is free text for people (never a metric label).
    """

    stage: str
    reason: str
    detail: str = ""

    def __bool__(self) -> bool:
        return False

    def to_dict(self) -> dict[str, str]:
        return {"stage": self.stage, "reason": self.reason, "detail": self.detail}


@dataclass(frozen=True, slots=True)
class Frame:
    """One camera image. ``image`` is (H, W, 3) uint8 BGR; ``stamp_ns`` is the capture time."""

    image: np.ndarray
    stamp_ns: int
    camera: str
    frame_id: int

    @property
    def size(self) -> tuple[int, int]:
        """(width, height) in pixels."""
        return int(self.image.shape[1]), int(self.image.shape[0])


@dataclass(frozen=True, slots=True)
class Ellipse:
    """An ellipse in pixel coordinates.

    ``(cx, cy)`` is the centre, ``a >= b > 0`` the semi-axes in pixels, ``theta`` the angle of the
    major axis from +x in radians, normalised to ``[0, pi)``. The point at parameter ``t`` is
    ``c + a cos t * u + b sin t * v`` with ``u = (cos theta, sin theta)``, ``v = (-sin theta, cos theta)``.
    """

    cx: float
    cy: float
    a: float
    b: float
    theta: float

    @property
    def center(self) -> Point:
        return (self.cx, self.cy)

    def point_at(self, t: np.ndarray | float) -> np.ndarray:
        """Points at parametric angles ``t`` (radians); returns shape (..., 2)."""
        t = np.asarray(t, dtype=float)
        ct, st = math.cos(self.theta), math.sin(self.theta)
        x = self.cx + self.a * np.cos(t) * ct - self.b * np.sin(t) * st
        y = self.cy + self.a * np.cos(t) * st + self.b * np.sin(t) * ct
        return np.stack([x, y], axis=-1)

    def scaled(self, factor: float) -> Ellipse:
        """The concentric ellipse with both semi-axes multiplied by ``factor``."""
        return Ellipse(self.cx, self.cy, self.a * factor, self.b * factor, self.theta)

    def to_dict(self) -> dict[str, float]:
        return {"cx": self.cx, "cy": self.cy, "a": self.a, "b": self.b, "theta": self.theta}


@dataclass(frozen=True, slots=True)
class GaugeDetection:
    """A gauge face found in a frame: its box, detector score and, when known, the face ellipse."""

    box: Box
    score: float
    ellipse: Ellipse | None = None


@dataclass(frozen=True, slots=True)
class NeedleLine:
    """The needle as a line: a point on it, a unit direction from tail (pivot side) to tip.

    ``tip`` is the farthest needle pixel along ``direction``; ``rms_px`` is the orthogonal RMS
    residual of the fit and ``support`` the number of pixels it used.
    """

    point: Point
    direction: Point
    tip: Point
    rms_px: float = 0.0
    support: int = 0

    @property
    def angle(self) -> float:
        """Raw image angle of the tail-to-tip direction, radians in (-pi, pi]. Not a dial angle: read
        the scale with :func:`gauged.geometry.needle_line.needle_dial_angle`."""
        return math.atan2(self.direction[1], self.direction[0])


@dataclass(frozen=True, slots=True)
class ScaleMarker:
    """A number printed on the scale: OCR text, parsed value, box, and its angle on the scale ellipse.

    ``angle`` is the dial angle (radians, :func:`gauged.geometry.dial_frame.dial_angle`) of the
    number's centre, or ``None`` before projection. ``inlier`` is set by the RANSAC fit.
    """

    text: str
    value: float
    box: Box
    angle: float | None = None
    inlier: bool | None = None
    score: float = 1.0
    net_minus: bool = False  # the nets' evidence leans to a minus before its digits (counted or not: minus_sign)


@dataclass(frozen=True, slots=True)
class ScaleModel:
    """The scale of one gauge: where it lies and how angle maps to value.

    ``value = slope * unwrap(angle) + intercept``, where ``unwrap`` maps a dial angle
    (:func:`gauged.geometry.dial_frame.dial_angle`) into the
    interval ``[zero_angle, zero_angle + 2 pi)`` with ``zero_angle`` the wrap-around angle (the
    midpoint of the gap between the end and start notches, outside the scale).
    """

    ellipse: Ellipse
    slope: float
    intercept: float
    zero_angle: float
    min_value: float
    max_value: float
    unit: str | None = None
    inliers: int = 0
    rms_value: float = 0.0
    markers: tuple[ScaleMarker, ...] = ()
    full_circle: bool = False  # no gap: the scale runs all the way round (gauged.reader.stages.full_circle)

    def unwrap(self, angle: float) -> float:
        """Map a dial angle into ``[zero_angle, zero_angle + 2 pi)``."""
        return self.zero_angle + (angle - self.zero_angle) % (2.0 * math.pi)

    def value_at(self, angle: float) -> float:
        return self.slope * self.unwrap(angle) + self.intercept

    def to_dict(self) -> dict[str, Any]:
        return {"min": self.min_value, "max": self.max_value, "unit": self.unit}


@dataclass(frozen=True, slots=True)
class RawReading:
    """What the reader says about one gauge in one frame, before smoothing.

    Either ``value`` is a float and ``failure`` is ``None``, or ``value`` is ``None`` and ``failure``
    says which stage refused and why.
    """

    gauge: str
    camera: str
    stamp_ns: int
    value: float | None
    unit: str | None
    confidence: float
    scale: ScaleModel | None = None
    failure: StageFailure | None = None
    needle_angle: float | None = None


@dataclass(frozen=True, slots=True)
class ScaleInfo:
    """The published summary of a gauge's scale (the ``scale`` field of the reading contract)."""

    min: float | None
    max: float | None
    unit: str | None
    locked: bool = False

    def to_dict(self) -> dict[str, Any]:
        return {"min": self.min, "max": self.max, "unit": self.unit, "locked": self.locked}


@dataclass(frozen=True, slots=True)
class Reading:
    """A published reading: the DESIGN contract of ``<prefix>/<gauge>/reading``."""

    gauge: str
    camera: str
    stamp_ns: int
    value: float | None
    raw_value: float | None
    unit: str | None
    quality: Quality
    confidence: float
    scale: ScaleInfo
    failure: StageFailure | None = None
    reasons: tuple[str, ...] = field(default=())

    def to_dict(self) -> dict[str, Any]:
        return {
            "gauge": self.gauge,
            "camera": self.camera,
            "stamp_ns": self.stamp_ns,
            "value": self.value,
            "raw_value": self.raw_value,
            "unit": self.unit,
            "quality": self.quality.value,
            "confidence": self.confidence,
            "scale": self.scale.to_dict(),
            "failure": None if self.failure is None else self.failure.to_dict(),
            "reasons": list(self.reasons),
        }


class FrameOutcome(str, enum.Enum):
    """What one call did with its input; the alarms use it to tell fresh values from held ones."""

    ACCEPTED = "accepted"  # a measurement passed the checks and updated the value
    REJECTED = "rejected"  # a measurement was an outlier or implausible
    FAILED = "failed"  # the reader gave no usable value
    NO_FRAME = "no_frame"  # a tick: time passed without a frame
