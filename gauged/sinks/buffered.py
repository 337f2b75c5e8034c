"""The wrapper around every output: a bounded buffer, one worker thread, errors and self-metrics.

The app calls :class:`BufferedSink` from the reader's threads; each call only appends to a bounded
deque and returns. One worker thread per output feeds the plugin, so plugins never see two threads
and a slow output (a full disk, a congested network) never stalls reading. When the buffer is full
the *oldest* item is dropped and counted in ``gauged_sink_dropped_total{sink}``; annotated images
have their own small cap because they are large. A plugin call that raises is logged
(rate-limited) and counted in ``gauged_sink_errors_total{sink}``; the next item is tried anyway.
``close()`` drains what is buffered (bounded in time), then closes the plugin on the worker thread.
"""

from __future__ import annotations

import collections
import logging
import threading
import time
from typing import Any

import numpy as np

from gauged.metrics import Metrics
from gauged.sinks.base import AlarmEvent, Overlays, SinkBase
from gauged.types import Reading, StageFailure

log = logging.getLogger(__name__)

LOG_ERRORS_EVERY_S = 30.0


class BufferedSink:
    """Runs one sink plugin behind a bounded, drop-oldest buffer on its own thread."""

    def __init__(self, sink: SinkBase, metrics: Metrics | None = None, *, capacity: int = 10_000,
                 max_images: int = 4) -> None:
        self.sink = sink
        self.name = sink.name
        self._metrics = metrics
        self._capacity = capacity
        self._max_images = max_images
        self._items: collections.deque[tuple[str, tuple[Any, ...]]] = collections.deque()
        self._images = 0
        self._cond = threading.Condition()
        self._closing = False
        self._last_error_log = -LOG_ERRORS_EVERY_S
        if metrics is not None:  # at zero from the start, so rate() sees the first error
            metrics.sink_errors.labels(sink=self.name)
            metrics.sink_dropped.labels(sink=self.name)
        self._thread = threading.Thread(target=self._run, name=f"sink-{self.name}", daemon=True)
        self._thread.start()

    # -- the app's side: enqueue and return -----------------------------------------------------
    def publish_reading(self, reading: Reading) -> None:
        self._put("publish_reading", (reading,))

    def publish_failure(self, gauge: str, camera: str, stamp_ns: int, failure: StageFailure) -> None:
        self._put("publish_failure", (gauge, camera, stamp_ns, failure))

    def publish_alarm(self, event: AlarmEvent) -> None:
        self._put("publish_alarm", (dict(event),))

    def publish_image(self, camera: str, stamp_ns: int, image: np.ndarray) -> None:
        self._put("publish_image", (camera, stamp_ns, image))

    def publish_annotations(self, camera: str, stamp_ns: int, overlays: Overlays) -> None:
        self._put("publish_annotations", (camera, stamp_ns, overlays))

    @property
    def annotations(self) -> bool:
        """Whether the plugin publishes image overlays."""
        return bool(self.sink.annotations)

    def _put(self, method: str, args: tuple[Any, ...]) -> None:
        dropped = 0
        with self._cond:
            if self._closing:
                dropped = 1
            elif method == "publish_image" and self._images >= self._max_images:
                dropped = 1  # keep the images already waiting; they are as good as this one
            else:
                self._items.append((method, args))
                self._images += method == "publish_image"
                while len(self._items) > self._capacity:
                    old, _ = self._items.popleft()
                    self._images -= old == "publish_image"
                    dropped += 1
                self._cond.notify()
        if dropped and self._metrics is not None:
            self._metrics.sink_dropped.labels(sink=self.name).inc(dropped)

    @property
    def pending(self) -> int:
        """Items waiting in the buffer."""
        with self._cond:
            return len(self._items)

    def close(self, timeout: float = 10.0) -> None:
        """Publish what is buffered (for at most ``timeout`` s), then close the plugin. Idempotent."""
        with self._cond:
            self._closing = True
            self._cond.notify()
        self._thread.join(timeout)
        if self._thread.is_alive():
            log.error("sink %s: still busy after %.0f s at close; %d items not written",
                      self.name, timeout, self.pending)

    # -- the worker's side --------------------------------------------------------------------------
    def _run(self) -> None:
        interval = self.sink.flush_interval_s
        next_flush = time.monotonic() + interval if interval else None
        while True:
            with self._cond:
                while not self._items and not self._closing:
                    wait = None if next_flush is None else max(0.0, next_flush - time.monotonic())
                    if not self._cond.wait(wait) and next_flush is not None:
                        break  # time to flush
                item = self._items.popleft() if self._items else None
                if item is not None:
                    self._images -= item[0] == "publish_image"
                done = item is None and self._closing
                if self._metrics is not None:
                    self._metrics.sink_queue.labels(sink=self.name).set(len(self._items))
            if done:
                break
            if item is not None:
                self._call(item[0], *item[1])
            if next_flush is not None and time.monotonic() >= next_flush:
                self._call("flush")
                next_flush = time.monotonic() + interval  # type: ignore[operator]
        self._call("close")

    def _call(self, method: str, *args: Any) -> None:
        try:
            getattr(self.sink, method)(*args)
        except Exception as err:  # noqa: BLE001 - one bad item or outage must not stop the output
            if self._metrics is not None:
                self._metrics.sink_errors.labels(sink=self.name).inc()
            now = time.monotonic()
            if now - self._last_error_log >= LOG_ERRORS_EVERY_S:
                self._last_error_log = now
                log.error("sink %s: %s failed: %s: %s", self.name, method, type(err).__name__, err,
                          exc_info=log.isEnabledFor(logging.DEBUG))
