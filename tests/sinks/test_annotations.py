"""Image overlays (foxglove.ImageAnnotations): geometry in image pixels, Foxglove's schema, image times.

- Round trip: a dial built in image pixels, handed over in crop pixels as the reader gives it, comes
  back on the image (ellipse, ends, needle) for several crops.
- A real replay of the first frames of the bundled demo with the shipped reader: one overlay per
  image, every message valid against the vendored Foxglove schema, stamped with the image's time,
  its points on the image and on the gauges; a gauge configured on a bare wall shows its refusal.
- The daemon over Zenoh on loopback: each gauge's overlay arrives on ``<prefix>/<gauge>/annotations``.
"""

from __future__ import annotations

import base64
import json
import math
import time
from pathlib import Path

import cv2
import jsonschema
import numpy as np
import pytest
import yaml
import zenoh
from mcap.reader import make_reader
from mcap.writer import CompressionType, Writer

from gauged.commands.replay import batch_config
from gauged.config import parse_config
from gauged.daemon.app import Daemon
from gauged.daemon.gauge_runner import GaugeOutput
from gauged.geometry.dial_frame import dial_angle, normalized_radius, point_at_dial_angle
from gauged.metrics import Metrics
from gauged.reader.gauge_read import GaugeRead
from gauged.reader.ocr.units import PrintedUnit
from gauged.reader.stages.crop import Crop, crop_gauge
from gauged.reader.stages.ellipse import ScaleArc
from gauged.reader.stages.needle import NeedleReading
from gauged.reader.stages.reading import Value
from gauged.sinks import open_sinks
from gauged.sinks.annotations import LINE_LOOP, LINE_STRIP, POINTS, frame_annotations, gauge_annotations
from gauged.sinks.config import OutputsConfig
from gauged.sinks.mcap_schemas import IMAGE_ANNOTATIONS_SCHEMA
from gauged.types import Ellipse, NeedleLine, Quality, Reading, ScaleInfo, StageFailure
from tests.zenoh_loopback import free_port

REPO = Path(__file__).resolve().parents[2]
SCHEMA_FILE = REPO / "gauged" / "sinks" / "foxglove_schemas" / "ImageAnnotations.json"
T0 = 1_700_000_000_000_000_000
VALIDATOR = jsonschema.Draft202012Validator(json.loads(SCHEMA_FILE.read_text()))


def validate(message: dict) -> None:
    VALIDATOR.validate(message)  # raises jsonschema.ValidationError naming the offending field


def stamps_of(message: dict) -> set[int]:
    """Every time in an overlay message (its own and each annotation's), as ns."""
    times = [message["timestamp"], *(a["timestamp"] for kind in ("circles", "points", "texts") for a in message[kind])]
    return {t["sec"] * 1_000_000_000 + t["nsec"] for t in times}


def reading(gauge: str = "g1", value: float | None = 4.5, quality: Quality = Quality.GOOD,
            failure: StageFailure | None = None, stamp: int = T0) -> Reading:
    return Reading(gauge, "cam1", stamp, value, value, "bar", quality, 0.9, ScaleInfo(0.0, 10.0, "bar"), failure)


def dial_read(box, crop: Crop | None, ellipse_px: Ellipse, pivot_px, needle_angle: float | None,
              start: float = 2.4, end: float = 0.75) -> GaugeRead:
    """A read whose dial is given in image pixels and stored, as the reader stores it, in crop pixels."""
    read = GaugeRead(box=box, score=1.0, crop=crop)
    if crop is None:
        return read
    s, (ox, oy) = crop.scale, crop.to_frame[:2, 2]
    ellipse = Ellipse((ellipse_px.cx - ox) / s, (ellipse_px.cy - oy) / s, ellipse_px.a / s, ellipse_px.b / s,
                      ellipse_px.theta)
    centre = tuple(float(v) for v in crop.points_to_crop(np.asarray(pivot_px))[0])
    read.arc = ScaleArc(ellipse, centre, start, end, (start + end) / 2 + math.pi, np.empty((0, 2)), 0.0, False)
    if needle_angle is not None:
        tip = point_at_dial_angle(ellipse, needle_angle, centre)[0]
        direction = (tip - centre) / np.linalg.norm(tip - centre)
        read.needle = NeedleReading(NeedleLine(centre, tuple(direction), tuple(tip)), needle_angle, 1.0, 0.0)
    return read


