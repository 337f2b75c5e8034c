"""Overlays of the readings on the camera image: ``foxglove.ImageAnnotations`` messages (JSON).

Foxglove and Lichtblick draw these over an image in the Image panel, with no plugin, when the
overlay's timestamp equals the image's: every timestamp here is the frame's ``stamp_ns``, which is
the image message's own time (:mod:`gauged.sources.mcap_source`, :mod:`gauged.sources.zenoh_source`).
Coordinates are the full camera image's pixels with the origin at the top-left corner of the
top-left pixel, which is both gauged's convention (:mod:`gauged.types`) and Foxglove's; the reader
works on a crop, and :meth:`~gauged.reader.stages.crop.Crop.points_to_frame` maps its geometry back.

One gauge's overlay (:func:`gauge_annotations`):

- the scale ellipse, a ``LINE_LOOP`` of :data:`ELLIPSE_POINTS` points;
- the scale ends, ``POINTS``: the start green, the end red;
- the needle, a ``LINE_STRIP`` from the pivot (the dial centre the angles are measured from) to the
  point where it meets the scale ellipse, which is where the value is read;
- a text at the top-left corner of the gauge's box: ``<gauge>: <value> <unit>``, coloured by
  quality (good green, uncertain amber, bad or stale red).

A refused frame shows what the reader had found before it refused, all in red: the gauge's box
(a ``LINE_LOOP``), so that the refusal is visibly about that dial, the ellipse and ends when they
were fitted, the needle when it was found; and the text names the refusal, ``[stage/reason]``,
after the value the tracker still holds, if any. A gauge without a box (not detected in this
frame) has an empty overlay: nothing says where in the image it would be. Every frame gets its
messages, empty or not, so that a viewer never keeps an overlay that no longer holds.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from gauged.geometry.dial_frame import point_at_dial_angle
from gauged.types import Quality, Reading, StageFailure

if TYPE_CHECKING:
    from gauged.reader.gauge_read import GaugeRead

ELLIPSE_POINTS = 48  # a 48-gon strays at most 0.2 % of the radius from the ellipse (0.3 px at r = 150)
POINTS, LINE_LOOP, LINE_STRIP = 1, 2, 3  # foxglove.PointsAnnotationType

Color = dict[str, float]


def _color(r: float, g: float, b: float, a: float = 1.0) -> Color:
    return {"r": r, "g": g, "b": b, "a": a}


GREEN, AMBER, RED, BLUE = _color(0.2, 0.85, 0.3), _color(1.0, 0.7, 0.1), _color(0.95, 0.2, 0.2), _color(0.2, 0.55, 1.0)
NONE, BACKDROP = _color(0.0, 0.0, 0.0, 0.0), _color(0.0, 0.0, 0.0, 0.6)
QUALITY_COLORS = {Quality.GOOD: GREEN, Quality.UNCERTAIN: AMBER, Quality.BAD: RED, Quality.STALE: RED}


class GaugeResult(Protocol):
    """One gauge's result of one frame, as the daemon has it (:class:`gauged.daemon.gauge_runner.GaugeOutput`)."""

    reading: Reading
    read: GaugeRead | None
    failure: StageFailure | None


def timestamp(stamp_ns: int) -> dict[str, int]:
    """A ``time`` of Foxglove's schemas: ``{sec, nsec}``."""
    sec, nsec = divmod(int(stamp_ns), 1_000_000_000)
    return {"sec": sec, "nsec": nsec}


def image_annotations(stamp_ns: int, points: Sequence[dict[str, Any]] = (),
                      texts: Sequence[dict[str, Any]] = ()) -> dict[str, Any]:
    """A ``foxglove.ImageAnnotations`` message (no circles: ellipses are drawn as polylines)."""
    return {"timestamp": timestamp(stamp_ns), "circles": [], "points": list(points), "texts": list(texts)}


