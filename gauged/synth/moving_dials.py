"""Recordings of fixed dials whose needles move: the bundled demo and test sequences.

A camera looks at ``K`` dials fixed on a cluttered wall. Each dial is drawn once per frame from its
own seed with the frame's true value (so only the needle moves), warped to its fixed place, and
the frame gets a small camera jitter and slowly changing light. Frames are written as
``foxglove.CompressedImage`` (JSON schema + JSON, JPEG data) on ``/<camera>/image``, and the truth
of every frame on ``/<camera>/truth``; with ``ros2=True`` the images are ROS 2
``sensor_msgs/msg/CompressedImage`` (ros2msg + cdr) instead, from the same sequence.

Everything is a function of the seed: the same arguments write byte-identical files.
"""

from __future__ import annotations

import base64
import json
import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from gauged.synth.recording import ROS2_COMPRESSED_IMAGE
from gauged.training.dial_renderer import _apply, _background, draw_dial, random_homography

NS_PER_S = 1_000_000_000
EPOCH_NS = 1_767_225_600 * NS_PER_S  # 2026-01-01T00:00:00Z: a fixed start keeps files reproducible

Profile = Callable[[float], float]  # seconds since start -> value


@dataclass(frozen=True)
class DialSpec:
    """One dial of a recording: id, scale, where it hangs (box in the frame) and how its value moves."""

    gauge: str
    seed: int
    min_value: float
    max_value: float
    unit: str
    box: tuple[int, int, int, int]
    profile: Profile


def excursion(base: float, peak: float, rise_at: float, hold_from: float, hold_to: float, fall_to: float) -> Profile:
    """Base, a ramp up to ``peak``, a hold, a ramp back: an alarm-worthy excursion."""
    def value(t: float) -> float:
        if t < rise_at or t >= fall_to:
            return base
        if t < hold_from:
            return base + (peak - base) * (t - rise_at) / (hold_from - rise_at)
        if t < hold_to:
            return peak
        return peak + (base - peak) * (t - hold_to) / (fall_to - hold_to)
    return value


def oscillation(centre: float, amplitude: float, period_s: float) -> Profile:
    return lambda t: centre + amplitude * math.sin(2 * math.pi * t / period_s)


