"""The daemon's wiring with real sources and sinks, read by a test double whose truth is the frame.

``BrightnessReader`` stands in for the model-based reader (it never ships): each test frame is a flat
grey image whose level encodes the value (``value = level / 25``), so the readings that come out of
the real MCAP/Zenoh sources, tracker and sinks can be checked against the truth that went in.
"""

from __future__ import annotations

import base64
import json
import time
from pathlib import Path

import cv2
import numpy as np
import pytest
import zenoh
from mcap.reader import make_reader
from mcap.writer import CompressionType, Writer

from gauged.commands.replay import batch_config
from gauged.config import parse_config
from gauged.daemon.app import Daemon
from gauged.reader.gauge_read import GaugeRead
from gauged.reader.ocr.units import PrintedUnit
from gauged.reader.stages.reading import Value
from gauged.types import StageFailure

BASE_NS = 1_700_000_000_000_000_000


class BrightnessReader:
    """Test double of :class:`gauged.reader.pipeline.GaugeReader`: value = mean grey level / 25."""

    detector = None

    def read_box(self, image, box, score=1.0, known=None, primary_unit=None, located=False) -> GaugeRead:
        x0, y0, x1, y1 = (int(v) for v in box)
        level = float(image[y0:y1, x0:x1].mean())
        read = GaugeRead(box=box, score=score, units=(PrintedUnit("bar", 1.0),), seconds={"needle": 0.001})
        if level < 5:  # a black frame: the double's way to provoke a stage failure
            read.failure = StageFailure("needle", "no_needle", "black frame")
        else:
            read.value = Value(round(level / 25, 3), 0.9, 0.5)
        return read

    def read_locked(self, image, box, arc, scale) -> GaugeRead:  # never locks: no arc is produced
        raise AssertionError("the double never locks a scale")


def frame_for(value: float | None) -> np.ndarray:
    level = 0 if value is None else int(round(value * 25))
    return np.full((120, 160, 3), level, np.uint8)


