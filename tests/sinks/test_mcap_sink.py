"""MCAP sink: channels and schemas read back with mcap's reader, rotation, and crash/stop durability."""

from __future__ import annotations

import base64
import json
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import cv2
import numpy as np
import pytest
from mcap.exceptions import McapError
from mcap.reader import NonSeekingReader, make_reader

from gauged.sinks.buffered import BufferedSink
from gauged.sinks.mcap_sink import McapSink
from gauged.sources.mcap_read import McapMessages
from gauged.types import Quality, StageFailure

T0 = 1_700_000_000_000_000_000


def read_all(path: Path) -> list[tuple[str, str, int, dict]]:
    """(topic, schema name, log_time, message) of every message, via mcap's reader (needs a finished file)."""
    with open(path, "rb") as f:
        reader = make_reader(f)
        assert reader.get_summary() is not None  # footer and summary written: the file was finished
        return [(c.topic, s.name, m.log_time, json.loads(m.data)) for s, c, m in reader.iter_messages()]


def test_readings_failures_alarms_and_images_read_back(tmp_path, reading):
    sink = McapSink(tmp_path, images="annotated")
    failure = StageFailure("ocr", "no_numbers", "0 numbers read")
    alarm = {"gauge": "boiler-pressure", "stamp_ns": T0 + 3, "level": "high", "state": "active", "value": 9.0,
             "limit": 8.0, "message": "high"}
    image = np.zeros((40, 60, 3), np.uint8)
    cv2.circle(image, (30, 20), 10, (0, 0, 255), -1)
    sink.publish_reading(reading(0))
    sink.publish_failure("boiler-pressure", "cam1", T0 + 2, failure)
    sink.publish_alarm(alarm)
    sink.publish_image("cam1", T0 + 4, image)
    sink.publish_reading(reading(1, value=None, quality=Quality.BAD))
    sink.close()
    assert len(sink.files) == 1 and sink.files[0].name.startswith("gauged-20231114T221320.000Z-0000")
    messages = read_all(sink.files[0])
    assert [(t, s, lt) for t, s, lt, _ in messages] == [
        ("/gauged/readings", "gauged.Reading", T0),
        ("/gauged/failures", "gauged.StageFailure", T0 + 2),
        ("/gauged/alarms", "gauged.AlarmEvent", T0 + 3),
        ("/gauged/cam1/annotated", "foxglove.CompressedImage", T0 + 4),
        ("/gauged/readings", "gauged.Reading", T0 + 100_000_000)]
    assert messages[0][3] == reading(0).to_dict() and messages[0][3]["value"] == 4.5
    assert messages[1][3] == {"gauge": "boiler-pressure", "camera": "cam1", "stamp_ns": T0 + 2, **failure.to_dict()}
    assert messages[2][3] == alarm
    shown = messages[3][3]
    assert shown["timestamp"] == {"sec": T0 // 10**9, "nsec": 4} and shown["format"] == "jpeg"
    decoded = cv2.imdecode(np.frombuffer(base64.b64decode(shown["data"]), np.uint8), cv2.IMREAD_COLOR)
    assert decoded.shape == image.shape and decoded[20, 30, 2] > 200
    assert messages[4][3]["value"] is None and messages[4][3]["failure"]["reason"] == "no_needle"
    with open(sink.files[0], "rb") as f:
        summary = make_reader(f).get_summary()
    assert {c.topic for c in summary.channels.values()} == {
        "/gauged/readings", "/gauged/failures", "/gauged/alarms", "/gauged/cam1/annotated"}
    assert {c.message_encoding for c in summary.channels.values()} == {"json"}
    assert {s.encoding for s in summary.schemas.values()} == {"jsonschema"}
    assert all(json.loads(s.data)["type"] == "object" for s in summary.schemas.values())
    assert all(c.compression == "zstd" for c in summary.chunk_indexes)


def test_images_are_not_written_unless_enabled(tmp_path, reading):
    sink = McapSink(tmp_path)
    sink.publish_image("cam1", T0, np.zeros((8, 8, 3), np.uint8))
    sink.publish_reading(reading(0))
    sink.close()
    assert [m[0] for m in read_all(sink.files[0])] == ["/gauged/readings"]


def test_rotation_by_size_writes_several_valid_files(tmp_path, reading):
    sink = McapSink(tmp_path, rotate_mb=0.005, chunk_kb=4)  # ~5 KiB files (zstd packs readings tightly)
    for i in range(600):
        sink.publish_reading(reading(i, value=i / 100))
    sink.close()
    assert len(sink.files) >= 3 and sorted(sink.files) == sink.files
    values = [m[3]["value"] for path in sink.files for m in read_all(path)]
    assert values == [i / 100 for i in range(600)]
    assert all(path.stat().st_size < 0.005 * 1024 * 1024 + 8 * 1024 for path in sink.files)


def test_rotation_by_frame_time(tmp_path, reading):
    sink = McapSink(tmp_path, rotate_s=1.0)
    for i in range(25):  # 100 ms of frame time apart: 2.5 s in all
        sink.publish_reading(reading(i))
    sink.close()
    counts = [len(read_all(path)) for path in sink.files]
    assert counts == [10, 10, 5]


def test_an_existing_file_is_never_overwritten(tmp_path, reading):
    first = McapSink(tmp_path)
    first.publish_reading(reading(0))
    first.close()
    second = McapSink(tmp_path)
    second.publish_reading(reading(0))
    second.close()
    assert first.files[0] != second.files[0] and len(list(tmp_path.glob("*.mcap"))) == 2


CHILD = textwrap.dedent("""
    import signal, sys, time
    from gauged.sinks.buffered import BufferedSink
    from gauged.sinks.mcap_sink import McapSink
    from gauged.types import Quality, Reading, ScaleInfo

    def reading(i):
        return Reading("g", "cam1", 1_700_000_000_000_000_000 + i * 10**8, float(i), float(i), "bar",
                       Quality.GOOD, 0.9, ScaleInfo(0.0, 10.0, "bar", True))

    sink = BufferedSink(McapSink(sys.argv[1], chunk_kb=4, flush_s=0.2))
    def stop(signum, frame):
        sink.close()
        sys.exit(0)
    signal.signal(signal.SIGTERM, stop)
    for i in range(200):
        sink.publish_reading(reading(i))
    time.sleep(1.0)  # the wrapper flushes every 0.2 s: the 200 are on disk now
    for i in range(200, 203):
        sink.publish_reading(reading(i))
    time.sleep(0.05)
    print("ready", flush=True)
    time.sleep(60)
""")


def run_child(tmp_path: Path, sig: int) -> Path:
    child = subprocess.Popen([sys.executable, "-c", CHILD, str(tmp_path)], stdout=subprocess.PIPE, text=True)
    try:
        assert child.stdout is not None and child.stdout.readline().strip() == "ready"
        child.send_signal(sig)
        child.wait(timeout=20)
    finally:
        if child.poll() is None:
            child.kill()
            child.wait()
    files = list(tmp_path.glob("*.mcap"))
    assert len(files) == 1
    return files[0]


def test_sigkill_loses_at_most_the_open_chunk(tmp_path):
    path = run_child(tmp_path, signal.SIGKILL)
    messages = McapMessages(path)
    values = [json.loads(m.data)["value"] for _, _, m in messages]
    assert not messages.finished_file and messages.damage is not None  # no footer: read linearly
    assert 200 <= len(values) <= 203 and values == [float(i) for i in range(len(values))]
    # mcap's own NonSeekingReader gives the same messages, then raises at the cut
    seen = []
    with open(path, "rb") as f, pytest.raises(McapError):
        for _, _, message in NonSeekingReader(f).iter_messages(log_time_order=False):
            seen.append(json.loads(message.data)["value"])
    assert seen == values


def test_sigterm_and_close_lose_nothing(tmp_path):
    path = run_child(tmp_path, signal.SIGTERM)
    assert [m[3]["value"] for m in read_all(path)] == [float(i) for i in range(203)]


def test_wrapped_sink_writes_from_its_own_thread(tmp_path, reading):
    sink = BufferedSink(McapSink(tmp_path))
    for i in range(50):
        sink.publish_reading(reading(i))
    sink.close()
    assert len(read_all(next(tmp_path.glob("*.mcap")))) == 50
