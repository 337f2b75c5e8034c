"""Image decoding: JPEG/PNG, raw encodings, ROS 2 CDR, and every invalid-frame reason."""

from __future__ import annotations

import struct

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gauged.sources.image_decode import (
    INVALID_REASONS,
    MAX_PAYLOAD_BYTES,
    ImageMessage,
    InvalidFrame,
    decode_compressed,
    decode_image,
    decode_raw,
    parse_payload,
    parse_ros_image_cdr,
)


def image(h: int = 30, w: int = 40, seed: int = 0) -> np.ndarray:
    return np.random.default_rng(seed).integers(0, 256, (h, w, 3), dtype=np.uint8)


def encode(img: np.ndarray, ext: str) -> bytes:
    ok, buf = cv2.imencode(ext, img)
    assert ok
    return buf.tobytes()


def reason(result: object) -> str:
    assert isinstance(result, InvalidFrame) and not result, result
    assert result.reason in INVALID_REASONS
    return result.reason


def test_decode_png_and_jpeg_by_magic_bytes():
    img = image()
    assert np.array_equal(decode_image(parse_payload(encode(img, ".png"))), img)
    jpg = decode_image(parse_payload(encode(img, ".jpg"), "image/jpeg"))
    assert jpg.shape == img.shape and jpg.dtype == np.uint8


def test_decode_gray_png_becomes_bgr():
    gray = image()[:, :, 0]
    out = decode_compressed(encode(gray, ".png"), "png")
    assert out.shape == (30, 40, 3) and np.array_equal(out[:, :, 1], gray)


@pytest.mark.parametrize("encoding, convert", [
    ("bgr8", None), ("rgb8", cv2.COLOR_BGR2RGB), ("bgra8", cv2.COLOR_BGR2BGRA), ("rgba8", cv2.COLOR_BGR2RGBA)])
def test_decode_raw_colour_encodings_round_trip(encoding, convert):
    img = image()
    pixels = img if convert is None else cv2.cvtColor(img, convert)
    out = decode_raw(pixels.tobytes(), 40, 30, encoding)
    assert np.array_equal(out, img)


def test_decode_raw_honours_row_padding():
    img = image(5, 7)
    padded = np.zeros((5, 7 * 3 + 11), np.uint8)
    padded[:, :21] = img.reshape(5, 21)
    assert np.array_equal(decode_raw(padded.tobytes(), 7, 5, "bgr8", step=32), img)


@pytest.mark.parametrize("big_endian", [False, True])
def test_decode_mono16_keeps_top_byte(big_endian):
    values = np.arange(0, 65536, 4369, dtype=np.uint16).reshape(4, 4)
    data = values.astype(">u2" if big_endian else "<u2").tobytes()
    out = decode_raw(data, 4, 4, "mono16", big_endian=big_endian)
    assert np.array_equal(out[:, :, 0], (values >> 8).astype(np.uint8))


def test_decode_mono8_and_yuyv():
    gray = image(6, 8)[:, :, 0]
    assert np.array_equal(decode_raw(gray.tobytes(), 8, 6, "mono8")[:, :, 2], gray)
    yuyv = np.full((6, 8, 2), 128, np.uint8)
    yuyv[:, :, 0] = 200  # Y = 200, U = V = 128: a neutral grey, video range (BT.601: 1.164 (Y - 16))
    out = decode_raw(yuyv.tobytes(), 8, 6, "yuyv")
    assert out.shape == (6, 8, 3) and np.all(np.abs(out.astype(int) - round(1.164 * (200 - 16))) <= 1)


