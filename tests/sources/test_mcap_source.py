"""MCAP replay: every image flavour, stamps, pacing, loop, damage and bad frames."""

from __future__ import annotations

import logging
import time

import cv2
import numpy as np
import pytest
from gauged.metrics import Metrics
from gauged.sources.mcap_read import McapMessages
from gauged.sources.mcap_source import McapSource, iter_frames


FLAVOURS = ["foxglove-compressed-json", "foxglove-raw-json", "foxglove-compressed-protobuf",
            "foxglove-raw-protobuf", "ros2-compressed", "ros2-raw"]


def drain(source: McapSource, timeout: float = 10.0) -> list:
    frames, deadline = [], time.monotonic() + timeout
    while not source.finished and time.monotonic() < deadline:
        frame = source.next_frame(0.2)
        if frame is not None:
            frames.append(frame)
    return frames


@pytest.mark.parametrize("flavour", FLAVOURS)
def test_iter_frames_reads_every_flavour_with_stamps_and_pixels(recording, flavour):
    path, rec = recording(flavour, 3)
    frames = list(iter_frames(path, "/cam1/image", camera="cam1"))
    assert [f.stamp_ns for f in frames] == rec.stamps
    assert [f.frame_id for f in frames] == [0, 1, 2]
    for frame, image, payload in zip(frames, rec.images, rec.payloads):
        assert frame.camera == "cam1" and frame.image.dtype == np.uint8 and frame.image.shape == image.shape
        if "compressed" in flavour:
            assert np.array_equal(frame.image, cv2.imdecode(np.frombuffer(payload, np.uint8), cv2.IMREAD_COLOR))
            assert np.abs(frame.image.astype(int) - image).mean() < 3
        else:
            assert np.array_equal(frame.image, image)


@pytest.mark.parametrize("flavour", ["foxglove-compressed-json", "ros2-raw", "foxglove-raw-protobuf"])
def test_iter_frames_falls_back_to_log_time_without_stamp(recording, flavour):
    path, rec = recording(flavour, 2, zero_stamp=True)
    assert [f.stamp_ns for f in iter_frames(path, "/cam1/image")] == rec.log_times


def test_mcap_source_fast_hands_over_every_frame_in_order(recording):
    path, rec = recording("ros2-compressed", 12)
    metrics = Metrics()
    source = McapSource("cam1", path, "/cam1/image", pace="fast", metrics=metrics)
    source.start()
    try:
        frames = drain(source)
    finally:
        source.stop()
    assert [f.stamp_ns for f in frames] == rec.stamps
    assert metrics.value("gauged_frames_received_total", camera="cam1") == 12
    assert metrics.value("gauged_frames_dropped_total", camera="cam1") == 0


def test_mcap_source_realtime_paces_by_log_time_and_counts_drops(recording):
    path, rec = recording("foxglove-raw-json", 6, period_ns=80_000_000)
    metrics = Metrics()
    source = McapSource("cam1", path, "/cam1/image", pace="realtime", metrics=metrics)
    started = time.monotonic()
    source.start()
    try:
        first = source.next_frame(5.0)
        time.sleep(0.6)  # a slow reader: 5 frames arrive meanwhile, only the newest survives
        last = source.next_frame(5.0)
        elapsed = time.monotonic() - started
    finally:
        source.stop()
    assert first is not None and first.stamp_ns == rec.stamps[0]
    assert last is not None and last.stamp_ns == rec.stamps[-1]
    assert elapsed >= 0.4  # 5 intervals of 80 ms of log time
    assert metrics.value("gauged_frames_received_total", camera="cam1") == 6
    assert metrics.value("gauged_frames_dropped_total", camera="cam1") == 4


