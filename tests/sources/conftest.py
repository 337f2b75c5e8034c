"""Fixtures of the source tests: real MCAP recordings of every image flavour, real Zenoh sessions."""

from __future__ import annotations

import base64
import json
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
import pytest
import zenoh
from google.protobuf import descriptor_pb2, descriptor_pool, message_factory, timestamp_pb2
from mcap.writer import CompressionType, Writer
from mcap_ros2._dynamic import serialize_dynamic
from mcap_ros2.writer import Writer as Ros2Writer

from tests.zenoh_loopback import free_port, peer_config, zenoh_pair_sessions  # noqa: F401 (re-exported)

TIME_MSG = "================================================================================\n" \
    "MSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n" \
    "================================================================================\n" \
    "MSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n"
ROS_COMPRESSED_DEF = "std_msgs/Header header\nstring format\nuint8[] data\n" + TIME_MSG
ROS_IMAGE_DEF = ("std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\nuint8 is_bigendian\n"
                 "uint32 step\nuint8[] data\n" + TIME_MSG)

def draw(index: int, width: int = 96, height: int = 64) -> np.ndarray:
    """A BGR test image that differs per index: a coloured disc on a grey ramp."""
    image = np.zeros((height, width, 3), np.uint8)
    image[:] = np.linspace(40, 200, width, dtype=np.uint8)[None, :, None]
    cv2.circle(image, (10 + 7 * index % (width - 20), height // 2), 9, (255, 40 * index % 256, 30), -1)
    return image


def jpeg(image: np.ndarray) -> bytes:
    ok, buf = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, 95])
    assert ok
    return buf.tobytes()


@dataclass
class Recorded:
    """What a test recording holds: per message the header stamp (0: none), log time, image, bytes sent."""

    stamps: list[int]
    log_times: list[int]
    images: list[np.ndarray]
    payloads: list[bytes]  # JPEG bytes (compressed flavours) or raw RGB bytes (raw flavours)


def _foxglove_descriptor(kind: str) -> descriptor_pb2.FileDescriptorSet:
    """foxglove.CompressedImage / foxglove.RawImage as the foxglove SDK describes them (field numbers too)."""
    F = descriptor_pb2.FieldDescriptorProto
    fd = descriptor_pb2.FileDescriptorProto(name=f"foxglove/{kind}.proto", package="foxglove", syntax="proto3",
                                            dependency=["google/protobuf/timestamp.proto"])
    msg = fd.message_type.add(name=kind)
    fields = [("timestamp", 1, F.TYPE_MESSAGE)]
    if kind == "CompressedImage":
        fields += [("frame_id", 4, F.TYPE_STRING), ("data", 2, F.TYPE_BYTES), ("format", 3, F.TYPE_STRING)]
    else:
        fields += [("frame_id", 7, F.TYPE_STRING), ("width", 2, F.TYPE_FIXED32), ("height", 3, F.TYPE_FIXED32),
                   ("encoding", 4, F.TYPE_STRING), ("step", 5, F.TYPE_FIXED32), ("data", 6, F.TYPE_BYTES)]
    for name, number, ftype in fields:
        msg.field.add(name=name, number=number, type=ftype, label=F.LABEL_OPTIONAL,
                      type_name=".google.protobuf.Timestamp" if ftype == F.TYPE_MESSAGE else None)
    ts = descriptor_pb2.FileDescriptorProto()
    timestamp_pb2.DESCRIPTOR.CopyToProto(ts)
    return descriptor_pb2.FileDescriptorSet(file=[fd, ts])  # dependency last on purpose


def _protobuf_class(fds: descriptor_pb2.FileDescriptorSet, name: str) -> type:
    pool = descriptor_pool.DescriptorPool()
    for f in reversed(fds.file):
        pool.Add(f)
    return message_factory.GetMessageClass(pool.FindMessageTypeByName(name))