def merge(stamp_ns: int, messages: Iterable[Mapping[str, Any]]) -> dict[str, Any]:
    """The overlays of several gauges as one message (one camera's frame)."""
    messages = list(messages)
    return image_annotations(stamp_ns, [p for m in messages for p in m["points"]],
                             [t for m in messages for t in m["texts"]])


def _points(stamp_ns: int, kind: int, xy: np.ndarray, color: Color, thickness: float,
            colors: Sequence[Color] = ()) -> dict[str, Any]:
    return {"timestamp": timestamp(stamp_ns), "type": kind,
            "points": [{"x": round(float(x), 2), "y": round(float(y), 2)} for x, y in np.asarray(xy).reshape(-1, 2)],
            "outline_color": color, "outline_colors": list(colors), "fill_color": NONE if kind != POINTS else color,
            "thickness": thickness}


def _label(gauge: str, reading: Reading, failure: StageFailure | None) -> str:
    if reading.value is not None and math.isfinite(reading.value):
        text = f"{gauge}: {reading.value:.4g} {reading.unit or ''}".rstrip()
    else:
        text = f"{gauge}: {reading.quality.value}"
    return text if failure is None else f"{text} [{failure.stage}/{failure.reason}]"


def gauge_annotations(result: GaugeResult, stamp_ns: int, image_size: tuple[int, int]) -> dict[str, Any]:
    """The overlay of one gauge on the frame of time ``stamp_ns`` and ``image_size`` (width, height) px
    (see module docs)."""
    reading, read, failure = result.reading, result.read, result.failure
    if read is None:
        return image_annotations(stamp_ns)
    refused = failure is not None
    color = RED if refused else QUALITY_COLORS[reading.quality]
    x0, y0, x1, y1 = (float(v) for v in read.box)
    side = max(1.0, min(x1 - x0, y1 - y0))
    thickness = round(max(1.5, side / 120), 1)
    points = []
    if refused:
        points.append(_points(stamp_ns, LINE_LOOP, np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]]), RED, thickness))
    if read.crop is not None and read.arc is not None:
        arc, to_frame = read.arc, read.crop.points_to_frame
        ring = point_at_dial_angle(arc.ellipse, np.linspace(0, 2 * math.pi, ELLIPSE_POINTS, endpoint=False), arc.centre)
        points.append(_points(stamp_ns, LINE_LOOP, to_frame(ring), RED if refused else BLUE, thickness))
        ends = point_at_dial_angle(arc.ellipse, np.array([arc.start_angle, arc.end_angle]), arc.centre)
        points.append(_points(stamp_ns, POINTS, to_frame(ends), RED if refused else GREEN, 3 * thickness,
                              [RED if refused else GREEN, RED]))
        if read.needle is not None:
            tip = point_at_dial_angle(arc.ellipse, read.needle.angle, arc.centre)
            needle = to_frame(np.vstack([np.asarray(arc.centre, float).reshape(1, 2), tip]))
            points.append(_points(stamp_ns, LINE_STRIP, needle, color, 1.5 * thickness))
    font = round(min(48.0, max(12.0, side / 10)), 1)
    label = _label(reading.gauge, reading, failure)
    width, height = image_size
    # The position is the text's bottom-left corner: just above the box, kept inside the image (a
    # character is about 0.6 font sizes wide).
    position = {"x": round(max(0.0, min(x0, width - 0.6 * font * len(label))), 2),
                "y": round(min(max(y0 - 0.25 * font, font), float(height)), 2)}
    text = {"timestamp": timestamp(stamp_ns), "position": position, "text": label, "font_size": font,
            "text_color": color, "background_color": BACKDROP}
    return image_annotations(stamp_ns, points, [text])


def frame_annotations(results: Iterable[GaugeResult], stamp_ns: int, image_size: tuple[int, int]
                      ) -> dict[str, dict[str, Any]]:
    """Each gauge's overlay of one frame, by gauge id, in the order given."""
    return {result.reading.gauge: gauge_annotations(result, stamp_ns, image_size) for result in results}
