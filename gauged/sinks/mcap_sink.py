"""Readings, stage failures, alarms and (optionally) annotated images logged to MCAP files.

Channels (see :mod:`gauged.sinks.mcap_schemas`): ``/gauged/readings``, ``/gauged/failures`` and
``/gauged/alarms`` with JSON schemas and JSON messages, registered in every file; and, with
``images: annotated``, ``/gauged/<camera>/annotated`` as ``foxglove.CompressedImage`` (JPEG); and,
with ``annotations: true`` (the default), ``/<camera>/gauged/annotations``, one
``foxglove.ImageAnnotations`` per camera frame holding every gauge's overlay
(:mod:`gauged.sinks.annotations`), registered at the camera's first frame.
``log_time`` and ``publish_time`` are the frame time ``stamp_ns``, so a replay writes the same data.

Durability: chunks are zstd-compressed and small (``chunk_kb``), and the wrapper calls
:meth:`McapSink.flush` every ``flush_s``, which closes the open chunk and hands it to the OS. A
crash (SIGKILL, OOM) therefore loses at most the chunk being filled; such a file has no footer and
is read linearly up to its last complete chunk (:class:`gauged.sources.mcap_read.McapMessages`,
or mcap's ``NonSeekingReader``, which yields every complete chunk and then raises at the cut).
:meth:`McapSink.close` finishes the file (summary, footer), so a clean stop loses nothing.

Files rotate when they reach ``rotate_mb`` or span ``rotate_s`` of frame time. They are named
``<name_prefix>-<UTC frame time of their first message>-<index>.mcap``, e.g.
``gauged-20250314T092653.120Z-0000.mcap``, which sorts in time order.
"""

from __future__ import annotations

import base64
import datetime as dt
import logging
from pathlib import Path
from typing import IO, Any

import cv2
import numpy as np
from mcap.writer import CompressionType, Writer

from gauged.metrics import gauged_version
from gauged.sinks import mcap_schemas as schemas
from gauged.sinks.annotations import merge
from gauged.sinks.base import AlarmEvent, Overlays, SinkBase, failure_record, to_json
from gauged.sinks.config import McapSinkConfig
from gauged.types import Reading, StageFailure

log = logging.getLogger(__name__)