def test_invalid_reasons_each_provoked():
    png = encode(image(), ".png")
    huge = bytearray(png)
    huge[16:20] = (20000).to_bytes(4, "big")  # IHDR width: checked before any pixel is decoded
    assert reason(parse_payload(b"")) == "empty"
    assert reason(decode_raw(b"", 0, 10, "mono8")) == "empty"
    assert reason(decode_compressed(bytes(huge))) == "too_large"
    assert reason(decode_raw(b"\0" * 10, 20000, 10, "mono8")) == "too_large"
    assert reason(parse_payload(b"\xff\xd8\xff" + bytes(MAX_PAYLOAD_BYTES))) == "too_large"
    assert reason(decode_compressed(b"\xff\xd8\xff\xe0" + bytes(40))) == "undecodable"
    assert reason(decode_compressed(png[:-40] + bytes(40))) == "undecodable"
    assert reason(parse_payload(b"GIF89a....", "image/jpeg")) == "undecodable"
    assert reason(parse_payload(b"RIFF....WEBP", "image/webp")) == "unsupported_encoding"
    assert reason(decode_compressed(b"\x00\x00\x00\x01\x67", "h264")) == "unsupported_encoding"
    assert reason(decode_raw(bytes(40), 10, 1, "32FC1")) == "unsupported_encoding"
    assert reason(decode_raw(bytes(10), 10, 10, "mono8")) == "size_mismatch"
    assert reason(parse_payload(b"\x00\x01\x00\x00" + bytes(7))) == "bad_cdr"
    assert reason(parse_payload(b"hello world", "text/plain")) == "unknown_format"


def _compressed(cdr, stamp: tuple[int, int], frame_id: str, fmt: str, data: bytes) -> bytes:
    return cdr.compressed({"header": {"stamp": {"sec": stamp[0], "nanosec": stamp[1]}, "frame_id": frame_id},
                           "format": fmt, "data": data})


@settings(max_examples=60, deadline=None)
@given(sec=st.integers(1, 2**31 - 1), nsec=st.integers(0, 999_999_999), frame_id=st.text(max_size=9),
       fmt=st.sampled_from(["jpeg", "png", "bgr8; jpeg compressed bgr8"]), data=st.binary(max_size=64))
def test_cdr_compressed_image_round_trip(cdr, sec, nsec, frame_id, fmt, data):
    message = parse_ros_image_cdr(_compressed(cdr, (sec, nsec), frame_id, fmt, data))
    assert isinstance(message, ImageMessage)
    assert (message.stamp_ns, message.format, message.data, message.encoding) == (sec * 10**9 + nsec, fmt, data, None)


@settings(max_examples=60, deadline=None)
@given(h=st.integers(1, 6), w=st.integers(1, 6), pad=st.integers(0, 5), frame_id=st.text(max_size=9),
       encoding=st.sampled_from(["rgb8", "bgr8", "mono8"]), hint=st.sampled_from([None, "raw", "compressed"]))
def test_cdr_image_round_trip_whatever_the_hint(cdr, h, w, pad, frame_id, encoding, hint):
    channels = 1 if encoding == "mono8" else 3
    step = w * channels + pad
    data = bytes(range(256)) * ((h * step) // 256 + 1)
    raw = cdr.raw({"header": {"stamp": {"sec": 3, "nanosec": 4}, "frame_id": frame_id}, "height": h, "width": w,
                   "encoding": encoding, "is_bigendian": 0, "step": step, "data": data[: h * step]})
    message = parse_ros_image_cdr(raw, hint)
    assert isinstance(message, ImageMessage)
    assert (message.width, message.height, message.step, message.encoding) == (w, h, step, encoding)
    assert decode_image(message).shape == (h, w, 3)


def test_cdr_big_endian_compressed_image():
    body = struct.pack(">iI", 7, 9) + struct.pack(">I", 2) + b"c\0" + b"\0\0" + struct.pack(">I", 5) + b"jpeg\0" \
        + b"\0\0\0" + struct.pack(">I", 3) + b"\xff\xd8\xff"
    message = parse_ros_image_cdr(b"\x00\x00\x00\x00" + body)
    assert isinstance(message, ImageMessage) and message.stamp_ns == 7 * 10**9 + 9 and message.data == b"\xff\xd8\xff"


def test_cdr_with_zero_stamp_has_no_stamp(cdr):
    message = parse_payload(_compressed(cdr, (0, 0), "cam", "jpeg", b"x"), "", "cam/CompressedImage")
    assert isinstance(message, ImageMessage) and message.stamp_ns is None
