"""End to end with the real reader: the daemon over Zenoh on loopback, and ``gauged replay`` as a user runs it.

1. Two dials of the bundled demo, rendered afresh by :func:`gauged.synth.moving_dials.render_frames`
   (960x540, known truth), are sent to a running :class:`gauged.daemon.app.Daemon` by a separate Zenoh
   session: first as ROS 2 ``sensor_msgs/msg/CompressedImage`` in CDR on an rmw_zenoh-like key
   (type name and type hash after the topic), then as bare JPEG (``image/jpeg``). Another session
   receives the readings, asks the queryable for the latest state and watches the liveliness token.
   A third gauge's ROI frames bare wall: the reader must refuse it on every frame, honestly.
2. ``gauged replay`` of ``recordings/demo.mcap`` twice, in subprocesses: identical readings, bit for bit.

Both need the shipped crop model and skip without it. The two dials are ones the interim model reads
(``gauged eval recording`` on the demo: boiler-pressure and steam-line); feed-tank-temp is refused on
almost every frame, so it is not used to judge accuracy.
"""

from __future__ import annotations

import json
import subprocess
import sys
import time
from collections import defaultdict
from pathlib import Path

import cv2
import numpy as np
import pytest
import zenoh
from mcap.reader import make_reader
from mcap.summary import Summary
from mcap_ros2._dynamic import serialize_dynamic

from gauged.daemon.app import Daemon
from gauged.config import parse_config
from gauged.reader.factory import CROP_MODEL
from gauged.reader.onnx_model import packaged_model_path
from gauged.synth.moving_dials import demo_dials, render_frames
from tests.sources.conftest import ROS_COMPRESSED_DEF, free_port, peer_config

REPO = Path(__file__).resolve().parents[1]
DIALS = ("boiler-pressure", "steam-line")
WALL = "empty-wall"  # an ROI with no dial in it
WALL_ROI = [640, 300, 900, 530]
GAUGES = (*DIALS, WALL)
SECONDS, FPS, SEED = 48, 1.0, 7  # 48 frames over the boiler's excursion and 2.4 periods of the steam line
PREFIX = "gauged/e2e"
NODE = "e2e-node"
# rmw_zenoh's key: <topic>/<ROS type>/<type hash>; the daemon subscribes to robot/cam1/image/**.
ROS_KEY = ("robot/cam1/image/compressed/sensor_msgs::msg::dds_::CompressedImage_/RIHS01_"
           "ae1ba8f2c2e6b2da2ad7c2b6f7d36bfc0fcbb5e57d2c1c55b9a1b8f6d3b2c5e1")
JPEG_KEY = "robot/cam1/image/jpeg"
MAX_ERROR = 0.02  # of the span: the bar, for every reading that is not refused
MAX_MEDIAN_ERROR = 0.01  # of the span: typical readings are well inside it
MIN_READ_FRACTION = 0.8  # the rest must be honest refusals

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(not packaged_model_path(CROP_MODEL).is_file(),
                       reason=f"gauged/models/{CROP_MODEL} is missing: train and export it (gauged/models/README.md)"),
]


@pytest.fixture(scope="module")
def frames() -> list[tuple[int, np.ndarray, dict]]:
    """(truth stamp_ns, BGR 960x540 frame, truth) of the two dials, one frame per second."""
    dials = [d for d in demo_dials() if d.gauge in DIALS]
    return list(render_frames(dials, SECONDS, FPS, SEED))


def daemon_config(frames, endpoint: str, state_dir: Path) -> str:
    """The daemon's YAML: one Zenoh camera, the two dials with ROIs and scales from the truth, the wall."""
    gauges = []
    for g in frames[0][2]["gauges"]:
        x0, y0, x1, y1 = g["box"]
        roi = [max(0, int(x0) - 4), max(0, int(y0) - 4), int(x1) + 5, int(y1) + 5]
        alarms = "{high: 8.0, deadband: 0.2}" if g["gauge"] == "boiler-pressure" else "{}"
        gauges.append(f"  - {{id: {g['gauge']}, camera: cam1, roi: {roi}, "
                      f"scale: {{min: {g['min']}, max: {g['max']}, unit: {g['unit']}}}, alarms: {alarms}}}")
    gauges.append(f"  - {{id: {WALL}, camera: cam1, roi: {WALL_ROI}, scale: {{min: 0, max: 10, unit: bar}}}}")
    return "\n".join([
        "site: e2e",
        f"node: {NODE}",
        f"zenoh: {{mode: peer, listen: ['{endpoint}'], multicast_scouting: false}}",
        "cameras:",
        '  - {id: cam1, source: {type: zenoh, key: "robot/cam1/image/**"}}',
        "gauges:", *gauges,
        "outputs:",
        f"  zenoh: {{prefix: {PREFIX}}}",
        "  mcap: {enabled: false}",
        "  prometheus: {enabled: false}",
        f"state: {{dir: {state_dir}}}",
        "",
    ])


