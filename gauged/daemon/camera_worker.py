"""The worker of one camera: take the newest frame, read every gauge on it, publish the results.

One thread per camera. The source keeps only the newest frame, so when reading is slower than the
camera the worker simply reads less often and the source counts the drops. ``max_rate_hz`` drops
(and counts) frames that come sooner than the configured rate.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable, Sequence
from typing import Protocol

from gauged.daemon.association import associate
from gauged.reader.locate import locate_gauges
from gauged.config.model import CameraConfig
from gauged.daemon.gauge_runner import GaugeOutput, GaugeRunner
from gauged.metrics import Metrics
from gauged.sources import FrameSource
from gauged.types import Box, Frame, GaugeDetection, StageFailure

log = logging.getLogger(__name__)

NS_PER_S = 1_000_000_000


class Detector(Protocol):
    def detect(self, image) -> list[GaugeDetection] | StageFailure: ...


class Publisher(Protocol):
    """Where a worker's results go (the app fans them out to the sinks)."""

    def gauge_output(self, frame: Frame, output: GaugeOutput) -> None: ...
    def frame_read(self, frame: Frame, outputs: Sequence[GaugeOutput]) -> None: ...


class CameraWorker:
    """Reads the gauges of one camera on a thread of its own."""

    def __init__(self, camera: CameraConfig, source: FrameSource, runners: Sequence[GaugeRunner],
                 detector: Detector | None, publisher: Publisher, metrics: Metrics,
                 heartbeat: Callable[[str], None] = lambda camera: None):
        self.camera = camera
        self.source = source
        self.runners = list(runners)
        self.detector = detector
        self.publisher = publisher
        self.metrics = metrics
        self.heartbeat = heartbeat
        self.frames_read = 0
        self.last_stamp_ns: int | None = None
        self._previous_boxes: dict[str, Box] = {}
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name=f"camera-{camera.id}", daemon=True)

    @property
    def finished(self) -> bool:
        """The source has ended (a replay without loop) and the worker has read everything."""
        return not self._thread.is_alive() and self.source.finished

    def start(self) -> None:
        self.source.start()
        self._thread.start()

    def stop(self, timeout: float = 10.0) -> None:
        self._stop.set()
        self.source.stop()
        self._thread.join(timeout)
        if self._thread.is_alive():
            log.error("camera %s: worker did not stop within %.0f s", self.camera.id, timeout)

    def join(self, timeout: float | None = None) -> None:
        self._thread.join(timeout)

    def _run(self) -> None:
        min_gap_ns = int(NS_PER_S / self.camera.max_rate_hz) if self.camera.max_rate_hz else 0
        while not self._stop.is_set():
            frame = self.source.next_frame(timeout=0.5)
            self.heartbeat(self.camera.id)
            if frame is None:
                if self.source.finished:
                    break
                continue
            if min_gap_ns and self.last_stamp_ns is not None and 0 <= frame.stamp_ns - self.last_stamp_ns < min_gap_ns:
                self.metrics.frames_skipped.labels(camera=self.camera.id).inc()
                continue
            self.last_stamp_ns = frame.stamp_ns
            try:
                self.read_frame(frame)
            except Exception:  # a bug on one frame must not stop the camera; it is logged with its trace
                log.exception("camera %s: reading frame %d failed", self.camera.id, frame.frame_id)
            self.frames_read += 1

    def read_frame(self, frame: Frame) -> None:
        """Read every gauge of this camera on ``frame`` and publish the outputs."""
        boxes = self._boxes(frame)
        outputs = []
        for runner in self.runners:
            box, score = boxes.get(runner.gauge, (None, 0.0))
            output = runner.process(frame, box, score)
            self.metrics.reads.labels(gauge=runner.gauge).inc()
            self.publisher.gauge_output(frame, output)
            outputs.append(output)
        self.publisher.frame_read(frame, outputs)  # the frame's overlays, every gauge's in one message

    def _boxes(self, frame: Frame) -> dict[str, tuple[Box | None, float]]:
        boxes: dict[str, tuple[Box | None, float]] = {}
        unboxed = []
        for runner in self.runners:
            if runner.config.roi is not None:
                boxes[runner.gauge] = (tuple(float(v) for v in runner.config.roi), 1.0)
            elif runner.needs_box:
                unboxed.append(runner.gauge)
        if not unboxed or self.detector is None:
            return boxes
        started = time.perf_counter()
        detections, _ = locate_gauges(self.detector, frame.image)  # the rules gauged read and eval use too
        self.metrics.stage_duration.labels(stage="detect").observe(time.perf_counter() - started)
        for gauge, detection in associate(unboxed, self._previous_boxes, detections).items():
            boxes[gauge] = (detection.box, detection.score)
            self._previous_boxes[gauge] = detection.box
        return boxes
