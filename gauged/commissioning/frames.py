"""The frames a commissioning reads: from a photo, from each image topic of an MCAP recording, or from a
live Zenoh key, with the ``source:`` block the written config gives each camera.

A recording or live camera gives up to ``count`` frames per camera, at least ``every_s`` seconds of frame
time apart, so the frames show the needle in several places and one bad frame cannot decide a scale.
A source that is no photo or recording (or is damaged before its first frame) raises :class:`BadSource`
(the command exits 2); a live key that gives no frame in time raises :class:`NoFrames` (exit 1).
"""

from __future__ import annotations

import logging
import re
import time
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import Any

import cv2
from gauged.sources.image_decode import JPEG_MAGIC, PNG_MAGIC
from gauged.sources.mailbox import FrameMailbox, Pending
from gauged.sources.mcap_read import MCAP_MAGIC, ImageDecoder, McapMessages
from gauged.types import Frame

log = logging.getLogger(__name__)

ZENOH_PREFIX = "zenoh:"  # SOURCE "zenoh:<key expression>" is a live camera
IMAGE_SCHEMAS = frozenset({"foxglove.CompressedImage", "foxglove.RawImage",
                           "sensor_msgs/msg/CompressedImage", "sensor_msgs/msg/Image"})
# topic or key segments that name the message, not the camera (/cam1/image/compressed -> cam1)
GENERIC_SEGMENTS = frozenset({"image", "image_raw", "image_rect", "image_color", "image_rect_color",
                              "compressed", "raw", "color"})


class BadSource(Exception):
    """SOURCE is not a photo, a recording or a key expression frames can be taken from."""


class NoFrames(Exception):
    """A live source gave no frame: no session could be opened, or no frame arrived in time."""


@dataclass
class CameraFrames:
    """The frames of one camera and the ``source:`` block of its camera in the written config."""

    camera: str
    source: dict[str, Any]
    frames: list[Frame] = field(default_factory=list)
    note: str | None = None  # what the operator should know of this source (damage, fewer frames)


def camera_id(name: str, fallback: str = "cam1") -> str:
    """A camera id (config pattern ``[A-Za-z0-9_.-]+``) from a topic or key: the segments that are not
    wildcards, ROS domain ids, type names or generic image words, joined by ``-``.

    >>> camera_id("/cam1/image"), camera_id("0/plant/cam2/image/compressed/**"), camera_id("/image_raw")
    ('cam1', 'plant-cam2', 'cam1')
    """
    kept = [s for s in name.split("/") if s and "*" not in s and "::" not in s and not s.isdigit()
            and not s.startswith("RIHS") and s.lower() not in GENERIC_SEGMENTS]
    cleaned = re.sub(r"[^A-Za-z0-9_.-]+", "_", "-".join(kept)).strip("_-.")
    return cleaned or fallback


def sniff_file(path: Path) -> str:
    """``"photo"`` or ``"mcap"`` from a file's first bytes; :class:`BadSource` naming the file otherwise."""
    if not path.exists():
        raise BadSource(f"{path}: no such file")
    if not path.is_file():
        raise BadSource(f"{path}: not a file (a photo, an MCAP recording or zenoh:<key expression>)")
    try:
        with path.open("rb") as stream:
            head = stream.read(len(MCAP_MAGIC))
    except OSError as err:
        raise BadSource(f"{path}: cannot read: {err}") from err
    if head.startswith(JPEG_MAGIC) or head.startswith(PNG_MAGIC):
        return "photo"
    if head == MCAP_MAGIC:
        return "mcap"
    what = "an empty file" if not head else f"first bytes {head.hex()}"
    raise BadSource(f"{path}: not a photo (JPEG/PNG) or an MCAP recording ({what})")


def photo_frames(path: Path, camera: str) -> CameraFrames:
    """The one frame of a photo; a truncated or undecodable image raises :class:`BadSource`."""
    from PIL import Image

    try:  # OpenCV decodes a truncated JPEG with a warning and grey rows; Pillow refuses it
        with Image.open(path) as image:
            image.load()
    except Exception as err:  # noqa: BLE001 - any decoder complaint is a damaged photo
        raise BadSource(f"{path}: damaged or truncated image ({err})") from err
    image = cv2.imread(str(path), cv2.IMREAD_COLOR)
    if image is None:
        raise BadSource(f"{path}: cannot decode the image")
    source = {"type": "zenoh", "key": f"TODO/{camera}/image"}  # a photo names no camera source
    frame = Frame(image=image, stamp_ns=0, camera=camera, frame_id=0)
    return CameraFrames(camera, source, [frame], note="a photo names no camera: set the source's Zenoh key")


def _image_topics(path: Path) -> tuple[dict[str, str], McapMessages]:
    """Image topic -> schema name of a recording, from a first pass that stops once every channel was seen."""
    messages = McapMessages(path)
    found: dict[str, str] = {}
    seen: set[str] = set()
    for schema, channel, _message in messages:
        if channel.topic not in seen:
            seen.add(channel.topic)
            if schema is not None and schema.name in IMAGE_SCHEMAS:
                found[channel.topic] = schema.name
            if messages.finished_file and seen >= messages.topics_seen:
                break  # the summary listed every channel: each has been seen once
    return found, messages


