"""One configured gauge in the daemon: read it on a frame, lock its scale, smooth, raise alarms.

    box (ROI or detection) -> reader (full read, or needle only once the scale is locked)
        -> RawReading -> GaugeTracker (smoothing, quality, alarms) -> Reading + alarm events

A locked gauge's needle is found by a radial scan (gauged.reader.stages.needle_scan) whose look is
learnt from the last locked frame the crop model read; the crop model reads every
:data:`CROP_MODEL_EVERY`-th locked frame, and every frame the scan cannot tell.

Owned by its camera's worker thread; the Zenoh command path reaches the tracker through ``lock``.
"""

from __future__ import annotations

import logging
import threading
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from gauged.alarms.lifecycle import AlarmEvent
from gauged.config.model import GaugeConfig, ScaleLockConfig
from gauged.reader.gauge_read import GaugeRead, KnownScale
from gauged.reader.stages.ellipse import ScaleArc
from gauged.reader.stages.needle_scan import NeedleLook, ScannedNeedle, follow_needle, learn_needle_look
from gauged.tracking.scale_lock import LockedScale, ScaleLock
from gauged.tracking.tracker import GaugeTracker
from gauged.types import Box, Frame, RawReading, Reading, ScaleModel, StageFailure

log = logging.getLogger(__name__)
CROP_MODEL_EVERY = 10  # locked frames: one in ten is read by the crop model, which checks and re-learns the scan


class Reader(Protocol):
    """What a gauge needs of the reading pipeline (:class:`gauged.reader.pipeline.GaugeReader`)."""

    def read_box(self, image: np.ndarray, box: Box, score: float = 1.0, known: KnownScale | None = None,
                 primary_unit: str | None = None, located: bool = False) -> GaugeRead: ...

    def read_locked(self, image: np.ndarray, box: Box, arc: ScaleArc, scale: ScaleModel,
                    look: NeedleLook | None = None) -> GaugeRead: ...


@dataclass
class GaugeOutput:
    """What one frame produced for one gauge."""

    reading: Reading
    events: list[AlarmEvent]
    read: GaugeRead | None
    failure: StageFailure | None
    locked: bool
    lock_changed: bool


class GaugeRunner:
    """Reads one gauge frame after frame and keeps its scale lock and tracker."""

    def __init__(self, config: GaugeConfig, lock_config: ScaleLockConfig, reader: Reader, tracker: GaugeTracker):
        self.config = config
        self.reader = reader
        self.tracker = tracker
        self.scale_lock = ScaleLock(lock_config.frames, lock_config.recheck_every_s, lock_config.move_tolerance_px)
        self.known = (KnownScale(config.scale.min, config.scale.max, config.scale.unit,
                                 1 if config.scale.direction == "cw" else -1)
                      if config.scale is not None else None)
        self.lock = threading.Lock()  # guards the tracker against Zenoh command threads
        self._last_ns = 0
        self._look: NeedleLook | None = None  # the needle's look, learnt on the lock whose arc is _look_arc
        self._look_arc: ScaleArc | None = None
        self._scans = 0  # locked frames scanned since the crop model last read one

    @property
    def gauge(self) -> str:
        return self.config.id

    @property
    def needs_box(self) -> bool:
        """True while this gauge needs a box from detection this frame (no ROI, no locked scale)."""
        locked = self.scale_lock.locked
        return self.config.roi is None and (locked is None or self.scale_lock.recheck_due(self._last_ns))

    def process(self, frame: Frame, box: Box | None, score: float = 1.0) -> GaugeOutput:
        """Read this gauge on ``frame``; ``box`` is its ROI or associated detection (None: not found)."""
        self._last_ns = frame.stamp_ns
        lock_changed = False
        locked = self.scale_lock.locked
        read: GaugeRead | None = None
        if locked is not None and not self.scale_lock.recheck_due(frame.stamp_ns):
            read = self._read_locked(frame, locked)
            lock_changed = self._check_moved(read, locked.arc)
        elif box is None:
            failure = StageFailure("detect", "gauge_not_found", f"no detection associated with gauge {self.gauge}")
            return self._track(frame, None, failure, lock_changed)
        else:
            read = self.reader.read_box(frame.image, box, score, self.known, self.config.primary_unit,
                                        located=self.config.roi is None)  # a box of gauged.reader.locate
            if read.arc is not None and read.scale is not None and (read.failure is None or read.failure.stage == "reading"):
                was_locked = self.scale_lock.is_locked
                if self.scale_lock.offer(box, read.arc, read.scale, frame.stamp_ns):
                    log.info("gauge %s: scale locked (%g..%g %s)", self.gauge, read.scale.min_value,
                             read.scale.max_value, read.scale.unit or "")
                    lock_changed = True
                elif was_locked and not self.scale_lock.is_locked:
                    log.warning("gauge %s: scale re-check disagreed, lock released", self.gauge)
                    lock_changed = True
        return self._track(frame, read, read.failure, lock_changed)

    def _read_locked(self, frame: Frame, locked: LockedScale) -> GaugeRead:
        """The needle-only read of a locked frame: scanned while the scan's look is fresh, else (and
        whenever the scan cannot tell) by the crop model, whose read the look is then learnt from."""
        look = self._look if self._look_arc is locked.arc else None
        scan = look if look is not None and self._scans < CROP_MODEL_EVERY - 1 else None
        read = self.reader.read_locked(frame.image, locked.box, locked.arc, locked.scale, look=scan)
        if read.keypoints is None:  # scanned (or not even cropped)
            if isinstance(read.needle, ScannedNeedle):
                self._scans += 1
                self._look = follow_needle(look, read.needle)
            return read
        self._scans = 0
        if read.needle is not None and CROP_MODEL_EVERY > 1:  # (1: the crop model reads every frame, no scan)
            learnt = learn_needle_look(read.crop.image, locked.arc, read.needle, look)
            self._look, self._look_arc = (None, None) if isinstance(learnt, StageFailure) else (learnt, locked.arc)
        return read

    def _check_moved(self, read: GaugeRead, arc: ScaleArc) -> bool:
        if read.crop is None or read.keypoints is None or isinstance(read.keypoints, StageFailure):
            return False
        best = read.keypoints.pivot.best()
        seen = None if best is None else tuple(read.crop.points_to_frame(best[0])[0])
        expected = tuple(read.crop.points_to_frame(np.asarray(arc.centre))[0])
        if self.scale_lock.observe_pivot(seen, expected):
            log.warning("gauge %s moved in the image: scale lock released", self.gauge)
            return True
        return False

    def _track(self, frame: Frame, read: GaugeRead | None, failure: StageFailure | None,
               lock_changed: bool) -> GaugeOutput:
        value = read.value if read is not None else None
        scale = read.scale if read is not None else None
        raw = RawReading(
            gauge=self.gauge, camera=frame.camera, stamp_ns=frame.stamp_ns,
            value=None if value is None else value.value,
            unit=(scale.unit if scale is not None else None) or (read.unit if read is not None else None),
            confidence=0.0 if value is None else value.confidence,
            scale=scale, failure=failure if value is None else None,
            needle_angle=None if read is None or read.needle is None else read.needle.angle,
        )
        with self.lock:
            reading, events = self.tracker.update(raw, scale_locked=self.scale_lock.is_locked)
        return GaugeOutput(reading, events, read, raw.failure, self.scale_lock.is_locked, lock_changed)
