"""Read MCAP recordings leniently, and turn their image messages into :class:`ImageMessage`.

:class:`McapMessages` iterates the messages of a file up to its first damage and then stops,
recording what happened in ``damage`` instead of raising:

- a finished file (footer and summary present) is read through mcap's ``SeekingReader`` in log-time
  order, with chunk CRCs checked;
- an unfinished file (the writer crashed or is still writing: no footer) is read linearly with
  mcap's ``NonSeekingReader`` in file order; every complete chunk is read, and the iteration stops
  at the first truncated or corrupt record. Record lengths are capped at the file size so a garbage
  length cannot make the reader allocate gigabytes.

:class:`ImageDecoder` accepts the four image flavours: ``foxglove.CompressedImage`` and
``foxglove.RawImage`` in JSON (base64 ``data``) or protobuf (the message class is built from the
FileDescriptorSet stored in the schema, so no generated code is needed), and ROS 2
``sensor_msgs/msg/CompressedImage`` / ``sensor_msgs/msg/Image`` (``ros2msg`` schema, ``cdr``
messages, decoded by mcap-ros2-support).
"""

from __future__ import annotations

import base64
import io
import json
import logging
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import Any

from mcap.opcode import Opcode
from mcap.reader import FOOTER_SIZE, NonSeekingReader, SeekingReader
from mcap.records import Channel, Message, Schema
from mcap.stream_reader import MAGIC_SIZE
from mcap_ros2.decoder import DecoderFactory as Ros2DecoderFactory

from gauged.sources.image_decode import ImageMessage, InvalidFrame

log = logging.getLogger(__name__)

MCAP_MAGIC = b"\x89MCAP0\r\n"


class McapMessages:
    """The messages of one MCAP file on ``topics`` (None: all), up to the first damage.

    After iterating, ``damage`` is None for a clean read, else a sentence saying what was wrong and
    where; ``count`` is the number of messages yielded; ``topics_seen`` the topics of all channels.
    """

    def __init__(self, path: str | Path, topics: Iterable[str] | None = None) -> None:
        self.path = Path(path)
        self.topics = None if topics is None else set(topics)
        self.damage: str | None = None
        self.count = 0
        self.finished_file = False
        self.topics_seen: set[str] = set()

    def __iter__(self) -> Iterator[tuple[Schema | None, Channel, Message]]:
        self.damage, self.count = None, 0
        try:
            stream = open(self.path, "rb")
        except OSError as err:
            self.damage = f"cannot open {self.path}: {err}"
            return
        with stream:
            size = self.path.stat().st_size
            try:
                yield from self._messages(stream, size)
            except Exception as err:  # noqa: BLE001 - any damage ends the read, never the daemon
                where = stream.tell() if not stream.closed else "?"
                self.damage = (f"{self.path}: damaged at about byte {where} of {size} after {self.count} "
                               f"messages ({type(err).__name__}: {err})")

    def _messages(self, stream: io.BufferedReader, size: int) -> Iterator[tuple[Schema | None, Channel, Message]]:
        self.finished_file = _has_footer(stream, size)
        stream.seek(0)
        limit = max(size, 1)
        if self.finished_file:
            reader = SeekingReader(stream, validate_crcs=True, record_size_limit=limit)
            summary = reader.get_summary()
            if summary is not None and summary.chunk_indexes:
                self.topics_seen = {c.topic for c in summary.channels.values()}
                for item in reader.iter_messages(topics=self.topics, log_time_order=True):
                    self.count += 1
                    yield item
                return
            stream.seek(0)
        for schema, channel, message in NonSeekingReader(stream, validate_crcs=True, record_size_limit=limit) \
                .iter_messages(log_time_order=False):
            self.topics_seen.add(channel.topic)
            if self.topics is None or channel.topic in self.topics:
                self.count += 1
                yield schema, channel, message


def _has_footer(stream: io.BufferedReader, size: int) -> bool:
    """True when the file ends in a footer record and the closing magic (the writer finished it)."""
    if size < 2 * MAGIC_SIZE + FOOTER_SIZE:
        return False
    stream.seek(size - MAGIC_SIZE - FOOTER_SIZE)
    tail = stream.read(MAGIC_SIZE + FOOTER_SIZE)
    return tail[0] == Opcode.FOOTER and tail.endswith(MCAP_MAGIC)


def _stamp(sec: int, nsec: int) -> int | None:
    stamp = int(sec) * 1_000_000_000 + int(nsec)
    return stamp or None