def mcap_frames(path: Path, count: int, every_s: float, topics: list[str] | None = None) -> list[CameraFrames]:
    """Up to ``count`` frames of each image topic of the recording, ``every_s`` apart in frame time."""
    found, first = _image_topics(path)
    if first.damage and not found:
        raise BadSource(f"{first.damage}: truncated or damaged before any image")
    if topics:
        missing = [t for t in topics if t not in found]
        if missing:
            raise BadSource(f"{path}: no image topic {', '.join(missing)} (image topics: {', '.join(sorted(found)) or 'none'})")
        found = {t: found[t] for t in topics}
    if not found:
        raise BadSource(f"{path}: no image topic (topics: {', '.join(sorted(first.topics_seen)) or 'none'})")
    cameras: dict[str, CameraFrames] = {}
    for topic in sorted(found):
        name = camera_id(topic, f"cam{len(cameras) + 1}")
        while name in {c.camera for c in cameras.values()}:
            name += "_"
        cameras[topic] = CameraFrames(name, {"type": "mcap", "path": str(path), "topic": topic,
                                             "pace": "realtime", "loop": False})
    mailboxes = {t: FrameMailbox(c.camera) for t, c in cameras.items()}
    decoder = ImageDecoder()
    messages = McapMessages(path, list(cameras))
    last: dict[str, int] = {}
    for seq, (schema, channel, message) in enumerate(messages):
        camera = cameras[channel.topic]
        if len(camera.frames) >= count:
            if all(len(c.frames) >= count for c in cameras.values()):
                break
            continue
        if channel.topic in last and message.log_time - last[channel.topic] < every_s * 1e9 * 0.999:
            continue  # log time first: most messages are skipped without decoding them
        frame = mailboxes[channel.topic].decode(
            Pending(seq, partial(decoder.parse, schema, channel, message), message.log_time))
        if frame is not None:
            camera.frames.append(frame)
            last[channel.topic] = message.log_time
    for camera in cameras.values():
        if messages.damage:
            camera.note = f"{messages.damage}; {len(camera.frames)} frame(s) read before it"
        if len(camera.frames) < count:
            log.info("camera %s: %d frame(s) of %s used (asked for %d)", camera.camera, len(camera.frames),
                     camera.source["topic"], count)
    if not any(c.frames for c in cameras.values()):
        raise BadSource(f"{messages.damage}: truncated or damaged before any image" if messages.damage
                        else f"{path}: no decodable frame on {', '.join(cameras)}")
    return [c for c in cameras.values() if c.frames]


def zenoh_frames(key: str, count: int, every_s: float, timeout_s: float, zenoh: Any,
                 camera: str | None = None) -> CameraFrames:
    """Up to ``count`` frames from a Zenoh key expression, ``every_s`` apart, within ``timeout_s``
    seconds. ``zenoh`` is the :class:`~gauged.config.model.ZenohConfig` of the session."""
    import zenoh as zenoh_lib

    from gauged.sources.zenoh_session import open_session
    from gauged.sources.zenoh_source import ZenohSource

    name = camera or camera_id(key)
    try:
        session = open_session(zenoh)
    except zenoh_lib.ZError as err:
        raise NoFrames(f"{ZENOH_PREFIX}{key}: cannot open a Zenoh session ({err})") from err
    try:
        source = ZenohSource(name, session, key)
        try:
            source.start()
        except zenoh_lib.ZError as err:
            raise BadSource(f"{ZENOH_PREFIX}{key}: not a usable key expression ({err})") from err
        result = CameraFrames(name, {"type": "zenoh", "key": key})
        deadline = time.monotonic() + timeout_s
        while len(result.frames) < count and (left := deadline - time.monotonic()) > 0:
            frame = source.next_frame(timeout=min(left, 0.5))
            if frame is None:
                continue
            if result.frames and frame.stamp_ns - result.frames[-1].stamp_ns < every_s * 1e9 * 0.999:
                continue
            result.frames.append(frame)
        source.stop()
    finally:
        session.close()
    if not result.frames:
        raise NoFrames(f"{ZENOH_PREFIX}{key}: no frame arrived in {timeout_s:g} s")
    if len(result.frames) < count:
        result.note = f"only {len(result.frames)} frame(s) arrived in {timeout_s:g} s"
    return result


def source_frames(source: str, count: int, every_s: float, *, topics: list[str] | None = None,
                  camera: str | None = None, timeout_s: float = 30.0, zenoh: Any = None) -> list[CameraFrames]:
    """The frames of SOURCE: ``zenoh:<key>`` (a live camera), else a photo or an MCAP recording by its
    first bytes (not its name). ``camera`` names the camera of a photo or a key; a recording's cameras
    are named after its image topics, of which ``topics`` selects some."""
    if source.startswith(ZENOH_PREFIX):
        key = source[len(ZENOH_PREFIX):].strip()
        if not key:
            raise BadSource(f"{source}: no key expression after {ZENOH_PREFIX}")
        return [zenoh_frames(key, count, every_s, timeout_s, zenoh, camera)]
    path = Path(source)
    if sniff_file(path) == "photo":
        return [photo_frames(path, camera or "cam1")]
    return mcap_frames(path, count, every_s, topics)
