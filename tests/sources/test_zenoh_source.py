"""Zenoh source over real sessions on loopback: JPEG, ROS 2 CDR on wildcard keys, drops, bad frames."""

from __future__ import annotations

import threading
import time

import cv2
import numpy as np
import pytest
import zenoh

from gauged.metrics import Metrics
from gauged.sources.zenoh_source import ZenohSource

RMW_HASH = "RIHS01_a5ba9a4fc6aa1a8a3a1ed4d7da62e6e4e6b0a6c7c5e2c6b6d4e0f7b2ef4d9c1a"


def picture(seed: int) -> np.ndarray:
    img = np.full((48, 64, 3), 90, np.uint8)
    cv2.rectangle(img, (5 + seed, 5), (30 + seed, 40), (20, 200, 240), -1)
    return img


def jpeg(img: np.ndarray) -> bytes:
    return cv2.imencode(".jpg", img, [cv2.IMWRITE_JPEG_QUALITY, 95])[1].tobytes()


def decoded(data: bytes) -> np.ndarray:
    return cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_COLOR)


def wait_for(predicate, timeout: float = 5.0) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(0.01)
    return predicate()


@pytest.fixture
def source_of(zenoh_pair):
    """``source_of(key) -> (source, metrics, publisher session)``; stopped after the test."""
    daemon, peer = zenoh_pair
    made = []

    def make(key: str):
        metrics = Metrics()
        source = ZenohSource("cam1", daemon, key, metrics=metrics)
        source.start()
        made.append(source)
        time.sleep(0.3)  # let the subscription reach the peer before it publishes
        return source, metrics, peer

    yield make
    for source in made:
        source.stop()


def test_jpeg_bytes_become_frames_stamped_by_the_receive_clock(source_of):
    source, metrics, peer = source_of("site/cam1/image")
    data = jpeg(picture(0))
    before = time.time_ns()
    peer.put("site/cam1/image", data, encoding=zenoh.Encoding.IMAGE_JPEG)
    frame = source.next_frame(5.0)
    after = time.time_ns()
    assert frame is not None and frame.camera == "cam1" and frame.frame_id == 0
    assert np.array_equal(frame.image, decoded(data))
    assert before - 50_000_000 <= frame.stamp_ns <= after + 50_000_000
    assert metrics.value("gauged_frames_received_total", camera="cam1") == 1


def test_ros2_compressed_image_on_an_rmw_zenoh_key_with_hash_suffix(source_of, cdr):
    source, _, peer = source_of("0/cam1/image/compressed/**")
    data = jpeg(picture(3))
    payload = cdr.compressed({"header": {"stamp": {"sec": 1_700_000_123, "nanosec": 456},
                                         "frame_id": "cam1_optical"}, "format": "jpeg", "data": data})
    peer.put(f"0/cam1/image/compressed/sensor_msgs::msg::dds_::CompressedImage_/{RMW_HASH}", payload)
    frame = source.next_frame(5.0)
    assert frame is not None and frame.stamp_ns == 1_700_000_123 * 10**9 + 456
    assert np.array_equal(frame.image, decoded(data))


def test_ros2_raw_image_pixels_are_exact(source_of, cdr):
    source, _, peer = source_of("cam1/image_raw")
    img = picture(5)
    rgb = cv2.cvtColor(img, cv2.COLOR_BGR2RGB)
    payload = cdr.raw({"header": {"stamp": {"sec": 12, "nanosec": 34}, "frame_id": "f"}, "height": 48, "width": 64,
                       "encoding": "rgb8", "is_bigendian": 0, "step": 64 * 3, "data": rgb.tobytes()})
    peer.put("cam1/image_raw", payload)  # zenoh-bridge-ros2dds style: bare topic, no encoding
    frame = source.next_frame(5.0)
    assert frame is not None and frame.stamp_ns == 12 * 10**9 + 34 and np.array_equal(frame.image, img)


def test_zenoh_sample_timestamp_is_used_when_present(source_of):
    source, _, peer = source_of("site/cam1/image")
    stamp = peer.new_timestamp()
    peer.put("site/cam1/image", cv2.imencode(".png", picture(1))[1].tobytes(), timestamp=stamp)
    frame = source.next_frame(5.0)
    assert frame is not None and frame.stamp_ns == stamp.get_time_as_ntp64().as_nanos()


def test_newest_frame_wins_and_drops_are_counted(source_of):
    source, metrics, peer = source_of("site/cam1/image")
    for i in range(5):
        peer.put("site/cam1/image", jpeg(picture(4 * i)))
    assert wait_for(lambda: metrics.value("gauged_frames_received_total", camera="cam1") == 5)
    frame = source.next_frame(1.0)
    assert frame is not None and frame.frame_id == 4
    assert source.next_frame(0.2) is None
    assert metrics.value("gauged_frames_dropped_total", camera="cam1") == 4


def test_bad_frames_are_counted_and_the_source_goes_on(source_of, caplog):
    source, metrics, peer = source_of("site/cam1/image")
    bad = [(b"\xff\xd8\xff\xe0 broken jpeg", zenoh.Encoding.IMAGE_JPEG), (b"{\"not\": \"an image\"}",
           zenoh.Encoding.APPLICATION_JSON), (b"\x00\x01\x00\x00\x05", None)]
    reasons = ["undecodable", "unknown_format", "bad_cdr"]
    for (payload, encoding), reason in zip(bad, reasons):
        peer.put("site/cam1/image", payload, encoding=encoding)
        # each bad frame is taken, counted under its reason and skipped: no frame comes out
        assert wait_for(lambda: source.next_frame(0.05) is None
                        and metrics.value("gauged_frames_invalid_total", camera="cam1", reason=reason) == 1)
    peer.put("site/cam1/image", jpeg(picture(2)))
    frame = source.next_frame(5.0)
    assert frame is not None and frame.frame_id == 3
    assert metrics.value("gauged_frames_dropped_total", camera="cam1") == 0
    assert any("camera cam1: invalid frame" in r.getMessage() for r in caplog.records)


def test_stop_wakes_a_waiting_consumer(source_of):
    source, _, _ = source_of("site/cam1/image")
    started = time.monotonic()
    threading.Timer(0.2, source.stop).start()
    assert source.next_frame(10.0) is None
    assert time.monotonic() - started < 5.0
