"""Turn image messages (compressed or raw, ROS 2 CDR, bare JPEG/PNG) into BGR uint8 arrays.

Two steps, both pure functions over bytes:

1. *parse*: a transport payload becomes an :class:`ImageMessage` (pixel bytes plus format or raw
   layout, and the time the message carries): :func:`parse_payload` for Zenoh payloads (JPEG/PNG
   by encoding or magic bytes, or ROS 2 ``sensor_msgs/msg/CompressedImage`` / ``Image`` in CDR,
   read by :func:`parse_ros_image_cdr`); the MCAP source builds them from its decoded messages.
2. *decode*: :func:`decode_image` makes the ``(H, W, 3)`` uint8 BGR array of :class:`gauged.types.Frame`.

A frame that cannot be used is an :class:`InvalidFrame` value (falsy) with a reason from
:data:`INVALID_REASONS`, used as the ``reason`` label of ``gauged_frames_invalid_total``.
Size limits are checked on the *declared* size before any pixel is decoded, so a crafted header
cannot make the daemon allocate gigabytes.

Example::

    >>> import cv2, numpy as np
    >>> ok, jpeg = cv2.imencode(".jpg", np.zeros((48, 64, 3), np.uint8))
    >>> decode_image(parse_payload(jpeg.tobytes())).shape
    (48, 64, 3)
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

import cv2
import numpy as np

from gauged.config.model import MAX_IMAGE_SIDE_PX

MAX_PAYLOAD_BYTES = 100 * 1024 * 1024  # no camera frame we accept is larger

INVALID_REASONS = (
    "empty",  # no bytes, or a zero width/height
    "too_large",  # more than MAX_PAYLOAD_BYTES or a side above MAX_IMAGE_SIDE_PX
    "undecodable",  # JPEG/PNG bytes the codec refuses
    "unsupported_encoding",  # a format or pixel encoding gauged does not read (h264, 32FC1, ...)
    "size_mismatch",  # raw pixel data shorter than width x height x step says
    "bad_cdr",  # a CDR payload that is neither a ROS 2 CompressedImage nor an Image
    "unknown_format",  # bytes that are no JPEG, PNG or CDR and carry no usable encoding
    "bad_message",  # a recorded message that does not deserialize, or is not an image type
)

JPEG_MAGIC = b"\xff\xd8\xff"
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


@dataclass(frozen=True, slots=True)
class InvalidFrame:
    """Why a frame cannot be used: ``reason`` from :data:`INVALID_REASONS`, ``detail`` for people."""

    reason: str
    detail: str = ""

    def __bool__(self) -> bool:
        return False


@dataclass(frozen=True, slots=True)
class ImageMessage:
    """An image as a message carries it, before pixel decoding.

    ``encoding`` is None for a compressed image (``format`` then says jpeg/png, possibly in ROS
    ``compressed_image_transport`` style such as ``"bgr8; jpeg compressed bgr8"``), else the raw
    pixel encoding (``rgb8``, ``bgr8``, ``mono8``, ``mono16``, ...) with ``width``, ``height`` and
    ``step`` (bytes per row). ``stamp_ns`` is the message's own time, None when it carries none.
    """

    data: bytes
    stamp_ns: int | None = None
    format: str = ""
    encoding: str | None = None
    width: int = 0
    height: int = 0
    step: int = 0
    big_endian: bool = False


def sniff(data: bytes) -> str | None:
    """``"jpeg"``, ``"png"`` or ``"cdr"`` from the first bytes, else None."""
    if data.startswith(JPEG_MAGIC):
        return "jpeg"
    if data.startswith(PNG_MAGIC):
        return "png"
    # CDR encapsulation: representation id 0x0000/0x0001 (CDR BE/LE), options 0x00xx
    if len(data) >= 4 and data[0] == 0 and data[1] in (0, 1) and data[2] == 0:
        return "cdr"
    return None


def parse_payload(payload: bytes, encoding: str = "", key: str = "") -> ImageMessage | InvalidFrame:
    """Classify one Zenoh payload as a compressed image or a ROS 2 CDR image message.

    ``encoding`` is the Zenoh encoding string (``image/jpeg``, ``image/png``, ``application/cdr``,
    or empty); the payload's magic bytes decide when it is absent or generic. ``key`` is the key
    the sample arrived on: rmw_zenoh keys name the ROS type, which is tried first.
    """
    if not payload:
        return InvalidFrame("empty", "payload has no bytes")
    if len(payload) > MAX_PAYLOAD_BYTES:
        return InvalidFrame("too_large", f"payload of {len(payload)} bytes")
    mime = encoding.split(";", 1)[0].strip().lower()
    kind = sniff(payload)
    if kind in ("jpeg", "png"):
        return ImageMessage(data=payload, format=kind)
    if mime.startswith("image/"):
        reason = "undecodable" if mime in ("image/jpeg", "image/png") else "unsupported_encoding"
        return InvalidFrame(reason, f"encoding {mime} but the bytes are not JPEG or PNG")
    if kind == "cdr":
        hint = "compressed" if "compressed" in key.lower() else "raw" if "image" in key.lower() else None
        return parse_ros_image_cdr(payload, hint)
    return InvalidFrame("unknown_format", f"encoding {mime or 'none'}, first bytes {payload[:4].hex()}")


class _CdrReader:
    """Reads CDR primitives; alignment counts from the end of the 4-byte encapsulation header."""

    def __init__(self, body: memoryview, little: bool) -> None:
        self.body, self.pos, self.order = body, 0, "<" if little else ">"

    def _take(self, size: int, align: int) -> memoryview:
        self.pos += -self.pos % align
        if self.pos + size > len(self.body):
            raise ValueError(f"needs {size} bytes at offset {self.pos}, has {len(self.body) - self.pos}")
        out = self.body[self.pos:self.pos + size]
        self.pos += size
        return out

    def u32(self) -> int:
        return struct.unpack(self.order + "I", self._take(4, 4))[0]

    def u8(self) -> int:
        return self._take(1, 1)[0]

    def string(self) -> str:
        raw = self._take(self.u32(), 1)
        if len(raw) == 0 or raw[-1] != 0:
            raise ValueError("string without terminating NUL")
        return bytes(raw[:-1]).decode("utf-8")

    def octets(self) -> bytes:
        return bytes(self._take(self.u32(), 1))

    def stamp_ns(self) -> int:
        sec = struct.unpack(self.order + "i", self._take(4, 4))[0]
        return sec * 1_000_000_000 + self.u32()


def _read_ros_image(r: _CdrReader, kind: str) -> ImageMessage:
    stamp = r.stamp_ns()
    r.string()  # header.frame_id
    if kind == "compressed":
        fmt = r.string()
        data = r.octets()
        message = ImageMessage(data=data, stamp_ns=stamp or None, format=fmt)
    else:
        height, width = r.u32(), r.u32()
        encoding = r.string()
        big_endian = bool(r.u8())
        step = r.u32()
        data = r.octets()
        message = ImageMessage(data=data, stamp_ns=stamp or None, encoding=encoding, width=width,
                               height=height, step=step, big_endian=big_endian)
    if len(r.body) - r.pos > 3:  # serializers pad to a multiple of 4, never more
        raise ValueError(f"{len(r.body) - r.pos} bytes left over")
    return message


def parse_ros_image_cdr(payload: bytes, hint: str | None = None) -> ImageMessage | InvalidFrame:
    """Read a CDR-serialized ``sensor_msgs/msg/CompressedImage`` or ``sensor_msgs/msg/Image``.

    CDR carries no type, so both layouts are tried (``hint`` first: ``"compressed"`` or ``"raw"``)
    and the one that consumes the payload exactly wins; strings must end in NUL, so a payload of
    one type practically never parses as the other.
    """
    if len(payload) < 4 or sniff(payload) != "cdr":
        return InvalidFrame("bad_cdr", f"no CDR encapsulation header (first bytes {payload[:4].hex()})")
    body = memoryview(payload)[4:]
    kinds = ["raw", "compressed"] if hint == "raw" else ["compressed", "raw"]
    errors = []
    for kind in kinds:
        try:
            return _read_ros_image(_CdrReader(body, little=payload[1] == 1), kind)
        except (ValueError, UnicodeDecodeError, struct.error) as err:
            errors.append(f"as {kind}: {err}")
    return InvalidFrame("bad_cdr", "; ".join(errors))


def _jpeg_size(data: bytes) -> tuple[int, int] | None:
    """(width, height) from the first JPEG start-of-frame marker, None if not found."""
    pos = 2
    while pos + 9 <= len(data):
        if data[pos] != 0xFF:
            return None
        marker = data[pos + 1]
        if marker == 0xFF:  # fill byte
            pos += 1
            continue
        length = int.from_bytes(data[pos + 2:pos + 4], "big")
        if 0xC0 <= marker <= 0xCF and marker not in (0xC4, 0xC8, 0xCC):
            height = int.from_bytes(data[pos + 5:pos + 7], "big")
            width = int.from_bytes(data[pos + 7:pos + 9], "big")
            return width, height
        pos += 2 + length
    return None


def _declared_size(data: bytes, kind: str) -> tuple[int, int] | None:
    if kind == "png":
        return (int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")) if len(data) >= 24 else None
    return _jpeg_size(data)


def _check_size(width: int, height: int) -> InvalidFrame | None:
    if width <= 0 or height <= 0:
        return InvalidFrame("empty", f"image of {width}x{height} px")
    if width > MAX_IMAGE_SIDE_PX or height > MAX_IMAGE_SIDE_PX:
        return InvalidFrame("too_large", f"image of {width}x{height} px (limit {MAX_IMAGE_SIDE_PX} px a side)")
    return None


def decode_compressed(data: bytes, format: str = "") -> np.ndarray | InvalidFrame:
    """Decode JPEG or PNG bytes (recognised by their magic bytes) to (H, W, 3) uint8 BGR."""
    if not data:
        return InvalidFrame("empty", "compressed image has no bytes")
    if len(data) > MAX_PAYLOAD_BYTES:
        return InvalidFrame("too_large", f"compressed image of {len(data)} bytes")
    kind = sniff(data)
    if kind not in ("jpeg", "png"):
        fmt = format.lower()
        reason = "undecodable" if ("jpeg" in fmt or "jpg" in fmt or "png" in fmt or not fmt) else "unsupported_encoding"
        return InvalidFrame(reason, f"format {format!r}, first bytes {data[:4].hex()} are not JPEG or PNG")
    size = _declared_size(data, kind)
    if size is None:
        return InvalidFrame("undecodable", f"{kind} without a readable size header")
    if (bad := _check_size(*size)) is not None:
        return bad
    image = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_COLOR)
    if image is None or image.size == 0:
        return InvalidFrame("undecodable", f"{kind} of {len(data)} bytes does not decode")
    return image


# encoding -> (bytes per pixel, channels of the row view, OpenCV conversion to BGR or None)
_RAW_LAYOUTS: dict[str, tuple[int, int, int | None]] = {
    "bgr8": (3, 3, None), "8uc3": (3, 3, None),
    "rgb8": (3, 3, cv2.COLOR_RGB2BGR),
    "bgra8": (4, 4, cv2.COLOR_BGRA2BGR), "8uc4": (4, 4, cv2.COLOR_BGRA2BGR),
    "rgba8": (4, 4, cv2.COLOR_RGBA2BGR),
    "mono8": (1, 1, cv2.COLOR_GRAY2BGR), "8uc1": (1, 1, cv2.COLOR_GRAY2BGR),
    "mono16": (2, 1, cv2.COLOR_GRAY2BGR), "16uc1": (2, 1, cv2.COLOR_GRAY2BGR),
    "yuyv": (2, 2, cv2.COLOR_YUV2BGR_YUYV), "yuv422_yuy2": (2, 2, cv2.COLOR_YUV2BGR_YUYV),
    "uyvy": (2, 2, cv2.COLOR_YUV2BGR_UYVY), "yuv422": (2, 2, cv2.COLOR_YUV2BGR_UYVY),
    # ROS names the first 2x2 pattern; OpenCV names the pattern one pixel further (cv_bridge's mapping).
    "bayer_rggb8": (1, 1, cv2.COLOR_BayerBG2BGR), "bayer_bggr8": (1, 1, cv2.COLOR_BayerRG2BGR),
    "bayer_gbrg8": (1, 1, cv2.COLOR_BayerGR2BGR), "bayer_grbg8": (1, 1, cv2.COLOR_BayerGB2BGR),
}


def decode_raw(data: bytes, width: int, height: int, encoding: str, step: int = 0,
               big_endian: bool = False) -> np.ndarray | InvalidFrame:
    """Raw pixels (ROS ``sensor_msgs/Image`` / ``foxglove.RawImage`` layout) to (H, W, 3) uint8 BGR.

    ``step`` is the byte length of one row (0: tightly packed). 16-bit mono keeps its top 8 bits.
    """
    if (bad := _check_size(width, height)) is not None:
        return bad
    layout = _RAW_LAYOUTS.get(encoding.lower())
    if layout is None:
        return InvalidFrame("unsupported_encoding", f"raw pixel encoding {encoding!r}")
    bpp, channels, conversion = layout
    row = width * bpp
    step = step or row
    if len(data) > MAX_PAYLOAD_BYTES:
        return InvalidFrame("too_large", f"raw image of {len(data)} bytes")
    if step < row or len(data) < step * (height - 1) + row:
        return InvalidFrame("size_mismatch", f"{encoding} {width}x{height} step {step} needs "
                            f"{step * (height - 1) + row} bytes, has {len(data)}")
    buf = np.frombuffer(data, np.uint8, count=step * (height - 1) + row)
    rows = np.lib.stride_tricks.as_strided(buf, shape=(height, row), strides=(step, 1))
    packed = np.ascontiguousarray(rows)
    if bpp == 2 and channels == 1:
        pixels = (packed.view(">u2" if big_endian else "<u2") >> 8).astype(np.uint8)
    else:
        pixels = packed.reshape((height, width) if channels == 1 else (height, width, channels))
    image = pixels if conversion is None else cv2.cvtColor(pixels, conversion)
    return np.ascontiguousarray(image)


def decode_image(message: ImageMessage) -> np.ndarray | InvalidFrame:
    """The BGR pixels of an image message (compressed or raw)."""
    if message.encoding is None:
        return decode_compressed(message.data, message.format)
    return decode_raw(message.data, message.width, message.height, message.encoding, message.step,
                      message.big_endian)