class Received:
    """What the subscriber session saw: readings by (gauge, stamp), the latest per gauge, alarm events.

    Samples wait in Zenoh channels and are taken on the test's own thread (``poll``): no Python
    callback of the test runs on a Zenoh thread.
    """

    def __init__(self, session: zenoh.Session) -> None:
        self.samples = session.declare_subscriber(f"{PREFIX}/**", zenoh.handlers.FifoChannel(100_000))
        self.tokens = session.liveliness().declare_subscriber(f"{PREFIX}/@alive/**", zenoh.handlers.FifoChannel(100),
                                                              history=True)
        self.by_stamp: dict[tuple[str, int], dict] = {}
        self.latest: dict[str, dict] = {}
        self.alarms: list[dict] = []
        self.alive: list[tuple[str, str]] = []  # (PUT or DELETE, key) of liveliness samples

    def poll(self) -> Received:
        while (sample := self.samples.try_recv()) is not None:
            key, body = str(sample.key_expr), json.loads(sample.payload.to_bytes())
            if key.endswith("/reading"):
                self.by_stamp[(body["gauge"], body["stamp_ns"])] = body
                self.latest[body["gauge"]] = body
            elif key.endswith("/alarm"):
                self.alarms.append(body)
        while (sample := self.tokens.try_recv()) is not None:
            self.alive.append((str(sample.kind).rsplit(".", 1)[-1], str(sample.key_expr)))
        return self

    def has_frame(self, stamp_ns: int) -> bool:
        return all((g, stamp_ns) in self.poll().by_stamp for g in GAUGES)


def wait_for(condition, timeout: float, what: str) -> None:
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout:g} s waiting for {what}")
        time.sleep(0.01)


def send_in_lock_step(publisher, received: Received, payload: bytes, stamp_ns: int, **put_kw) -> None:
    """Put one frame and wait until every gauge's reading of it arrives (so no frame is dropped)."""
    publisher.put(payload, **put_kw)
    wait_for(lambda: received.has_frame(stamp_ns), 15, f"the readings of frame {stamp_ns}")


def jpeg(image: np.ndarray) -> bytes:
    ok, buf = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, 90])
    assert ok
    return buf.tobytes()


def errors_by_gauge(received: Received, sent: list[tuple[int, dict]]) -> dict[str, dict]:
    """Per dial: relative errors of the frames read, and the refusals (raw_value null)."""
    out: dict[str, dict] = {g: {"errors": [], "refused": []} for g in DIALS}
    for stamp, truth in sent:
        for g in truth["gauges"]:
            reading = received.by_stamp[(g["gauge"], stamp)]
            if reading["raw_value"] is None:
                out[g["gauge"]]["refused"].append(reading)
            else:
                out[g["gauge"]]["errors"].append(abs(reading["raw_value"] - g["value"]) / (g["max"] - g["min"]))
    return out


def send_ros2_frames(pub: zenoh.Session, received: Received, frames) -> list[tuple[int, dict]]:
    """ROS 2 CompressedImage in CDR on an rmw_zenoh-like key; the header stamp is the frame time."""
    publisher = pub.declare_publisher(ROS_KEY)
    wait_for(lambda: publisher.matching_status.matching, 10, "the daemon's camera subscriber")
    encode = serialize_dynamic("sensor_msgs/msg/CompressedImage", ROS_COMPRESSED_DEF)["sensor_msgs/msg/CompressedImage"]
    sent = []
    for stamp, image, truth in frames:
        sec, nsec = divmod(stamp, 1_000_000_000)
        cdr = encode({"header": {"stamp": {"sec": sec, "nanosec": nsec}, "frame_id": "cam1"},
                      "format": "jpeg", "data": jpeg(image)})
        send_in_lock_step(publisher, received, cdr, stamp)
        sent.append((stamp, truth))
    return sent


