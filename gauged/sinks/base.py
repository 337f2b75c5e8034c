"""The one small interface every output implements, and the JSON encoding they share.

A plugin subclasses :class:`SinkBase` and overrides what it publishes; everything it does not
handle stays a no-op. Plugins are single-threaded: :class:`~gauged.sinks.buffered.BufferedSink`
calls them from its one worker thread and owns buffering, errors and self-metrics.

Calls the app makes (through the wrapper):

- ``publish_reading(reading)`` for every published :class:`~gauged.types.Reading`;
- ``publish_failure(gauge, camera, stamp_ns, failure)`` for every reader :class:`~gauged.types.StageFailure`;
- ``publish_alarm(event)`` for every alarm state change, the DESIGN dict
  ``{gauge, stamp_ns, level, state, value, limit, message}``;
- ``publish_image(camera, stamp_ns, image)`` for annotated images (BGR uint8), when enabled;
- ``publish_annotations(camera, stamp_ns, overlays)`` once per camera frame, to the plugins whose
  ``annotations`` is true: each gauge's ``foxglove.ImageAnnotations`` message, by gauge id
  (:mod:`gauged.sinks.annotations`);
- ``close()`` once, at stop.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from typing import Any, Protocol

import numpy as np

from gauged.alarms.lifecycle import AlarmState
from gauged.types import Reading, StageFailure

AlarmEvent = Mapping[str, Any]
Overlays = Mapping[str, Mapping[str, Any]]  # gauge id -> foxglove.ImageAnnotations message


class Sink(Protocol):
    """An output of gauged."""

    name: str

    def publish_reading(self, reading: Reading) -> None: ...
    def publish_failure(self, gauge: str, camera: str, stamp_ns: int, failure: StageFailure) -> None: ...
    def publish_alarm(self, event: AlarmEvent) -> None: ...
    def publish_image(self, camera: str, stamp_ns: int, image: np.ndarray) -> None: ...
    def publish_annotations(self, camera: str, stamp_ns: int, overlays: Overlays) -> None: ...
    def flush(self) -> None: ...
    def close(self) -> None: ...


class SinkBase:
    """No-op defaults for every :class:`Sink` method; plugins override what they publish."""

    name = "sink"
    flush_interval_s: float | None = None  # the wrapper calls flush() this often when set
    annotations = False  # the app builds image overlays only when some plugin publishes them

    def publish_reading(self, reading: Reading) -> None:
        """Publish one reading."""

    def publish_failure(self, gauge: str, camera: str, stamp_ns: int, failure: StageFailure) -> None:
        """Publish one stage failure."""

    def publish_alarm(self, event: AlarmEvent) -> None:
        """Publish one alarm state change."""

    def publish_image(self, camera: str, stamp_ns: int, image: np.ndarray) -> None:
        """Publish one annotated image (H, W, 3) uint8 BGR."""

    def publish_annotations(self, camera: str, stamp_ns: int, overlays: Overlays) -> None:
        """Publish the overlays of one camera frame (each gauge's, by gauge id)."""

    def flush(self) -> None:
        """Make everything published so far durable or visible."""

    def close(self) -> None:
        """Release everything; called once, after the last publish."""


# States in which an alarm is annunciated: active, acknowledged or not. Normal, returned-unacknowledged
# and shelved alarms are not (a shelved alarm is hidden from the operator on purpose).
ANNUNCIATED_STATES = frozenset({AlarmState.ACTIVE_UNACKNOWLEDGED.value, AlarmState.ACTIVE_ACKNOWLEDGED.value})


def alarm_is_active(event: AlarmEvent) -> bool:
    """True when an alarm event (``AlarmEvent.to_dict()``) leaves the alarm annunciated."""
    return str(event.get("state", "")) in ANNUNCIATED_STATES


def failure_record(gauge: str, camera: str, stamp_ns: int, failure: StageFailure) -> dict[str, Any]:
    """The JSON record of one stage failure (``/gauged/failures``)."""
    return {"gauge": gauge, "camera": camera, "stamp_ns": int(stamp_ns), **failure.to_dict()}


def _finite(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, Mapping):
        return {str(k): _finite(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_finite(v) for v in value]
    if isinstance(value, np.generic):
        return _finite(value.item())
    return value


def to_json(obj: Any) -> bytes:
    """Compact UTF-8 JSON; NaN and infinities become null (JSON has no such numbers)."""
    return json.dumps(_finite(obj), separators=(",", ":"), ensure_ascii=False, allow_nan=False).encode()
