"""Write camera sequences to MCAP, in the two flavours gauged reads.

Foxglove flavour (:func:`write_foxglove`): frames as ``foxglove.CompressedImage`` (schema encoding
``jsonschema``, message encoding ``json``, ``data`` base64 as in Foxglove's JSON convention) on
``/<camera>/image``, and the ground truth of each frame (:mod:`gauged.synth.truth`) as JSON on
``/<camera>/truth``.

ROS 2 flavour (:func:`write_ros2`, written with mcap-ros2-support's writer):
``sensor_msgs/msg/CompressedImage`` (``ros2msg`` + ``cdr``) on ``/<camera>/image``, and the truth as
``std_msgs/msg/String`` holding the same JSON on ``/<camera>/truth``.

In both, a message's log time and publish time are the frame stamp in ns, frames of all cameras
are interleaved in time order, and the timeline starts at :data:`~gauged.synth.sequence.EPOCH_NS`,
so the same sequences give the same bytes.
"""

from __future__ import annotations

import base64
import heapq
import json
import logging
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

from mcap.writer import CompressionType, Writer
from mcap_ros2.writer import Writer as Ros2Writer

from gauged.synth.sequence import EPOCH_NS, CameraSequence, SequenceFrame, camera_frames, encode_jpeg

log = logging.getLogger(__name__)

COMPRESSED_IMAGE_SCHEMA = {
    "title": "foxglove.CompressedImage",
    "description": "A compressed image",
    "type": "object",
    "properties": {
        "timestamp": {"type": "object", "title": "time", "description": "Timestamp of image",
                      "properties": {"sec": {"type": "integer", "minimum": 0},
                                     "nsec": {"type": "integer", "minimum": 0, "maximum": 999999999}}},
        "frame_id": {"type": "string", "description": "Frame of reference for the image."},
        "data": {"type": "string", "contentEncoding": "base64", "description": "Compressed image data"},
        "format": {"type": "string", "description": "Image format: jpeg, png, webp or avif"},
    },
}
TRUTH_SCHEMA = {
    "title": "gauged.synth.Truth",
    "description": "Ground truth of one synthetic frame (see gauged/synth/truth.py and docs/synth.md)",
    "type": "object",
}
ROS2_COMPRESSED_IMAGE = """std_msgs/Header header
string format
uint8[] data
================================================================================
MSG: std_msgs/Header
builtin_interfaces/Time stamp
string frame_id
================================================================================
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec
"""
ROS2_STRING = "string data\n"


@dataclass
class RecordingSummary:
    path: Path
    frames: int
    cameras: tuple[str, ...]
    bytes: int


def _json(obj) -> bytes:
    return json.dumps(obj, separators=(",", ":"), ensure_ascii=False).encode()


def merged_frames(sequences: list[CameraSequence], start_ns: int = EPOCH_NS) -> Iterator[SequenceFrame]:
    """Frames of all cameras, in stamp order (ties broken by camera order)."""
    iters = [((frame.stamp_ns, i, frame.index, frame) for frame in camera_frames(seq, start_ns))
             for i, seq in enumerate(sequences)]
    for _, _, _, frame in heapq.merge(*iters, key=lambda item: item[:3]):
        yield frame


def _progress(total: int, every: int = 20) -> Callable[[int], None]:
    def report(done: int) -> None:
        if done % every == 0 or done == total:
            log.info("rendered %d/%d frames", done, total)

    return report


def write_foxglove(path: Path | str, sequences: list[CameraSequence], *, quality: int = 80,
                   start_ns: int = EPOCH_NS, metadata: dict[str, str] | None = None) -> RecordingSummary:
    """Render ``sequences`` and write them as a Foxglove-JSON MCAP file at ``path``."""
    path = Path(path)
    total = sum(int(s.seconds * s.fps + 1e-9) for s in sequences)
    report = _progress(total)
    count = 0
    with path.open("wb") as stream:
        writer = Writer(stream, chunk_size=1 << 20, compression=CompressionType.ZSTD)
        writer.start(profile="", library="gauged.synth")
        image_schema = writer.register_schema("foxglove.CompressedImage", "jsonschema", _json(COMPRESSED_IMAGE_SCHEMA))
        truth_schema = writer.register_schema("gauged.synth.Truth", "jsonschema", _json(TRUTH_SCHEMA))
        channels = {}
        for seq in sequences:
            channels[seq.camera] = (writer.register_channel(f"/{seq.camera}/image", "json", image_schema),
                                    writer.register_channel(f"/{seq.camera}/truth", "json", truth_schema))
        if metadata:
            writer.add_metadata("gauged.synth", metadata)
        for frame in merged_frames(sequences, start_ns):
            image_ch, truth_ch = channels[frame.camera]
            sec, nsec = divmod(frame.stamp_ns, 1_000_000_000)
            message = {"timestamp": {"sec": sec, "nsec": nsec}, "frame_id": frame.camera, "format": "jpeg",
                       "data": base64.b64encode(encode_jpeg(frame.image, quality)).decode("ascii")}
            writer.add_message(image_ch, frame.stamp_ns, _json(message), frame.stamp_ns, sequence=frame.index)
            writer.add_message(truth_ch, frame.stamp_ns, _json(frame.record), frame.stamp_ns, sequence=frame.index)
            count += 1
            report(count)
        writer.finish()
    return RecordingSummary(path, count, tuple(s.camera for s in sequences), path.stat().st_size)


def write_ros2(path: Path | str, sequences: list[CameraSequence], *, quality: int = 80,
               start_ns: int = EPOCH_NS, metadata: dict[str, str] | None = None) -> RecordingSummary:
    """Render ``sequences`` and write them as a ROS 2 (CDR) MCAP file at ``path``."""
    path = Path(path)
    total = sum(int(s.seconds * s.fps + 1e-9) for s in sequences)
    report = _progress(total)
    count = 0
    with path.open("wb") as stream:
        writer = Ros2Writer(stream)
        image_schema = writer.register_msgdef("sensor_msgs/msg/CompressedImage", ROS2_COMPRESSED_IMAGE)
        truth_schema = writer.register_msgdef("std_msgs/msg/String", ROS2_STRING)
        if metadata:
            writer.add_metadata("gauged.synth", metadata)
        for frame in merged_frames(sequences, start_ns):
            sec, nsec = divmod(frame.stamp_ns, 1_000_000_000)
            message = {"header": {"stamp": {"sec": sec, "nanosec": nsec}, "frame_id": frame.camera},
                       "format": "jpeg", "data": encode_jpeg(frame.image, quality)}
            writer.write_message(f"/{frame.camera}/image", image_schema, message, frame.stamp_ns, frame.stamp_ns,
                                 sequence=frame.index)
            writer.write_message(f"/{frame.camera}/truth", truth_schema, {"data": _json(frame.record).decode()},
                                 frame.stamp_ns, frame.stamp_ns, sequence=frame.index)
            count += 1
            report(count)
        writer.finish()
    return RecordingSummary(path, count, tuple(s.camera for s in sequences), path.stat().st_size)