def send_jpeg_frames(pub: zenoh.Session, received: Received, frames) -> list[tuple[int, dict]]:
    """Bare JPEG (image/jpeg) with a Zenoh timestamp from the publisher, which becomes the frame time."""
    publisher = pub.declare_publisher(JPEG_KEY, encoding=zenoh.Encoding.IMAGE_JPEG)
    wait_for(lambda: publisher.matching_status.matching, 10, "the daemon's camera subscriber")
    sent = []
    for _, image, truth in frames:
        timestamp = pub.new_timestamp()
        stamp = timestamp.get_time_as_ntp64().as_nanos()
        send_in_lock_step(publisher, received, jpeg(image), stamp, timestamp=timestamp)
        sent.append((stamp, truth))
    return sent


def check_accuracy(received: Received, sent: list[tuple[int, dict]], flavour: str) -> None:
    """Every reading of the dials within 2% of the span (median within 1%), refusals honest."""
    units = {g["gauge"]: g["unit"] for g in sent[0][1]["gauges"]}
    for gauge, result in errors_by_gauge(received, sent).items():
        errors, refused = np.asarray(result["errors"]), result["refused"]
        where = f"{gauge} ({flavour}): errors {np.round(100 * errors, 2).tolist()} %, {len(refused)} refused"
        print(f"{gauge:<16} {flavour:<8} {len(errors)}/{len(sent)} read, error of span: median "
              f"{100 * np.median(errors):.2f}%, max {100 * errors.max():.2f}%, "
              f"{100 * np.mean(errors <= MAX_ERROR):.0f}% within 2%")
        assert len(errors) >= MIN_READ_FRACTION * len(sent), where
        assert np.median(errors) <= MAX_MEDIAN_ERROR, where
        assert errors.max() <= MAX_ERROR, where
        for reading in refused:  # an honest refusal: no value of its own, the stage and reason why
            assert reading["failure"]["stage"] and reading["failure"]["reason"], reading
            assert reading["quality"] in ("uncertain", "bad", "stale"), reading
        assert {received.by_stamp[(gauge, stamp)]["unit"] for stamp, _ in sent} == {units[gauge]}


def check_wall_refused(received: Received, sent: list[tuple[int, dict]]) -> None:
    """No dial in the ROI: every frame is refused with its stage and reason, and no value is invented."""
    for stamp, _ in sent:
        reading = received.by_stamp[(WALL, stamp)]
        assert reading["raw_value"] is None and reading["value"] is None, reading
        assert reading["failure"]["stage"] and reading["failure"]["reason"], reading
        assert reading["quality"] in ("bad", "stale"), reading


