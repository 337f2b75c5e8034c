"""Frames from a Zenoh key expression: JPEG/PNG bytes or ROS 2 CDR images (rmw_zenoh, zenoh-bridge-ros2dds).

The subscriber's callback runs on a Zenoh thread and only hands the sample to the camera's
:class:`~gauged.sources.mailbox.FrameMailbox` (a one-slot ring: the newest sample wins, every
replaced one is counted as dropped). Copying the payload, parsing CDR and decoding JPEG all happen
later, in the camera worker's thread, so Zenoh's threads are never blocked and dropped samples
cost nothing. (Zenoh's own ``RingChannel`` also keeps the newest sample, but it cannot count
what it drops, and ``gauged_frames_dropped_total`` must.)

The key may hold wildcards: rmw_zenoh publishes on ``<domain>/<topic>/<type>/<type hash>``, e.g.
``0/cam1/image/compressed/sensor_msgs::msg::dds_::CompressedImage_/RIHS01_...``, so
``0/cam1/image/compressed/**`` matches it; zenoh-bridge-ros2dds publishes on the bare topic
name (``cam1/image/compressed``).

``stamp_ns`` of a frame is, in order of preference: the ROS header stamp (when non-zero); the
sample's Zenoh timestamp (present when the publisher or a router timestamps samples); else the
receive time on a clock that is monotonic but anchored once to the wall clock at start, so it never
runs backwards yet reads like a Unix time.
"""

from __future__ import annotations

import logging
import threading
import time
from typing import Any

import zenoh

from gauged.metrics import Metrics
from gauged.sources.config import ZenohSourceConfig
from gauged.sources.image_decode import ImageMessage, InvalidFrame, parse_payload
from gauged.sources.mailbox import FrameMailbox, Pending
from gauged.types import Frame

log = logging.getLogger(__name__)


class ReceiveClock:
    """A monotonic nanosecond clock that starts at the wall clock's reading (never runs backwards)."""

    def __init__(self) -> None:
        self._wall0 = time.time_ns()
        self._mono0 = time.monotonic_ns()

    def now_ns(self) -> int:
        return self._wall0 + time.monotonic_ns() - self._mono0


def _parse_sample(sample: Any) -> ImageMessage | InvalidFrame:
    return parse_payload(sample.payload.to_bytes(), str(sample.encoding), str(sample.key_expr))


class ZenohSource:
    """Subscribes to one key expression and serves the newest frame of one camera."""

    def __init__(self, camera: str, session: zenoh.Session, key: str, *, metrics: Metrics | None = None) -> None:
        self.camera, self.key = camera, key
        self._session = session
        self._mailbox = FrameMailbox(camera, metrics)
        self._clock = ReceiveClock()
        self._seq = 0
        self._seq_lock = threading.Lock()
        self._subscriber: Any = None

    @classmethod
    def from_config(cls, camera: str, config: ZenohSourceConfig, session: zenoh.Session,
                    metrics: Metrics | None = None) -> ZenohSource:
        return cls(camera, session, config.key, metrics=metrics)

    @property
    def finished(self) -> bool:
        """A live source never finishes."""
        return False

    def start(self) -> None:
        """Declare the subscriber; raises ``zenoh.ZError`` for an invalid key expression."""
        self._subscriber = self._session.declare_subscriber(self.key, self._on_sample)
        log.info("camera %s: subscribed to %s", self.camera, self.key)

    def _on_sample(self, sample: Any) -> None:
        # Runs on a Zenoh thread: take the arrival time and hand over, nothing more.
        if sample.kind != zenoh.SampleKind.PUT:
            return
        received = self._clock.now_ns()
        stamp = sample.timestamp
        fallback = stamp.get_time_as_ntp64().as_nanos() if stamp is not None else received
        with self._seq_lock:
            seq, self._seq = self._seq, self._seq + 1
        self._mailbox.put(Pending(seq, lambda: _parse_sample(sample), fallback))

    def next_frame(self, timeout: float | None = None) -> Frame | None:
        """The newest frame, or None after ``timeout`` s or once the source is stopped."""
        return self._mailbox.next_frame(timeout)

    def stop(self) -> None:
        """Undeclare the subscriber (the session stays open: the app owns it) and wake the consumer."""
        if self._subscriber is not None:
            try:
                self._subscriber.undeclare()
            except Exception as err:  # noqa: BLE001 - a closed session already dropped it
                log.debug("camera %s: undeclare failed: %s", self.camera, err)
            self._subscriber = None
        self._mailbox.close()