def of_type(message: dict, kind: int) -> list[np.ndarray]:
    return [np.array([[p["x"], p["y"]] for p in a["points"]]) for a in message["points"] if a["type"] == kind]


@pytest.mark.parametrize("side, size, theta, squash", [(240.0, 256, 0.3, 0.8), (90.0, 128, 1.2, 0.95),
                                                        (600.0, 384, 2.9, 0.6)])
def test_overlay_puts_crop_geometry_back_on_the_image(side, size, theta, squash):
    image = np.zeros((720, 1280, 3), np.uint8)
    box = (310.0, 170.0, 310.0 + side, 170.0 + side * 0.9)
    crop = crop_gauge(image, box, size)
    assert isinstance(crop, Crop) and crop.scale != 1.0  # the geometry really comes from crop pixels
    truth = Ellipse(box[0] + side / 2, box[1] + side * 0.45, side * 0.42, side * 0.42 * squash, theta)
    pivot = (truth.cx + side * 0.02, truth.cy - side * 0.015)  # a perspective view: not the ellipse centre
    needle_angle = -0.7
    message = gauge_annotations(GaugeOutput(reading(), [], dial_read(box, crop, truth, pivot, needle_angle), None,
                                            False, False), T0, (1280, 720))
    validate(message)
    (ring,), (ends,), (needle,) = of_type(message, LINE_LOOP), of_type(message, POINTS), of_type(message, LINE_STRIP)
    tolerance = 0.02 / truth.b  # coordinates are rounded to 0.01 px
    assert np.allclose(normalized_radius(truth, ring), 1.0, atol=tolerance)
    assert np.allclose(normalized_radius(truth, ends), 1.0, atol=tolerance)
    assert np.allclose(dial_angle(truth, ends, pivot), [2.4, 0.75], atol=1e-3)
    assert np.allclose(needle[0], pivot, atol=0.01)
    assert abs(normalized_radius(truth, needle[1:])[0] - 1.0) < tolerance
    assert abs(dial_angle(truth, needle[1:], pivot)[0] - needle_angle) < 1e-3
    (text,) = message["texts"]
    assert text["text"] == "g1: 4.5 bar" and text["position"]["x"] == box[0]
    assert stamps_of(message) == {T0}