def _from_fields(get: Callable[[str], Any], stamp_ns: int | None, data: bytes) -> ImageMessage | InvalidFrame:
    """Build an ImageMessage from a decoded compressed or raw image message's fields."""
    encoding = get("encoding")
    if encoding is None:
        fmt = get("format")
        if fmt is None:
            return InvalidFrame("bad_message", "message has neither 'format' nor 'encoding'")
        return ImageMessage(data=data, stamp_ns=stamp_ns, format=str(fmt))
    return ImageMessage(data=data, stamp_ns=stamp_ns, encoding=str(encoding), width=int(get("width") or 0),
                        height=int(get("height") or 0), step=int(get("step") or 0),
                        big_endian=bool(get("is_bigendian") or 0))


def _from_ros(msg: Any) -> ImageMessage | InvalidFrame:
    stamp = msg.header.stamp
    return _from_fields(lambda name: getattr(msg, name, None), _stamp(stamp.sec, stamp.nanosec), bytes(msg.data))


def _from_json(raw: bytes) -> ImageMessage | InvalidFrame:
    obj = json.loads(raw)
    if not isinstance(obj, dict):
        return InvalidFrame("bad_message", "JSON message is not an object")
    ts = obj.get("timestamp") or {}
    stamp = _stamp(ts.get("sec", 0), ts.get("nsec", ts.get("nanosec", 0))) if isinstance(ts, dict) else None
    data = base64.b64decode(obj.get("data") or "", validate=True)
    return _from_fields(obj.get, stamp, data)


def _protobuf_class(schema: Schema) -> Callable[[bytes], Any]:
    """The message class named by a protobuf schema, built from its FileDescriptorSet."""
    from google.protobuf import descriptor_pb2, descriptor_pool, message_factory

    files = list(descriptor_pb2.FileDescriptorSet.FromString(schema.data).file)
    pool = descriptor_pool.DescriptorPool()
    while files:  # add each file after its dependencies, whatever order the writer used
        ready = [f for f in files if all(_in_pool(pool, dep) for dep in f.dependency)]
        if not ready:
            raise ValueError(f"unresolvable protobuf imports in schema {schema.name}")
        for f in ready:
            pool.Add(f)
        files = [f for f in files if f.name not in {r.name for r in ready}]
    return message_factory.GetMessageClass(pool.FindMessageTypeByName(schema.name)).FromString


def _in_pool(pool: Any, name: str) -> bool:
    try:
        pool.FindFileByName(name)
    except KeyError:
        return False
    return True


def _from_protobuf(msg: Any) -> ImageMessage | InvalidFrame:
    fields = {f.name for f in msg.DESCRIPTOR.fields}
    ts = msg.timestamp
    return _from_fields(lambda name: getattr(msg, name) if name in fields else None,
                        _stamp(ts.seconds, ts.nanos), bytes(msg.data))


class ImageDecoder:
    """Turns MCAP image messages of the four supported flavours into ImageMessages (cached per schema)."""

    def __init__(self) -> None:
        self._ros2 = Ros2DecoderFactory()
        self._decoders: dict[int, Callable[[bytes], ImageMessage | InvalidFrame]] = {}

    def parse(self, schema: Schema | None, channel: Channel, message: Message) -> ImageMessage | InvalidFrame:
        """The image of one message, or why it is not one (reason ``bad_message``)."""
        decoder = self._decoders.get(channel.id)
        if decoder is None:
            try:
                decoder = self._decoder_for(schema, channel)
            except Exception as err:  # noqa: BLE001 - a bad schema is a bad message, not a crash
                detail = f"schema {schema.name if schema else None!r} on {channel.topic}: {err}"
                decoder = lambda _data: InvalidFrame("bad_message", detail)  # noqa: E731
            self._decoders[channel.id] = decoder
        try:
            return decoder(message.data)
        except Exception as err:  # noqa: BLE001
            return InvalidFrame("bad_message", f"{channel.topic}: {type(err).__name__}: {err}")

    def _decoder_for(self, schema: Schema | None, channel: Channel) -> Callable[[bytes], ImageMessage | InvalidFrame]:
        encoding = channel.message_encoding
        if encoding == "json":
            return _from_json
        if schema is None:
            raise ValueError(f"no schema for {encoding} messages")
        if encoding == "cdr":
            ros = self._ros2.decoder_for(encoding, schema)
            if ros is None:
                raise ValueError(f"cdr with schema encoding {schema.encoding!r} (need ros2msg)")
            return lambda data: _from_ros(ros(data))
        if encoding == "protobuf":
            parse = _protobuf_class(schema)
            return lambda data: _from_protobuf(parse(data))
        raise ValueError(f"message encoding {encoding!r} is not supported")