def write_recording(path: Path, flavour: str, count: int = 3, *, topic: str = "/cam1/image",
                    zero_stamp: bool = False, period_ns: int = 50_000_000, chunk_size: int = 1024 * 1024,
                    extra: Callable[[int], bytes | None] | None = None) -> Recorded:
    """Write ``count`` frames of ``flavour`` on ``topic``; header stamps are 1 ms before the log times.

    ``extra(i)`` may return replacement payload bytes for message ``i`` (to plant bad frames).
    """
    base_log = 1_700_000_000_000_000_000
    rec = Recorded([], [], [], [])
    compressed = "compressed" in flavour
    stream = open(path, "wb")
    if flavour.startswith("ros2"):
        ros = Ros2Writer(stream, chunk_size=chunk_size)
        name = "sensor_msgs/msg/CompressedImage" if compressed else "sensor_msgs/msg/Image"
        schema = ros.register_msgdef(name, ROS_COMPRESSED_DEF if compressed else ROS_IMAGE_DEF)
    else:
        writer = Writer(stream, chunk_size=chunk_size, compression=CompressionType.ZSTD)
        writer.start()
        kind = "CompressedImage" if compressed else "RawImage"
        if flavour.endswith("json"):
            schema_id = writer.register_schema(f"foxglove.{kind}", "jsonschema", b'{"type":"object"}')
            channel = writer.register_channel(topic, "json", schema_id)
        else:
            fds = _foxglove_descriptor(kind)
            proto_cls = _protobuf_class(fds, f"foxglove.{kind}")
            schema_id = writer.register_schema(f"foxglove.{kind}", "protobuf", fds.SerializeToString())
            channel = writer.register_channel(topic, "protobuf", schema_id)
    for i in range(count):
        log_time = base_log + i * period_ns
        stamp = 0 if zero_stamp else log_time - 1_000_000
        image = draw(i)
        data = jpeg(image) if compressed else cv2.cvtColor(image, cv2.COLOR_BGR2RGB).tobytes()
        if extra is not None and (planted := extra(i)) is not None:
            data = planted
        rec.stamps.append(stamp), rec.log_times.append(log_time), rec.images.append(image), rec.payloads.append(data)
        sec, nsec = divmod(stamp, 1_000_000_000)
        h, w = image.shape[:2]
        fields = {"format": "jpeg"} if compressed else {"width": w, "height": h, "encoding": "rgb8", "step": 3 * w}
        if flavour.startswith("ros2"):
            msg = {"header": {"stamp": {"sec": sec, "nanosec": nsec}, "frame_id": "cam1"}, "data": data, **fields}
            if not compressed:
                msg["is_bigendian"] = 0
            ros.write_message(topic, schema, msg, log_time=log_time)
        elif flavour.endswith("json"):
            obj = {"timestamp": {"sec": sec, "nsec": nsec}, "frame_id": "cam1",
                   "data": base64.b64encode(data).decode(), **fields}
            writer.add_message(channel, log_time=log_time, data=json.dumps(obj).encode(), publish_time=log_time)
        else:
            msg = proto_cls(frame_id="cam1", data=data, **fields)
            msg.timestamp.seconds, msg.timestamp.nanos = sec, nsec
            writer.add_message(channel, log_time=log_time, data=msg.SerializeToString(), publish_time=log_time)
    (ros if flavour.startswith("ros2") else writer).finish()
    stream.close()
    return rec


@pytest.fixture
def recording(tmp_path: Path) -> Callable[..., tuple[Path, Recorded]]:
    """``recording(flavour, count=3, **kw) -> (path, Recorded)``: a real MCAP file in tmp_path."""
    def make(flavour: str, count: int = 3, **kw: object) -> tuple[Path, Recorded]:
        path = tmp_path / f"{flavour}-{count}.mcap"
        return path, write_recording(path, flavour, count, **kw)  # type: ignore[arg-type]
    return make


@dataclass(frozen=True)
class CdrEncoders:
    """ROS 2 CDR serializers (mcap-ros2-support's) of the two image messages, taking dicts."""

    compressed: Callable[[dict], bytes]
    raw: Callable[[dict], bytes]


@pytest.fixture(scope="session")
def cdr() -> CdrEncoders:
    """CDR encoders of sensor_msgs/msg/CompressedImage (``cdr.compressed``) and Image (``cdr.raw``)."""
    compressed = "sensor_msgs/msg/CompressedImage"
    raw = "sensor_msgs/msg/Image"
    return CdrEncoders(serialize_dynamic(compressed, ROS_COMPRESSED_DEF)[compressed],
                       serialize_dynamic(raw, ROS_IMAGE_DEF)[raw])






@pytest.fixture
def zenoh_pair() -> Iterator[tuple[zenoh.Session, zenoh.Session]]:
    """(daemon session listening on loopback, peer session connected to it); both closed after."""
    yield from zenoh_pair_sessions()