def steps(levels: list[float], every_s: float) -> Profile:
    return lambda t: levels[int(t // every_s) % len(levels)]


def drift(start: float, rate_per_s: float, wobble: float = 0.0) -> Profile:
    return lambda t: start + rate_per_s * t + wobble * math.sin(t * 1.7)


def demo_dials() -> list[DialSpec]:
    """The four dials of ``recordings/demo.mcap`` (see recordings/README.md)."""
    return [
        DialSpec("boiler-pressure", 101, 0.0, 10.0, "bar", (40, 60, 300, 320),
                 excursion(5.0, 9.4, rise_at=10.0, hold_from=25.0, hold_to=38.0, fall_to=48.0)),
        DialSpec("steam-line", 202, 0.0, 160.0, "psi", (360, 40, 580, 260), oscillation(80.0, 30.0, 20.0)),
        DialSpec("feed-tank-temp", 303, -30.0, 50.0, "C", (640, 70, 900, 330), drift(5.0, 0.4, wobble=1.0)),
        DialSpec("header-pressure", 404, 0.0, 25.0, "bar", (330, 300, 530, 500), steps([6.0, 12.0, 18.0, 9.0], 15.0)),
    ]


class DialPlacer:
    """Draws one fixed dial at its place with a given needle value."""

    def __init__(self, spec: DialSpec):
        self.spec = spec
        rng = np.random.default_rng(spec.seed)
        x0, y0, x1, y1 = spec.box
        side = min(x1 - x0, y1 - y0)
        # A fixed, moderate view of the dial: the tilt and spin come from the dial's own seed.
        local = random_homography(rng, side, 1.0)
        self.homography = np.array([[1, 0, x0 + (x1 - x0 - side) / 2], [0, 1, y0 + (y1 - y0 - side) / 2], [0, 0, 1]]) @ local
        self.dial_seed = int(rng.integers(2**31))

    def draw(self, scene: np.ndarray, value: float, shift: tuple[float, float]) -> tuple[float, float, float, float]:
        """Composite the dial reading ``value`` into ``scene`` (float32, in place); returns its face box."""
        dial, alpha, points, _, _ = draw_dial(np.random.default_rng(self.dial_seed), value,
                                              (self.spec.min_value, self.spec.max_value), self.spec.unit)
        h = np.array([[1, 0, shift[0]], [0, 1, shift[1]], [0, 0, 1]]) @ self.homography
        half = np.array([[1, 0, 0.5], [0, 1, 0.5], [0, 0, 1]])
        m = np.linalg.inv(half) @ h @ half
        size = (scene.shape[1], scene.shape[0])
        warped = cv2.warpPerspective(dial, m, size).astype(np.float32)
        mask = cv2.warpPerspective(alpha, m, size).astype(np.float32)[..., None] / 255
        scene *= 1 - mask
        scene += warped * mask
        face = _apply(h, points["face"])
        return (float(face[:, 0].min()), float(face[:, 1].min()), float(face[:, 0].max()), float(face[:, 1].max()))


def render_frames(dials: list[DialSpec], seconds: float, fps: float, seed: int, width: int = 960, height: int = 540):
    """Yield (stamp_ns, BGR frame, truth dict) for every frame of the sequence."""
    rng = np.random.default_rng(seed)
    wall = cv2.resize(_background(128, rng), (width, height), interpolation=cv2.INTER_CUBIC).astype(np.float32)
    for _ in range(5):
        p = rng.integers(0, width, 4)
        cv2.line(wall, (int(p[0]), int(p[1]) % height), (int(p[2]), int(p[3]) % height),
                 tuple(float(v) for v in rng.integers(40, 200, 3)), int(rng.integers(8, 40)))
    placers = [DialPlacer(spec) for spec in dials]
    frames = int(round(seconds * fps))
    for index in range(frames):
        t = index / fps
        stamp_ns = EPOCH_NS + int(round(t * NS_PER_S))
        jitter = (float(rng.normal(0, 0.6)), float(rng.normal(0, 0.6)))
        scene = wall.copy()
        truth = {"stamp_ns": stamp_ns, "gauges": []}
        for placer in placers:
            value = placer.spec.profile(t)
            box = placer.draw(scene, value, jitter)
            truth["gauges"].append({"gauge": placer.spec.gauge, "value": round(value, 6), "min": placer.spec.min_value,
                                    "max": placer.spec.max_value, "unit": placer.spec.unit,
                                    "box": [round(v, 1) for v in box]})
        light = 1.0 + 0.15 * math.sin(2 * math.pi * t / 45.0)  # slow light change
        noise = rng.normal(0, 2.0, scene.shape).astype(np.float32)
        yield stamp_ns, (scene * light + noise).clip(0, 255).astype(np.uint8), truth


def write_recording(out: Path, dials: list[DialSpec], seconds: float, fps: float, seed: int, camera: str = "cam1",
                    ros2: bool = False, jpeg_quality: int = 70, progress: Callable[[int, int], None] | None = None,
                    width: int = 960, height: int = 540) -> int:
    """Write the sequence to ``out``; returns the number of frames."""
    from mcap.writer import CompressionType, Writer

    out.parent.mkdir(parents=True, exist_ok=True)
    total = int(round(seconds * fps))
    with out.open("wb") as stream:
        if ros2:
            from mcap_ros2.writer import Writer as Ros2Writer

            ros = Ros2Writer(stream, compression=CompressionType.ZSTD)
            schema = ros.register_msgdef("sensor_msgs/msg/CompressedImage", ROS2_COMPRESSED_IMAGE)
            writer = ros._writer  # the truth channel is plain JSON beside the ROS messages
        else:
            writer = Writer(stream, compression=CompressionType.ZSTD)
            writer.start(profile="", library="gauged")
            image_schema = writer.register_schema("foxglove.CompressedImage", "jsonschema", json.dumps(
                {"type": "object", "properties": {"timestamp": {"type": "object"}, "frame_id": {"type": "string"},
                                                  "data": {"type": "string", "contentEncoding": "base64"},
                                                  "format": {"type": "string"}}}).encode())
            image_channel = writer.register_channel(f"/{camera}/image", "json", image_schema)
        truth_schema = writer.register_schema("gauged.Truth", "jsonschema", b'{"type":"object"}')
        truth_channel = writer.register_channel(f"/{camera}/truth", "json", truth_schema)
        for index, (stamp_ns, frame, truth) in enumerate(render_frames(dials, seconds, fps, seed, width, height)):
            ok, jpeg = cv2.imencode(".jpg", frame, [cv2.IMWRITE_JPEG_QUALITY, jpeg_quality])
            sec, nsec = divmod(stamp_ns, NS_PER_S)
            if ros2:
                message = {"header": {"stamp": {"sec": sec, "nanosec": nsec}, "frame_id": camera}, "format": "jpeg",
                           "data": jpeg.tobytes()}
                ros.write_message(f"/{camera}/image", schema, message, log_time=stamp_ns, publish_time=stamp_ns)
            else:
                body = {"timestamp": {"sec": sec, "nsec": nsec}, "frame_id": camera, "format": "jpeg",
                        "data": base64.b64encode(jpeg.tobytes()).decode()}
                writer.add_message(image_channel, log_time=stamp_ns, publish_time=stamp_ns, data=json.dumps(body).encode())
            writer.add_message(truth_channel, log_time=stamp_ns, publish_time=stamp_ns, data=json.dumps(truth).encode())
            if progress:
                progress(index + 1, total)
        (ros if ros2 else writer).finish()
    return total