def test_mcap_source_loop_keeps_stamps_increasing(recording):
    path, rec = recording("foxglove-compressed-protobuf", 3, period_ns=10_000_000)
    source = McapSource("cam1", path, "/cam1/image", pace="fast", loop=True)
    source.start()
    try:
        frames = [source.next_frame(5.0) for _ in range(7)]
        assert not source.finished  # a looping replay never ends by itself
    finally:
        source.stop()
    stamps = [f.stamp_ns for f in frames]
    span = rec.log_times[-1] - rec.log_times[0] + 10_000_000
    assert stamps[:3] == rec.stamps
    assert stamps[3:6] == [s + span for s in rec.stamps]
    assert stamps[6] == rec.stamps[0] + 2 * span


def test_truncated_recording_is_read_up_to_the_damage(recording, caplog):
    path, rec = recording("foxglove-raw-json", 40, chunk_size=30_000)
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    with caplog.at_level(logging.ERROR):
        frames = list(iter_frames(path, "/cam1/image"))
    assert 0 < len(frames) < 40
    assert [f.stamp_ns for f in frames] == rec.stamps[: len(frames)]
    assert all(np.array_equal(f.image, img) for f, img in zip(frames, rec.images))
    assert any("damaged at about byte" in r.getMessage() for r in caplog.records)


def test_corrupt_chunk_in_finished_recording_stops_there(recording):
    path, rec = recording("ros2-raw", 30, chunk_size=20_000)
    data = bytearray(path.read_bytes())
    middle = len(data) // 2
    data[middle:middle + 64] = bytes(64)  # zero out part of a chunk in the middle
    path.write_bytes(bytes(data))
    messages = McapMessages(path, ["/cam1/image"])
    read = [m.log_time for _, _, m in messages]
    assert messages.finished_file
    assert messages.damage is not None and "damaged" in messages.damage
    assert read == rec.log_times[: len(read)] and 0 < len(read) < 30


def test_mcap_source_ends_cleanly_on_damaged_and_missing_files(recording, tmp_path, caplog):
    path, _ = recording("ros2-compressed", 10, chunk_size=2_000)
    data = path.read_bytes()
    path.write_bytes(data[: 2 * len(data) // 3])
    intact, _ = recording("ros2-raw", 2)
    sources = [McapSource("cam1", path, "/cam1/image", pace="fast"),
               McapSource("cam2", tmp_path / "absent.mcap", "/cam1/image", pace="fast", loop=True),
               McapSource("cam3", intact, "/no/such/topic", pace="fast")]
    with caplog.at_level(logging.ERROR):
        for source in sources:
            source.start()
        counts = [len(drain(source)) for source in sources]
        for source in sources:
            source.stop()
    assert 0 < counts[0] < 10 and counts[1:] == [0, 0]
    assert all(source.finished for source in sources)
    text = "\n".join(r.getMessage() for r in caplog.records)
    assert "cannot open" in text and "no message on topic /no/such/topic (topics: /cam1/image)" in text


def test_bad_frames_are_counted_and_skipped(recording):
    def plant(i: int) -> bytes | None:
        return {1: b"\xff\xd8\xff\xe0garbage", 2: b"", 3: b"not an image at all"}.get(i)

    path, rec = recording("foxglove-compressed-json", 5, extra=plant)
    metrics = Metrics()
    frames = list(iter_frames(path, "/cam1/image", camera="cam1", metrics=metrics))
    assert [f.stamp_ns for f in frames] == [rec.stamps[0], rec.stamps[4]]
    assert metrics.value("gauged_frames_invalid_total", camera="cam1", reason="undecodable") == 2
    assert metrics.value("gauged_frames_invalid_total", camera="cam1", reason="empty") == 1


def test_raw_frame_of_wrong_size_is_counted(recording):
    path, _ = recording("ros2-raw", 3, extra=lambda i: b"\x00" * 100 if i == 1 else None)
    metrics = Metrics()
    frames = list(iter_frames(path, "/cam1/image", camera="cam1", metrics=metrics))
    assert [f.frame_id for f in frames] == [0, 2]
    assert metrics.value("gauged_frames_invalid_total", camera="cam1", reason="size_mismatch") == 1
