"""The one place where gauged is wired together: sources -> reader -> tracking -> alarms -> sinks.

Start order (stop runs it in reverse):

1. metrics            one registry per daemon
2. zenoh session      only when a camera or an output uses Zenoh
3. reader             models loaded once (or the reader given by the caller)
4. trackers           one per gauge, restored from the state directory
5. sinks              Prometheus, MCAP, Zenoh (queryable, liveliness, alarm commands)
6. camera workers     one thread per camera, each with its source
7. ticker             staleness in frame time, periodic state saves, watchdog health

Frame time drives everything the daemon publishes. The ticker extrapolates a camera's frame clock
by the monotonic time since its last frame, so a camera that goes dark turns stale; a ``batch`` run
(``gauged replay``) has no ticker, so its output depends on the recording alone.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from gauged.daemon.camera_worker import CameraWorker
from gauged.config.model import GaugedConfig
from gauged.daemon.gauge_runner import GaugeOutput, GaugeRunner, Reader
from gauged.metrics import Metrics
from gauged.reader.failures import failure_pairs
from gauged.sinks import BufferedSink, open_sinks
from gauged.sinks.annotations import frame_annotations
from gauged.sources import make_source
from gauged.tracking.state_file import restore_tracker, save_tracker
from gauged.tracking.tracker import GaugeTracker
from gauged.types import Frame, Reading

log = logging.getLogger(__name__)

NS_PER_S = 1_000_000_000
SAVE_EVERY_S = 30.0

def default_reader(config: GaugedConfig) -> Reader:
    """The shipped reader: packaged ONNX models on onnxruntime, plus OCR when it is installed."""
    from gauged.reader.factory import build_reader

    return build_reader(config.reader)


@dataclass
class DaemonStatus:
    """What the terminal table and the watchdog look at (latest reading per gauge)."""

    readings: dict[str, Reading] = field(default_factory=dict)
    active_alarms: dict[str, list[str]] = field(default_factory=dict)
    locked: dict[str, bool] = field(default_factory=dict)


class Daemon:
    """One running configuration. ``start()``, then ``stop()``; a reload is a new Daemon."""

    def __init__(self, config: GaugedConfig, *, reader_factory: Callable[[GaugedConfig], Reader] = default_reader,
                 batch: bool = False, node: str | None = None):
        self.config = config
        self.reader_factory = reader_factory
        self.batch = batch
        self.node = node or config.node or config.site
        self.metrics = Metrics()
        self.status = DaemonStatus()
        self.session: Any = None
        self.sinks: list[BufferedSink] = []
        self.runners: dict[str, GaugeRunner] = {}
        self.workers: list[CameraWorker] = []
        self._beats: dict[str, float] = {}
        self._frame_clock: dict[str, tuple[int, float]] = {}  # camera -> (stamp_ns, monotonic s)
        self._stop = threading.Event()
        self._ticker: threading.Thread | None = None
        self._status_lock = threading.Lock()

    # ---- lifecycle -------------------------------------------------------------------------
    def start(self) -> None:
        steps = (self._open_session, self._make_runners, self._open_sinks, self._start_workers, self._start_ticker)
        try:
            for step in steps:
                step()
        except BaseException:
            self.stop()
            raise
        log.info("gauged started: %d camera(s), %d gauge(s)", len(self.workers), len(self.runners))

    def stop(self) -> None:
        """Stop in reverse start order; flushes every sink and saves every tracker. Idempotent."""
        self._stop.set()
        if self._ticker is not None:
            self._ticker.join(5.0)
        for worker in self.workers:
            worker.stop()
        if not self.batch:
            self._save_states()
        for sink in reversed(self.sinks):
            sink.close()
        self.sinks = []
        if self.session is not None:
            self.session.close()
            self.session = None

    def wait(self, timeout: float | None = None) -> bool:
        """Block until every camera's source has ended (replays) or ``timeout``; True when all ended."""
        deadline = None if timeout is None else time.monotonic() + timeout
        for worker in self.workers:
            remaining = None if deadline is None else max(0.0, deadline - time.monotonic())
            worker.join(remaining)
        return all(worker.finished for worker in self.workers)

    def healthy(self, max_silence_s: float) -> bool:
        """Every camera worker has looped (a frame or an idle wait) within ``max_silence_s``."""
        now = time.monotonic()
        return all(now - self._beats.get(w.camera.id, 0.0) <= max_silence_s for w in self.workers
                   if not w.finished)

    # ---- start steps ------------------------------------------------------------------------
    def _open_session(self) -> None:
        uses_zenoh = self.config.outputs.zenoh.enabled or any(c.source.type == "zenoh" for c in self.config.cameras)
        if uses_zenoh:
            from gauged.sources.zenoh_session import open_session

            self.session = open_session(self.config.zenoh)

    def _make_runners(self) -> None:
        reader = self.reader_factory(self.config)
        self.reader = reader
        now_ns = time.time_ns()
        for gauge in self.config.gauges:
            tracker = GaugeTracker.from_config(gauge)
            if not self.batch:
                restored = restore_tracker(tracker, self.config.state.dir, now_ns, self.config.state.max_age_s)
                for warning in restored.warnings:
                    log.warning("gauge %s: %s", gauge.id, warning)
                if restored:
                    log.info("gauge %s: %s", gauge.id, restored.message)
            self.runners[gauge.id] = GaugeRunner(gauge, self.config.scale_lock, reader, tracker)

    def _open_sinks(self) -> None:
        self.sinks = open_sinks(
            self.config.outputs, metrics=self.metrics, session=self.session, node=self.node,
            gauges=list(self.runners), failure_pairs=failure_pairs(), on_command=self._on_command,
            alarm_state=self._alarm_state, name_prefix=self.config.site)
        for gauge in self.runners:
            self.metrics.scale_locked.labels(gauge=gauge).set(0)

    def _start_workers(self) -> None:
        detector = getattr(self.reader, "detector", None)
        for camera in self.config.cameras:
            runners = [self.runners[g.id] for g in self.config.gauges_of(camera.id)]
            self.metrics.add_camera(camera.id)
            source = make_source(camera, metrics=self.metrics, session=self.session)
            worker = CameraWorker(camera, source, runners, detector, self, self.metrics, self._beat)
            self.workers.append(worker)
        for worker in self.workers:
            worker.start()

    def _start_ticker(self) -> None:
        if not self.batch:
            self._ticker = threading.Thread(target=self._tick_loop, name="ticker", daemon=True)
            self._ticker.start()

    # ---- called by camera workers -----------------------------------------------------------
    def _beat(self, camera: str) -> None:
        self._beats[camera] = time.monotonic()

    def gauge_output(self, frame: Frame, output: GaugeOutput) -> None:
        """Publish one gauge's result of one frame to every sink and to the metrics."""
        self._frame_clock[frame.camera] = (frame.stamp_ns, time.monotonic())
        gauge = output.reading.gauge
        if output.read is not None:
            for stage, seconds in output.read.seconds.items():
                self.metrics.stage_duration.labels(stage=stage).observe(seconds)
        if output.failure is not None:
            self.metrics.stage_failures.labels(gauge=gauge, stage=output.failure.stage,
                                               reason=output.failure.reason).inc()
        self.metrics.scale_locked.labels(gauge=gauge).set(1 if output.locked else 0)
        self._publish(output.reading, output.events, output.failure, frame.camera)
        with self._status_lock:
            self.status.locked[gauge] = output.locked

    def frame_read(self, frame: Frame, outputs: Sequence[GaugeOutput]) -> None:
        """Publish the overlays of one frame (each gauge's geometry and value) to the sinks that take them."""
        sinks = [sink for sink in self.sinks if sink.annotations]
        if sinks and outputs:
            overlays = frame_annotations(outputs, frame.stamp_ns, frame.size)
            for sink in sinks:
                sink.publish_annotations(frame.camera, frame.stamp_ns, overlays)

    def _publish(self, reading: Reading | None, events, failure, camera: str) -> None:
        for sink in self.sinks:
            if reading is not None:
                sink.publish_reading(reading)
                if failure is not None:
                    sink.publish_failure(reading.gauge, camera, reading.stamp_ns, failure)
            for event in events:
                sink.publish_alarm(event.to_dict())
        if reading is not None:
            with self._status_lock:
                self.status.readings[reading.gauge] = reading
        for event in events:
            log.info("alarm %s %s: %s", event.gauge, event.level, event.message)

    # ---- Zenoh command path (runs on Zenoh threads) -----------------------------------------
    def _on_command(self, gauge: str, kind: str, payload: bytes) -> dict[str, Any]:
        runner = self.runners.get(gauge)
        if runner is None:
            return {"ok": False, "message": f"unknown gauge {gauge!r}"}
        now_ns = self._now_ns(runner.tracker.camera)
        with runner.lock:
            result = runner.tracker.command(kind, payload, now_ns)
        self._publish(None, list(result.events), None, runner.tracker.camera)
        return result.to_dict()

    def _alarm_state(self, gauge: str) -> dict[str, Any] | None:
        runner = self.runners.get(gauge)
        if runner is None:
            return None
        with runner.lock:
            statuses = runner.tracker.alarm_status()
        return {"gauge": gauge, "alarms": [s.to_dict() for s in statuses]}

    # ---- ticker -------------------------------------------------------------------------------
    def _now_ns(self, camera: str) -> int:
        """The camera's frame clock, run on by the monotonic time since its last frame."""
        stamp_ns, at = self._frame_clock.get(camera, (time.time_ns(), time.monotonic()))
        return stamp_ns + int((time.monotonic() - at) * NS_PER_S)

    def _tick_loop(self) -> None:
        last_save = time.monotonic()
        while not self._stop.wait(1.0):
            for runner in self.runners.values():
                with runner.lock:
                    reading, events = runner.tracker.tick(self._now_ns(runner.tracker.camera))
                if reading is not None or events:
                    self._publish(reading, events, None, runner.tracker.camera)
            if time.monotonic() - last_save >= SAVE_EVERY_S or any(r.tracker.dirty for r in self.runners.values()):
                self._save_states()
                last_save = time.monotonic()

    def _save_states(self) -> None:
        for runner in self.runners.values():
            try:
                with runner.lock:
                    save_tracker(runner.tracker, self.config.state.dir, self._now_ns(runner.tracker.camera))
            except OSError as exc:
                log.error("gauge %s: cannot save state under %s: %s", runner.gauge, self.config.state.dir, exc)

