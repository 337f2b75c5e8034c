"""Recordings: both MCAP flavours read back through gauged's own source, truth beside each frame,
deterministic bytes, and the needle follows its timeline."""

from __future__ import annotations

import base64
import json
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader

from gauged.sources.mcap_source import iter_frames
from gauged.synth.demo import QUALITY, demo_sequences
from gauged.synth.recording import write_foxglove, write_ros2
from gauged.synth.sequence import EPOCH_NS, Timeline, camera_frames, encode_jpeg, needle_state, random_sequence


def _sequence(seconds: float = 1.5, fps: float = 2.0):
    return random_sequence(np.random.default_rng(4), seconds=seconds, fps=fps, gauges=2, width=320, height=240)


def test_foxglove_recording_reads_back_with_truth(tmp_path):
    path = tmp_path / "f.mcap"
    summary = write_foxglove(path, [_sequence()], quality=70)
    assert summary.frames == 3
    frames = list(iter_frames(path, "/cam1/image"))
    assert [f.stamp_ns for f in frames] == [EPOCH_NS, EPOCH_NS + 500_000_000, EPOCH_NS + 1_000_000_000]
    assert frames[0].image.shape == (240, 320, 3)
    with path.open("rb") as stream:
        reader = make_reader(stream)
        messages = list(reader.iter_messages())
        schemas = {s.name: s.encoding for s in reader.get_summary().schemas.values()}
    assert schemas == {"foxglove.CompressedImage": "jsonschema", "gauged.synth.Truth": "jsonschema"}
    images = [(c, m) for _, c, m in messages if c.topic == "/cam1/image"]
    truths = [json.loads(m.data) for _, c, m in messages if c.topic == "/cam1/truth"]
    channel, first = images[0]
    body = json.loads(first.data)
    assert channel.message_encoding == "json" and body["format"] == "jpeg" and body["frame_id"] == "cam1"
    assert body["timestamp"] == {"sec": EPOCH_NS // 10**9, "nsec": 0}
    assert base64.b64decode(body["data"])[:2] == b"\xff\xd8"
    assert all(m.log_time == m.publish_time for _, m in images)
    assert [t["stamp_ns"] for t in truths] == [f.stamp_ns for f in frames]
    assert {g["gauge"] for g in truths[0]["gauges"]} == {"g0", "g1"}


def test_ros2_recording_reads_back(tmp_path):
    path = tmp_path / "r.mcap"
    write_ros2(path, [_sequence()])
    frames = list(iter_frames(path, "/cam1/image"))
    assert len(frames) == 3 and frames[0].image.shape == (240, 320, 3)
    with path.open("rb") as stream:
        reader = make_reader(stream)
        schemas = {s.name: s.encoding for s in reader.get_summary().schemas.values()}
    assert schemas["sensor_msgs/msg/CompressedImage"] == "ros2msg"


def test_recordings_are_byte_identical(tmp_path):
    write_foxglove(tmp_path / "a.mcap", [_sequence(1.0)])
    write_foxglove(tmp_path / "b.mcap", [_sequence(1.0)])
    assert (tmp_path / "a.mcap").read_bytes() == (tmp_path / "b.mcap").read_bytes()
    write_ros2(tmp_path / "c.mcap", [_sequence(1.0)])
    write_ros2(tmp_path / "d.mcap", [_sequence(1.0)])
    assert (tmp_path / "c.mcap").read_bytes() == (tmp_path / "d.mcap").read_bytes()


def test_timeline_steps_ramps_and_needle_stop():
    tl = Timeline(((0.0, 1.0), (10.0, 3.0), (10.0, 5.0)))
    assert tl.value(-1) == 1.0 and tl.value(5.0) == 2.0 and tl.value(10.0) == 5.0 and tl.value(20.0) == 5.0
    params = _sequence().scene.gauges[0].params
    low = params.primary.min - 0.5 * (params.primary.max - params.primary.min)
    value, at_stop = needle_state(params, low)
    assert at_stop and params.primary.min - 0.2 * (params.primary.max - params.primary.min) < value < params.primary.min


def test_bundled_plant_demo_matches_its_generator():
    """The first frames of recordings/plant-demo.mcap are what `gauged synth plant-demo` renders now
    (so the README's rebuild command stays true; regenerate the file after changing the renderer)."""
    path = Path(__file__).resolve().parents[2] / "recordings" / "plant-demo.mcap"
    if not path.is_file():
        pytest.skip("recordings/plant-demo.mcap is not in this checkout")
    with path.open("rb") as stream:
        stored = {}
        for _, channel, message in make_reader(stream).iter_messages():
            if channel.topic.endswith("/image") and (channel.topic, message.sequence) not in stored and message.sequence < 2:
                stored[(channel.topic, message.sequence)] = base64.b64decode(json.loads(message.data)["data"])
            if len(stored) == 4:
                break
    for seq in demo_sequences():
        for frame, _ in zip(camera_frames(seq), range(2)):
            assert encode_jpeg(frame.image, QUALITY) == stored[(f"/{seq.camera}/image", frame.index)]
