"""Frames replayed from an MCAP recording: one topic per camera, paced in real time or as fast as read.

``pace: realtime`` sleeps on the monotonic clock so frames arrive as they were logged; when the
reader falls behind, the newest frame wins and every dropped frame is counted, as with a live
camera. ``pace: fast`` hands over every frame as soon as the previous one was taken (lossless batch
replay; nothing is dropped). ``loop: true`` starts over at the end; each pass shifts the stamps by
the recording's length plus one mean frame interval, so time never runs backwards downstream.

``stamp_ns`` is the message's own time (``header.stamp`` for ROS 2, ``timestamp`` for foxglove),
or the record's ``log_time`` when that is zero or absent. A truncated or corrupt recording is
replayed up to the damage, which is logged once with its position; the source then ends (or loops
over the readable part).

For batch work without threads, :func:`iter_frames` yields every decodable frame of a topic.
"""

from __future__ import annotations

import dataclasses
import logging
import threading
import time
from collections.abc import Iterator
from functools import partial
from pathlib import Path

from mcap.records import Channel, Message, Schema

from gauged.metrics import Metrics
from gauged.sources.config import McapSourceConfig
from gauged.sources.image_decode import ImageMessage, InvalidFrame
from gauged.sources.mailbox import FrameMailbox, Pending
from gauged.sources.mcap_read import ImageDecoder, McapMessages
from gauged.types import Frame

log = logging.getLogger(__name__)


def _shifted(decoder: ImageDecoder, offset_ns: int, schema: Schema | None, channel: Channel,
             message: Message) -> ImageMessage | InvalidFrame:
    parsed = decoder.parse(schema, channel, message)
    if offset_ns and isinstance(parsed, ImageMessage) and parsed.stamp_ns:
        parsed = dataclasses.replace(parsed, stamp_ns=parsed.stamp_ns + offset_ns)
    return parsed


def _report(messages: McapMessages, topic: str, level: int = logging.ERROR) -> None:
    if messages.damage and messages.count:
        log.log(level, "%s; replayed the %d frames of %s before it", messages.damage, messages.count, topic)
    elif messages.damage:
        log.log(level, "%s; no frame of %s replayed", messages.damage, topic)
    elif messages.count == 0:
        log.log(level, "%s: no message on topic %s (topics: %s)", messages.path, topic,
                ", ".join(sorted(messages.topics_seen)) or "none")


def iter_frames(path: str | Path, topic: str, camera: str | None = None,
                metrics: Metrics | None = None) -> Iterator[Frame]:
    """Every decodable frame of ``topic`` in the recording, in log-time order (file order when unfinished).

    Invalid frames are skipped (counted on ``metrics`` when given, and logged); damage ends the
    iteration and is logged. ``frame_id`` is the message's index on the topic.
    """
    mailbox = FrameMailbox(camera or topic, metrics)
    decoder = ImageDecoder()
    messages = McapMessages(path, [topic])
    for seq, (schema, channel, message) in enumerate(messages):
        frame = mailbox.decode(Pending(seq, partial(decoder.parse, schema, channel, message), message.log_time))
        if frame is not None:
            yield frame
    _report(messages, topic)


class McapSource:
    """Replays one topic of an MCAP recording as the frames of one camera (see module docs)."""

    def __init__(self, camera: str, path: str | Path, topic: str, *, pace: str = "realtime",
                 loop: bool = False, metrics: Metrics | None = None) -> None:
        if pace not in ("realtime", "fast"):
            raise ValueError(f"pace must be 'realtime' or 'fast', got {pace!r}")
        self.camera, self.path, self.topic, self.pace, self.loop = camera, Path(path), topic, pace, loop
        self._mailbox = FrameMailbox(camera, metrics)
        self._stop = threading.Event()
        self._done = threading.Event()
        self._thread: threading.Thread | None = None

    @classmethod
    def from_config(cls, camera: str, config: McapSourceConfig, metrics: Metrics | None = None) -> McapSource:
        return cls(camera, config.path, config.topic, pace=config.pace, loop=config.loop, metrics=metrics)

    def start(self) -> None:
        """Start the reader thread; a missing file is logged and ends the source (never raises)."""
        self._thread = threading.Thread(target=self._run, name=f"mcap-{self.camera}", daemon=True)
        self._thread.start()

    def next_frame(self, timeout: float | None = None) -> Frame | None:
        """The newest frame, or None after ``timeout`` s or once the source is stopped."""
        return self._mailbox.next_frame(timeout)

    @property
    def finished(self) -> bool:
        """True once the recording was read to its end (without loop) and its last frame taken."""
        return self._done.is_set() and self._mailbox.empty

    def stop(self) -> None:
        """Stop reading and wake any waiting consumer."""
        self._stop.set()
        self._mailbox.close()
        if self._thread is not None:
            self._thread.join(timeout=5.0)

    def _run(self) -> None:
        try:
            self._replay()
        except Exception:  # noqa: BLE001 - the source ends, the daemon goes on
            log.exception("camera %s: replay of %s failed", self.camera, self.path)
        finally:
            self._done.set()

    def _replay(self) -> None:
        decoder = ImageDecoder()
        seq, offset, passes = 0, 0, 0
        pass_start = time.monotonic()
        while not self._stop.is_set():
            messages = McapMessages(self.path, [self.topic])
            first_log = last_log = None
            for schema, channel, message in messages:
                if first_log is None:
                    first_log = message.log_time
                last_log = message.log_time
                if self.pace == "realtime" and self._stop.wait(
                        max(0.0, pass_start + (message.log_time - first_log) / 1e9 - time.monotonic())):
                    return
                item = Pending(seq, partial(_shifted, decoder, offset, schema, channel, message),
                               message.log_time + offset)
                seq += 1
                if self.pace == "fast":
                    if not self._mailbox.put_when_empty(item, self._stop):
                        return
                else:
                    self._mailbox.put(item)
            _report(messages, self.topic, logging.ERROR if passes == 0 else logging.DEBUG)
            if not self.loop or first_log is None or last_log is None:
                return
            span = last_log - first_log
            gap = span // (messages.count - 1) if messages.count > 1 else 1_000_000_000
            offset += span + gap
            passes += 1
            pass_start = time.monotonic() + (gap / 1e9 if self.pace == "realtime" else 0.0)