def _file_stamp(stamp_ns: int) -> str:
    t = dt.datetime.fromtimestamp(stamp_ns // 1_000_000_000, dt.timezone.utc)
    return f"{t:%Y%m%dT%H%M%S}.{stamp_ns // 1_000_000 % 1000:03d}Z"


class McapSink(SinkBase):
    """Writes rotating MCAP files into one directory (see module docs)."""

    name = "mcap"

    def __init__(self, directory: str | Path, *, rotate_mb: float = 256.0, rotate_s: float = 3600.0,
                 images: str = "none", chunk_kb: int = 64, flush_s: float = 2.0,
                 name_prefix: str = "gauged", jpeg_quality: int = 85, annotations: bool = True) -> None:
        self.directory = Path(directory)
        self.directory.mkdir(parents=True, exist_ok=True)
        self.rotate_bytes = int(rotate_mb * 1024 * 1024)
        self.rotate_ns = int(rotate_s * 1e9)
        self.images = images
        self.annotations = annotations
        self.chunk_bytes = int(chunk_kb * 1024)
        self.flush_interval_s = flush_s
        self.name_prefix = name_prefix
        self.jpeg_quality = jpeg_quality
        self.files: list[Path] = []  # every file opened, in order
        self._stream: IO[bytes] | None = None
        self._writer: Writer | None = None
        self._channels: dict[str, int] = {}
        self._schema_ids: dict[str, int] = {}
        self._first_stamp = 0

    @classmethod
    def from_config(cls, config: McapSinkConfig, name_prefix: str = "gauged") -> McapSink:
        return cls(config.dir, rotate_mb=config.rotate_mb, rotate_s=config.rotate_s, images=config.images,
                   chunk_kb=config.chunk_kb, flush_s=config.flush_s, name_prefix=name_prefix,
                   annotations=config.annotations)

    def publish_reading(self, reading: Reading) -> None:
        self._write(schemas.READINGS_TOPIC, reading.stamp_ns, reading.to_dict())

    def publish_failure(self, gauge: str, camera: str, stamp_ns: int, failure: StageFailure) -> None:
        self._write(schemas.FAILURES_TOPIC, stamp_ns, failure_record(gauge, camera, stamp_ns, failure))

    def publish_alarm(self, event: AlarmEvent) -> None:
        self._write(schemas.ALARMS_TOPIC, int(event["stamp_ns"]), event)

    def publish_image(self, camera: str, stamp_ns: int, image: np.ndarray) -> None:
        if self.images != "annotated":
            return
        ok, jpeg = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, self.jpeg_quality])
        if not ok:
            raise ValueError(f"JPEG encoding of a {image.shape} {image.dtype} image failed")
        sec, nsec = divmod(int(stamp_ns), 1_000_000_000)
        record = {"timestamp": {"sec": sec, "nsec": nsec}, "frame_id": camera,
                  "data": base64.b64encode(jpeg.tobytes()).decode("ascii"), "format": "jpeg"}
        self._write(schemas.annotated_topic(camera), stamp_ns, record, schemas.COMPRESSED_IMAGE_SCHEMA)

    def publish_annotations(self, camera: str, stamp_ns: int, overlays: Overlays) -> None:
        if self.annotations:  # one message per frame: the Image panel shows one per topic and time
            self._write(schemas.annotations_topic(camera), stamp_ns, merge(stamp_ns, overlays.values()),
                        schemas.IMAGE_ANNOTATIONS_SCHEMA)

    def _write(self, topic: str, stamp_ns: int, record: Any, schema: dict[str, Any] | None = None) -> None:
        stamp_ns = int(stamp_ns)
        if self._writer is not None and self._stream is not None and (
                self._stream.tell() >= self.rotate_bytes or stamp_ns - self._first_stamp >= self.rotate_ns):
            self._finish()
        writer = self._writer if self._writer is not None else self._open(stamp_ns)
        channel = self._channels.get(topic)
        if channel is None:
            channel = self._register(topic, schema or {})
        before = self._stream.tell() if self._stream is not None else 0
        writer.add_message(channel, log_time=stamp_ns, data=to_json(record), publish_time=stamp_ns)
        if self._stream is not None and self._stream.tell() != before:
            self._stream.flush()  # a chunk was just completed: hand it to the OS now, not at 8 KiB

    def _open(self, stamp_ns: int) -> Writer:
        index = len(self.files)
        while (path := self.directory / f"{self.name_prefix}-{_file_stamp(stamp_ns)}-{index:04d}.mcap").exists():
            index += 1
        self._stream = open(path, "wb")
        self._writer = Writer(self._stream, chunk_size=self.chunk_bytes, compression=CompressionType.ZSTD)
        self._writer.start(profile="", library=f"gauged/{gauged_version()}")
        self._channels, self._schema_ids, self._first_stamp = {}, {}, stamp_ns
        for topic, schema in ((schemas.READINGS_TOPIC, schemas.READING_SCHEMA),
                              (schemas.FAILURES_TOPIC, schemas.FAILURE_SCHEMA),
                              (schemas.ALARMS_TOPIC, schemas.ALARM_SCHEMA)):
            self._register(topic, schema)
        self.files.append(path)
        log.info("mcap sink: writing %s", path)
        return self._writer

    def _register(self, topic: str, schema: dict[str, Any]) -> int:
        assert self._writer is not None
        title = schema["title"]
        schema_id = self._schema_ids.get(title)
        if schema_id is None:
            schema_id = self._schema_ids[title] = self._writer.register_schema(title, "jsonschema", to_json(schema))
        channel = self._channels[topic] = self._writer.register_channel(topic, "json", schema_id)
        return channel

    def flush(self) -> None:
        """Close the open chunk and hand it to the OS (a later crash cannot lose it)."""
        if self._writer is not None:
            self._writer.flush()

    def _finish(self) -> None:
        if self._writer is None or self._stream is None:
            return
        try:
            self._writer.finish()
        finally:
            self._stream.close()
            log.info("mcap sink: finished %s", self.files[-1])
            self._writer = self._stream = None

    def close(self) -> None:
        """Finish the current file (summary and footer): nothing written is lost."""
        self._finish()
