"""The newest-frame-wins hand-off between a source and the camera worker that reads its frames.

A source's producer (a Zenoh callback on a Zenoh thread, or an MCAP reader thread) ``put``\\ s a
:class:`Pending` frame: its arrival sequence number, its fallback time and a *deferred* parse.
The mailbox holds one pending frame; a newer one replaces it and the replaced one is counted in
``gauged_frames_dropped_total``. ``put`` only takes a lock, so it never blocks Zenoh's threads.

The camera worker calls :meth:`FrameMailbox.next_frame`, which takes the pending frame and decodes
it *in the worker's thread*: a dropped frame is never decoded, and the cost of JPEG decoding lands
on the thread that is behind, not on the transport. Frames that cannot be decoded are counted in
``gauged_frames_invalid_total{camera,reason}``, logged (rate-limited) with camera and reason, and
skipped; they never stop the source.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass

from gauged.metrics import Metrics
from gauged.sources.image_decode import ImageMessage, InvalidFrame, decode_image
from gauged.types import Frame

log = logging.getLogger(__name__)

LOG_EVERY_S = 30.0  # after the first bad frame of a reason, log that reason at most this often


@dataclass(frozen=True, slots=True)
class Pending:
    """A received frame not yet decoded.

    ``parse`` runs in the consumer's thread and returns the image message or why it is invalid;
    ``fallback_stamp_ns`` is used when the message carries no time of its own (0 or absent).
    """

    seq: int
    parse: Callable[[], ImageMessage | InvalidFrame]
    fallback_stamp_ns: int


class FrameMailbox:
    """A one-slot, newest-wins mailbox of pending frames for one camera, with its frame counters."""

    def __init__(self, camera: str, metrics: Metrics | None = None) -> None:
        self.camera = camera
        self._metrics = metrics
        self._cond = threading.Condition()
        self._pending: Pending | None = None
        self._closed = False
        self._last_logged: dict[str, float] = {}
        self._suppressed: dict[str, int] = {}
        if metrics is not None:
            metrics.add_camera(camera)

    def put(self, item: Pending) -> None:
        """Offer a frame; replaces (and counts as dropped) one the consumer has not taken. Never blocks."""
        with self._cond:
            if self._closed:
                return
            replaced = self._pending is not None
            self._pending = item
            self._cond.notify()
        if self._metrics is not None:
            self._metrics.frames_received.labels(camera=self.camera).inc()
            if replaced:
                self._metrics.frames_dropped.labels(camera=self.camera).inc()

    def put_when_empty(self, item: Pending, stop: threading.Event) -> bool:
        """Offer a frame once the previous one was taken (lossless replay); False if stopped or closed."""
        with self._cond:
            while self._pending is not None and not self._closed and not stop.is_set():
                self._cond.wait(0.1)
            if self._closed or stop.is_set():
                return False
        self.put(item)
        return True

    def take(self, timeout: float | None = None) -> Pending | None:
        """The pending frame, waiting up to ``timeout`` seconds (None: forever); None on timeout or close."""
        with self._cond:
            if not self._cond.wait_for(lambda: self._pending is not None or self._closed, timeout):
                return None
            item, self._pending = self._pending, None
            self._cond.notify_all()
            return item

    @property
    def empty(self) -> bool:
        """True when no frame is waiting."""
        with self._cond:
            return self._pending is None

    def close(self) -> None:
        """Wake every waiter; later puts are ignored."""
        with self._cond:
            self._closed = True
            self._cond.notify_all()

    def next_frame(self, timeout: float | None = None) -> Frame | None:
        """The newest frame, decoded; waits up to ``timeout`` s, skipping (and counting) invalid frames."""
        deadline = None if timeout is None else time.monotonic() + timeout
        while True:
            remaining = None if deadline is None else max(0.0, deadline - time.monotonic())
            item = self.take(remaining)
            if item is None:
                return None
            frame = self.decode(item)
            if frame is not None:
                return frame
            if deadline is not None and time.monotonic() >= deadline:
                return None

    def decode(self, item: Pending) -> Frame | None:
        """Decode one pending frame; None (counted and logged) when it is invalid."""
        try:
            message = item.parse()
            image = decode_image(message) if isinstance(message, ImageMessage) else message
        except Exception as err:  # noqa: BLE001 - a bad frame must never stop the source
            image = InvalidFrame("undecodable", f"{type(err).__name__}: {err}")
        if isinstance(image, InvalidFrame):
            self.reject(image, item.seq)
            return None
        assert isinstance(message, ImageMessage)
        stamp = message.stamp_ns if message.stamp_ns else item.fallback_stamp_ns
        return Frame(image=image, stamp_ns=int(stamp), camera=self.camera, frame_id=item.seq)

    def reject(self, invalid: InvalidFrame, seq: int) -> None:
        """Count an invalid frame and log it: the first of each reason, then at most every LOG_EVERY_S."""
        if self._metrics is not None:
            self._metrics.frames_invalid.labels(camera=self.camera, reason=invalid.reason).inc()
        now = time.monotonic()
        last = self._last_logged.get(invalid.reason)
        if last is not None and now - last < LOG_EVERY_S:
            self._suppressed[invalid.reason] = self._suppressed.get(invalid.reason, 0) + 1
            return
        self._last_logged[invalid.reason] = now
        more = self._suppressed.pop(invalid.reason, 0)
        log.warning("camera %s: invalid frame %d (%s): %s%s", self.camera, seq, invalid.reason, invalid.detail,
                    f" [{more} more of this reason since last report]" if more else "")