def test_refused_overlay_shows_box_geometry_found_and_reason():
    image = np.zeros((480, 640, 3), np.uint8)
    box = (100.0, 80.0, 300.0, 280.0)
    crop = crop_gauge(image, box, 256)
    failure = StageFailure("needle", "no_needle", "no line found")
    read = dial_read(box, crop, Ellipse(200.0, 180.0, 80.0, 70.0, 0.2), (200.0, 180.0), None)
    read.failure = failure
    held = GaugeOutput(reading(value=4.5, quality=Quality.UNCERTAIN, failure=failure), [], read, failure, False, False)
    message = gauge_annotations(held, T0, (640, 480))
    validate(message)
    loops = of_type(message, LINE_LOOP)
    assert np.array_equal(loops[0], [[100, 80], [300, 80], [300, 280], [100, 280]])  # the box, then the ellipse
    assert len(loops) == 2 and not of_type(message, LINE_STRIP)  # no needle was found: none is drawn
    assert all(a["outline_color"]["r"] > 0.9 and a["outline_color"]["g"] < 0.3 for a in message["points"])  # red
    assert message["texts"][0]["text"] == "g1: 4.5 bar [needle/no_needle]"

    early = GaugeRead(box=box, score=1.0, failure=StageFailure("keypoints", "no_notches"))  # before any geometry
    bad = GaugeOutput(reading(value=None, quality=Quality.BAD, failure=early.failure), [], early, early.failure,
                      False, False)
    message = gauge_annotations(bad, T0, (640, 480))
    validate(message)
    assert len(message["points"]) == 1 and message["texts"][0]["text"] == "g1: bad [keypoints/no_notches]"

    lost = GaugeOutput(reading(value=None, quality=Quality.BAD), [], None,
                       StageFailure("detect", "gauge_not_found"), False, False)
    assert gauge_annotations(lost, T0, (640, 480)) == {"timestamp": {"sec": T0 // 10**9, "nsec": 0},
                                                       "circles": [], "points": [], "texts": []}


def test_text_stays_inside_the_image():
    box = (600.0, 0.0, 640.0, 40.0)  # a small dial in the top-right corner
    out = GaugeOutput(reading(gauge="a-long-gauge-name"), [], GaugeRead(box=box, score=1.0), None, False, False)
    (text,) = gauge_annotations(out, T0, (640, 480))["texts"]
    assert text["position"]["y"] >= text["font_size"]  # the position is the text's bottom-left corner
    assert text["position"]["x"] + 0.6 * text["font_size"] * len(text["text"]) <= 640


def test_vendored_schema_is_foxgloves_and_is_registered():
    schema = json.loads(SCHEMA_FILE.read_text())
    jsonschema.Draft202012Validator.check_schema(schema)
    assert schema["title"] == "foxglove.ImageAnnotations" and IMAGE_ANNOTATIONS_SCHEMA == schema
    assert set(schema["properties"]) >= {"circles", "points", "texts"}


# ---- a real replay of the bundled demo --------------------------------------------------------------

DEMO, DEMO_CONFIG = REPO / "recordings" / "demo.mcap", REPO / "recordings" / "demo.yaml"
WALL = [560, 330, 760, 530]  # a bare part of the demo's wall: the reader refuses it every frame


def first_frames(source: Path, topic: str, count: int, out: Path) -> list[int]:
    """Copy the first ``count`` images of ``topic`` into ``out``; their own timestamps (ns)."""
    stamps = []
    with source.open("rb") as stream, out.open("wb") as sink:
        writer = Writer(sink, compression=CompressionType.ZSTD)
        writer.start()
        for schema, channel, message in make_reader(stream).iter_messages(topics=[topic]):
            if len(stamps) == count:
                break
            if not stamps:
                schema_id = writer.register_schema(schema.name, schema.encoding, schema.data)
                channel_id = writer.register_channel(topic, channel.message_encoding, schema_id)
            stamp = json.loads(message.data)["timestamp"]
            stamps.append(stamp["sec"] * 1_000_000_000 + stamp["nsec"])
            writer.add_message(channel_id, log_time=message.log_time, data=message.data,
                               publish_time=message.publish_time)
        writer.finish()
    return stamps


def read_output(path: Path) -> dict[str, list[tuple[int, dict]]]:
    out: dict[str, list[tuple[int, dict]]] = {}
    with path.open("rb") as stream:
        reader = make_reader(stream)
        summary = reader.get_summary()
        for channel in summary.channels.values():
            if channel.topic.endswith("/annotations"):
                schema = summary.schemas[channel.schema_id]
                assert (schema.name, schema.encoding, channel.message_encoding) == (
                    "foxglove.ImageAnnotations", "jsonschema", "json")
                assert json.loads(schema.data) == json.loads(SCHEMA_FILE.read_text())
        for _schema, channel, message in reader.iter_messages():
            out.setdefault(channel.topic, []).append((message.log_time, json.loads(message.data)))
    return out


@pytest.mark.slow
def test_replay_of_the_demo_overlays_every_image_at_its_time(tmp_path):
    from gauged.reader.factory import CROP_MODEL
    from gauged.reader.onnx_model import packaged_model_path

    if not packaged_model_path(CROP_MODEL).is_file():
        pytest.skip(f"gauged/models/{CROP_MODEL} is missing")
    recording = tmp_path / "short.mcap"
    stamps = first_frames(DEMO, "/cam1/image", 3, recording)
    config = yaml.safe_load(DEMO_CONFIG.read_text())
    config["gauges"].append({"id": "empty-wall", "camera": "cam1", "roi": WALL})
    config["state"] = {"dir": str(tmp_path / "state")}
    config = batch_config(parse_config(yaml.safe_dump(config)), recording, tmp_path / "out")
    daemon = Daemon(config, batch=True)
    daemon.start()
    try:
        assert daemon.wait(timeout=240)
    finally:
        daemon.stop()
    (path,) = (tmp_path / "out").glob("*.mcap")
    out = read_output(path)

    overlays = out["/cam1/gauged/annotations"]
    assert [log_time for log_time, _ in overlays] == stamps  # one per image, logged at the image's time
    boxes = {g.id: g.roi for g in config.gauges}
    readings = {(r["gauge"], t): r for t, r in out["/gauged/readings"]}
    for stamp, message in overlays:
        validate(message)
        assert stamps_of(message) == {stamp}
        points = np.array([[p["x"], p["y"]] for a in message["points"] for p in a["points"]])
        assert ((points >= 0) & (points <= [960, 540])).all()  # on the 960x540 image
        on_a_dial = [(points >= np.subtract(b[:2], 0.1 * (b[2] - b[0]))).all(axis=1)
                     & (points <= np.add(b[2:], 0.1 * (b[2] - b[0]))).all(axis=1) for b in boxes.values()]
        assert np.any(on_a_dial, axis=0).all()  # every point on a gauge's box (crop pixels would not be)
        texts = {t["text"].split(":")[0]: t["text"] for t in message["texts"]}
        assert set(texts) == set(boxes)
        for gauge, text in texts.items():
            published = readings[(gauge, stamp)]
            if published["failure"] is None:
                assert text == f"{gauge}: {published['value']:.4g} {published['unit']}"
            else:
                assert text.endswith(f"[{published['failure']['stage']}/{published['failure']['reason']}]")
        assert readings[("empty-wall", stamp)]["failure"] is not None
        x0, y0, x1, y1 = WALL
        assert [[x0, y0], [x1, y0], [x1, y1], [x0, y1]] in [[[p["x"], p["y"]] for p in a["points"]]
                                                            for a in message["points"] if a["type"] == LINE_LOOP]
        good = [g for g in boxes if readings[(g, stamp)]["failure"] is None]
        assert len(good) >= 3 and len(of_type(message, LINE_STRIP)) >= len(good)  # a needle for each dial read


# ---- outputs: MCAP per camera frame, Zenoh per gauge, both configurable ----------------------------------

def dial_double_output(gauge: str, stamp: int, value: float = 5.0) -> GaugeOutput:
    box = (40.0, 30.0, 200.0, 190.0)
    crop = crop_gauge(np.zeros((240, 320, 3), np.uint8), box, 128)
    read = dial_read(box, crop, Ellipse(120.0, 110.0, 60.0, 55.0, 0.1), (120.0, 110.0), value / 10 * 4.5 + 2.4)
    read.value = Value(value, 0.9, value / 10)
    return GaugeOutput(reading(gauge, value, stamp=stamp), [], read, None, False, False)


def test_mcap_sink_writes_one_overlay_per_camera_frame_and_can_be_off(tmp_path):
    for enabled in (True, False):
        outputs = OutputsConfig.model_validate({"zenoh": {"enabled": False}, "prometheus": {"enabled": False},
                                                "mcap": {"dir": str(tmp_path / str(enabled)), "annotations": enabled}})
        (sink,) = open_sinks(outputs, metrics=Metrics(), session=None, node="n1")
        assert sink.annotations is enabled
        for i in range(3):
            stamp = T0 + i * 100_000_000
            sink.publish_reading(reading(stamp=stamp))  # a file is opened either way
            sink.publish_annotations("cam1", stamp, frame_annotations(
                [dial_double_output("g1", stamp), dial_double_output("g2", stamp)], stamp, (320, 240)))
        sink.close()
        (path,) = (tmp_path / str(enabled)).glob("*.mcap")
        overlays = read_output(path).get("/cam1/gauged/annotations", [])
        if not enabled:
            assert overlays == []
            continue
        assert [t for t, _ in overlays] == [T0, T0 + 100_000_000, T0 + 200_000_000]
        for stamp, message in overlays:
            validate(message)
            assert stamps_of(message) == {stamp}
            assert [t["text"] for t in message["texts"]] == ["g1: 5 bar", "g2: 5 bar"]  # both gauges, one message


class DialDouble:
    """Test double of the reader: a dial inscribed in the box, read by the real crop stage; the needle
    points at the value, which is the frame's grey level / 25."""

    detector = None

    def read_box(self, image, box, score=1.0, known=None, primary_unit=None, located=False) -> GaugeRead:
        x0, y0, x1, y1 = box
        crop = crop_gauge(image, box, 128)
        value = round(float(image[int(y0):int(y1), int(x0):int(x1)].mean()) / 25, 3)
        centre = ((x0 + x1) / 2, (y0 + y1) / 2)
        read = dial_read(box, crop, Ellipse(*centre, (x1 - x0) * 0.4, (y1 - y0) * 0.35, 0.0), centre,
                         2.4 + value / 10 * 4.6, start=2.4, end=0.72)
        read.units, read.value = (PrintedUnit("bar", 1.0),), Value(value, 0.9, value / 10)
        return read

    def read_locked(self, image, box, arc, scale) -> GaugeRead:
        raise AssertionError("the double never locks a scale")


def grey_recording(path: Path, levels: list[int], period_ns: int = 100_000_000) -> list[int]:
    stamps = [T0 + i * period_ns for i in range(len(levels))]
    with path.open("wb") as stream:
        writer = Writer(stream, compression=CompressionType.ZSTD)
        writer.start()
        schema = writer.register_schema("foxglove.CompressedImage", "jsonschema", b'{"type":"object"}')
        channel = writer.register_channel("/cam1/image", "json", schema)
        for stamp, level in zip(stamps, levels):
            ok, png = cv2.imencode(".png", np.full((240, 320, 3), level, np.uint8))
            body = {"timestamp": {"sec": stamp // 10**9, "nsec": stamp % 10**9}, "frame_id": "cam1", "format": "png",
                    "data": base64.b64encode(png.tobytes()).decode()}
            writer.add_message(channel, log_time=stamp, publish_time=stamp, data=json.dumps(body).encode())
        writer.finish()
    return stamps


def test_daemon_puts_each_gauges_overlay_on_zenoh(tmp_path):
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    conf = zenoh.Config()
    conf.insert_json5("mode", '"peer"')
    conf.insert_json5("scouting/multicast/enabled", "false")
    conf.insert_json5("listen/endpoints", json.dumps([endpoint]))
    viewer = zenoh.open(conf)  # listens first, so its subscriber is known when the daemon connects
    stamps = grey_recording(tmp_path / "in.mcap", [100 + 5 * i for i in range(12)])
    smoothing = "smoothing: {method: none, hampel_window: 1}"
    text = f"""
site: test
zenoh: {{mode: peer, connect: ['{endpoint}'], multicast_scouting: false}}
cameras:
  - id: cam1
    source: {{type: mcap, path: {tmp_path / "in.mcap"}, topic: /cam1/image, pace: realtime}}
gauges:
  - {{id: g1, camera: cam1, roi: [10, 10, 150, 150], scale: {{min: 0, max: 10, unit: bar}}, {smoothing}}}
  - {{id: g2, camera: cam1, roi: [170, 60, 310, 200], scale: {{min: 0, max: 10, unit: bar}}, {smoothing}}}
outputs:
  zenoh: {{prefix: gauged/test}}
  mcap: {{enabled: false}}
  prometheus: {{enabled: false}}
state: {{dir: {tmp_path / "state"}}}
"""
    try:
        samples = viewer.declare_subscriber("gauged/test/*/annotations", zenoh.handlers.FifoChannel(1000))
        daemon = Daemon(parse_config(text), reader_factory=lambda c: DialDouble())
        daemon.start()
        try:
            assert daemon.wait(timeout=30)
            time.sleep(0.5)  # the last puts land
        finally:
            daemon.stop()
        got: dict[tuple[str, int], dict] = {}
        while (sample := samples.try_recv()) is not None:
            assert str(sample.encoding) == "application/json;foxglove.ImageAnnotations"
            message = json.loads(sample.payload.to_bytes())
            validate(message)
            (stamp,) = stamps_of(message)
            got[(str(sample.key_expr).split("/")[2], stamp)] = message
    finally:
        viewer.close()
    assert all(stamp in stamps for _, stamp in got)  # stamped with an image's own time
    for gauge in ("g1", "g2"):  # every frame after the connection settled (frames come every 0.1 s)
        assert {s for g, s in got if g == gauge} >= set(stamps[5:]), sorted(got)
    last = got[("g2", stamps[-1])]
    assert last["texts"][0]["text"] == f"g2: {(100 + 5 * 11) / 25:.4g} bar"
    (needle,) = of_type(last, LINE_STRIP)
    assert np.allclose(needle[0], [240, 130], atol=0.01)  # from the pivot, in image pixels