def write_recording(path: Path, values: list[float | None], period_ns: int = 100_000_000, base_ns: int = BASE_NS) -> None:
    with path.open("wb") as stream:
        writer = Writer(stream, compression=CompressionType.ZSTD)
        writer.start()
        schema = writer.register_schema("foxglove.CompressedImage", "jsonschema", b'{"type":"object"}')
        channel = writer.register_channel("/cam1/image", "json", schema)
        for i, value in enumerate(values):
            stamp = base_ns + i * period_ns
            ok, buf = cv2.imencode(".png", frame_for(value))
            body = {"timestamp": {"sec": stamp // 10**9, "nsec": stamp % 10**9}, "frame_id": "cam1",
                    "format": "png", "data": base64.b64encode(buf.tobytes()).decode()}
            writer.add_message(channel, log_time=stamp, publish_time=stamp, data=json.dumps(body).encode())
        writer.finish()


CONFIG = """
site: test
cameras:
  - id: cam1
    source: {{type: mcap, path: {path}, topic: /cam1/image, pace: fast}}
gauges:
  - id: g1
    camera: cam1
    roi: [0, 0, 160, 120]
    scale: {{min: 0, max: 10, unit: bar}}
    smoothing: {{method: none, hampel_window: 1}}
    alarms: {{high: 8, on_delay_s: 0.25, off_delay_s: 0.25}}
outputs:
  zenoh: {{enabled: false}}
  prometheus: {{enabled: false}}
  mcap: {{dir: {out}}}
state: {{dir: {state}}}
"""


def read_messages(path: Path) -> dict[str, list[dict]]:
    out: dict[str, list[dict]] = {}
    with path.open("rb") as stream:
        for _schema, channel, message in make_reader(stream).iter_messages():
            out.setdefault(channel.topic, []).append(json.loads(message.data))
    return out


def replay(tmp_path: Path, recording: Path, name: str) -> dict[str, list[dict]]:
    config = parse_config(CONFIG.format(path=recording, out=tmp_path / "unused", state=tmp_path / "state"))
    out_dir = tmp_path / name
    daemon = Daemon(batch_config(config, recording, out_dir), reader_factory=lambda c: BrightnessReader(), batch=True)
    daemon.start()
    assert daemon.wait(timeout=30)
    daemon.stop()
    (file,) = sorted(out_dir.glob("*.mcap"))
    return read_messages(file)


def test_daemon_replay_reads_every_frame_and_raises_alarm(tmp_path):
    values = [5.0] * 10 + [9.0] * 10 + [None] * 2 + [5.0] * 10
    recording = tmp_path / "in.mcap"
    write_recording(recording, values)
    messages = replay(tmp_path, recording, "out")
    readings = messages["/gauged/readings"]
    assert len(readings) == len(values)
    raw = [r["raw_value"] for r in readings]
    assert raw[:10] == [5.0] * 10 and raw[10:20] == [9.0] * 10
    assert readings[20]["failure"] == {"stage": "needle", "reason": "no_needle", "detail": "black frame"}
    assert readings[20]["value"] == 9.0  # a failed frame never zeroes the value
    assert [f["reason"] for f in messages["/gauged/failures"]] == ["no_needle", "no_needle"]
    alarms = messages["/gauged/alarms"]
    assert [(a["level"], a["state"]) for a in alarms][:1] == [("high", "active_unacknowledged")]
    assert alarms[0]["stamp_ns"] >= BASE_NS + 12 * 100_000_000  # on_delay 0.25 s after 9 bar began at frame 10


def test_daemon_replay_is_deterministic(tmp_path):
    values = list(np.round(np.linspace(2, 9, 40) + np.sin(np.arange(40)) * 0.3, 2))
    recording = tmp_path / "in.mcap"
    write_recording(recording, values)
    first = replay(tmp_path, recording, "a")
    second = replay(tmp_path, recording, "b")
    assert first == second
    assert len(first["/gauged/readings"]) == 40


def test_daemon_over_zenoh_publishes_readings_and_answers_queries(tmp_path):
    from tests.zenoh_loopback import free_port, peer_config

    endpoint = f"tcp/127.0.0.1:{free_port()}"
    text = CONFIG.format(path="unused.mcap", out=tmp_path / "out", state=tmp_path / "state")
    text = text.replace("{type: mcap, path: unused.mcap, topic: /cam1/image, pace: fast}",
                        '{type: zenoh, key: "robot/cam1/image/**"}')
    text = text.replace("zenoh: {enabled: false}", "zenoh: {prefix: gauged/test}")
    text += f"zenoh: {{mode: peer, listen: ['{endpoint}'], multicast_scouting: false}}\nnode: edge1\n"
    daemon = Daemon(parse_config(text), reader_factory=lambda c: BrightnessReader())
    daemon.start()
    peer = zenoh.open(peer_config(endpoint))
    received: list[dict] = []
    try:
        subscriber = peer.declare_subscriber("gauged/test/g1/reading", lambda s: received.append(json.loads(s.payload.to_bytes())))
        deadline = time.monotonic() + 10
        while not peer.info.peers_zid() and time.monotonic() < deadline:
            time.sleep(0.05)
        alive = [r.ok.key_expr for r in peer.liveliness().get("gauged/test/@alive/**", timeout=2) if r.ok]
        assert [str(k) for k in alive] == ["gauged/test/@alive/edge1"]
        stamp = time.time_ns()
        ok, jpeg = cv2.imencode(".jpg", frame_for(4.0))
        for i in range(20):
            peer.put(f"robot/cam1/image/hash{i % 2}", jpeg.tobytes(), encoding=zenoh.Encoding.IMAGE_JPEG)
            time.sleep(0.05)
            if received:
                break
        while not received and time.monotonic() < deadline:
            time.sleep(0.05)
        assert received, "no reading arrived over Zenoh"
        assert received[-1]["gauge"] == "g1" and abs(received[-1]["raw_value"] - 4.0) < 0.08
        assert received[-1]["stamp_ns"] >= stamp - 10**9
        replies = [r.ok for r in peer.get("gauged/test/**", timeout=3) if r.ok]
        keys = {str(r.key_expr) for r in replies}
        assert "gauged/test/g1/reading" in keys
        subscriber.undeclare()
    finally:
        daemon.stop()
    gone = [r for r in peer.liveliness().get("gauged/test/@alive/**", timeout=2) if r.ok]
    peer.close()
    assert gone == []


def test_daemon_saves_state_on_stop_and_restores_it(tmp_path):
    recording = tmp_path / "in.mcap"
    write_recording(recording, [9.5] * 10, base_ns=time.time_ns() - 10**9)  # state age is judged on frame time
    text = CONFIG.format(path=recording, out=tmp_path / "out", state=tmp_path / "state")
    daemon = Daemon(parse_config(text), reader_factory=lambda c: BrightnessReader())
    daemon.start()
    daemon.wait(timeout=30)
    daemon.stop()
    assert (tmp_path / "state" / "g1.json").is_file()
    again = Daemon(parse_config(text.replace("pace: fast", "pace: fast, loop: false")),
                   reader_factory=lambda c: BrightnessReader())
    again._make_runners()
    status = {s.level: s for s in again.runners["g1"].tracker.alarm_status()}
    assert status["high"].active


@pytest.mark.parametrize("bad", ["missing.mcap"])
def test_batch_config_keeps_topics_and_disables_network_outputs(tmp_path, bad):
    config = parse_config(CONFIG.format(path=bad, out=tmp_path, state=tmp_path))
    batch = batch_config(config, tmp_path / "r.mcap", tmp_path / "o")
    assert batch.cameras[0].source.path == tmp_path / "r.mcap" and batch.cameras[0].source.topic == "/cam1/image"
    assert not batch.outputs.zenoh.enabled and not batch.outputs.prometheus.enabled and batch.outputs.mcap.enabled


def test_daemon_alarm_ack_over_zenoh_is_applied_and_recorded(tmp_path):
    from tests.zenoh_loopback import free_port, peer_config

    endpoint = f"tcp/127.0.0.1:{free_port()}"
    recording = tmp_path / "in.mcap"
    write_recording(recording, [9.5] * 10, base_ns=time.time_ns() - 10**9)
    text = CONFIG.format(path=recording, out=tmp_path / "out", state=tmp_path / "state")
    text = text.replace("zenoh: {enabled: false}", "zenoh: {prefix: gauged/ack}")
    text += f"zenoh: {{mode: peer, listen: ['{endpoint}'], multicast_scouting: false}}\nnode: edge1\n"
    daemon = Daemon(parse_config(text), reader_factory=lambda c: BrightnessReader())
    daemon.start()
    peer = zenoh.open(peer_config(endpoint))
    try:
        assert daemon.wait(timeout=30)
        deadline = time.monotonic() + 10
        while not peer.info.peers_zid() and time.monotonic() < deadline:
            time.sleep(0.05)
        status = {s.level: s for s in daemon.runners["g1"].tracker.alarm_status()}
        assert status["high"].state.value == "active_unacknowledged"
        payload = json.dumps({"level": "high", "who": "operator-7", "why": "seen, valve opened"})
        replies = [r.ok for r in peer.get("gauged/ack/g1/alarm/ack", payload=payload, timeout=5) if r.ok]
        assert replies and json.loads(replies[0].payload.to_bytes())["ok"] is True
        status = {s.level: s for s in daemon.runners["g1"].tracker.alarm_status()}
        assert status["high"].state.value == "active_acknowledged"
    finally:
        daemon.stop()
        peer.close()
    (file,) = sorted((tmp_path / "out").glob("*.mcap"))
    alarms = read_messages(file)["/gauged/alarms"]
    acked = [a for a in alarms if a["state"] == "active_acknowledged"]
    assert acked and acked[0]["who"] == "operator-7" and acked[0]["why"] == "seen, valve opened"