def test_daemon_reads_ros2_cdr_and_jpeg_frames_over_zenoh_within_2_percent(tmp_path, frames):
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    daemon = Daemon(parse_config(daemon_config(frames, endpoint, tmp_path / "state")))
    daemon.start()
    pub = sub = None
    try:
        pub, sub = zenoh.open(peer_config(endpoint)), zenoh.open(peer_config(endpoint))
        received = Received(sub)
        alive = ("PUT", f"{PREFIX}/@alive/{NODE}")
        wait_for(lambda: alive in received.poll().alive, 10, "the liveliness token")

        ros_sent = send_ros2_frames(pub, received, frames[0::2])
        jpeg_sent = send_jpeg_frames(pub, received, frames[1::2])
        check_accuracy(received, ros_sent, "ros2 cdr")
        check_accuracy(received, jpeg_sent, "jpeg")
        check_wall_refused(received, ros_sent + jpeg_sent)
        assert (daemon.metrics.value("gauged_frames_received_total", camera="cam1") or 0) >= len(frames)
        for reason in ("bad_cdr", "undecodable", "unknown_format"):
            assert not daemon.metrics.value("gauged_frames_invalid_total", camera="cam1", reason=reason)

        # The boiler's excursion passed its high limit: the alarm went out on Zenoh.
        highs = [a for a in received.alarms if a["gauge"] == "boiler-pressure" and a["level"] == "high"]
        assert any(a["state"].startswith("active") for a in highs), received.alarms

        # The queryable answers with the latest state: the last reading of each gauge and its alarm state.
        time.sleep(0.3)  # let any late sample land before comparing
        replies = {str(r.ok.key_expr): json.loads(r.ok.payload.to_bytes())
                   for r in sub.get(f"{PREFIX}/**", timeout=5) if r.ok is not None}
        latest = received.poll().latest
        for gauge in GAUGES:
            assert replies[f"{PREFIX}/{gauge}/reading"] == latest[gauge]
            assert replies[f"{PREFIX}/{gauge}/reading"]["stamp_ns"] == jpeg_sent[-1][0]
            assert replies[f"{PREFIX}/{gauge}/alarm"]["gauge"] == gauge
        assert [str(r.ok.key_expr) for r in sub.liveliness().get(f"{PREFIX}/@alive/**", timeout=2) if r.ok] \
            == [alive[1]]

        # Stopping the daemon withdraws its liveliness token: watchers see it go.
        daemon.stop()
        wait_for(lambda: ("DELETE", alive[1]) in received.poll().alive, 10, "the token's withdrawal")
        assert [r for r in sub.liveliness().get(f"{PREFIX}/@alive/**", timeout=2) if r.ok] == []
    finally:
        daemon.stop()  # idempotent
        for session in (pub, sub):
            if session is not None:
                session.close()


# ---- gauged replay, as a user runs it ---------------------------------------------------------------


def replay(out: Path) -> None:
    """``gauged replay`` of the demo, as its README shows it, into ``out``."""
    done = subprocess.run([sys.executable, "-m", "gauged", "replay", "recordings/demo.mcap", "--config",
                           "recordings/demo.yaml", "--out", str(out)], cwd=REPO, capture_output=True, timeout=120)
    assert done.returncode == 0, done.stderr.decode()[-2000:]


def messages(path: Path) -> tuple[dict[str, list[tuple[int, bytes]]], Summary | None]:
    """(topic -> [(log_time, message bytes)] in file order, summary), through mcap's seeking reader."""
    out: dict[str, list[tuple[int, bytes]]] = defaultdict(list)
    with path.open("rb") as stream:
        reader = make_reader(stream)
        summary = reader.get_summary()
        for _schema, channel, message in reader.iter_messages(log_time_order=False):
            out[channel.topic].append((message.log_time, message.data))
    return out, summary


def test_replay_twice_gives_identical_readings_and_all_channels(tmp_path):
    # One after the other: on 2 cores two concurrent replays take as long as two in a row.
    replay(tmp_path / "a.mcap")
    replay(tmp_path / "b.mcap")
    (a, summary_a), (b, summary_b) = messages(tmp_path / "a.mcap"), messages(tmp_path / "b.mcap")

    assert a["/gauged/readings"] == b["/gauged/readings"]  # message bytes and log times, in order
    assert len(a["/gauged/readings"]) == 120 * 4  # every frame of the demo, every gauge
    assert a["/gauged/failures"] == b["/gauged/failures"] and a["/gauged/alarms"] == b["/gauged/alarms"]
    assert a["/cam1/gauged/annotations"] == b["/cam1/gauged/annotations"]  # the overlays, one per frame
    assert len(a["/cam1/gauged/annotations"]) == 120

    for summary in (summary_a, summary_b):  # finished files: a summary naming every channel, even an empty one
        assert summary is not None
        channels = {c.topic: c for c in summary.channels.values()}
        assert set(channels) == {"/gauged/readings", "/gauged/failures", "/gauged/alarms",
                                 "/cam1/gauged/annotations"}
        assert all(c.message_encoding == "json" for c in channels.values())
        assert all(summary.schemas[c.schema_id].encoding == "jsonschema" for c in channels.values())
        assert summary.statistics.channel_message_counts[channels["/gauged/readings"].id] == 480
    first = json.loads(a["/gauged/readings"][0][1])
    assert set(first) >= {"gauge", "camera", "stamp_ns", "value", "raw_value", "unit", "quality", "confidence",
                          "scale", "failure"}
