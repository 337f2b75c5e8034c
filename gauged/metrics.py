"""Every Prometheus metric of gauged, declared in this one module.

One :class:`Metrics` object per daemon instance owns a dedicated ``CollectorRegistry`` (never the
process-global one), so tests can build several daemons side by side. Sources count frames on it,
the reader observes stage durations on it, and the Prometheus sink updates the reading gauges and
serves it over HTTP.

Label values come from a fixed small set: gauge and camera ids from the configuration, stage and
reason tokens from the reader's fixed vocabularies, sink names (``zenoh``, ``mcap``,
``prometheus``), alarm levels and the four quality values. Never a free-text error, id or time.

Example::

    >>> m = Metrics()
    >>> m.frames_received.labels(camera="cam1").inc()
    >>> m.value("gauged_frames_received_total", camera="cam1")
    1.0
"""

from __future__ import annotations

import logging
from collections.abc import Iterable
from importlib.metadata import PackageNotFoundError, version

from prometheus_client import CollectorRegistry, Counter, Gauge, Histogram

from gauged.types import Quality

log = logging.getLogger(__name__)

QUALITIES: tuple[str, ...] = tuple(q.value for q in Quality)

# Reader stages take from ~1 ms (needle on a locked scale) to ~1 s (detection + OCR on a slow core).
STAGE_DURATION_BUCKETS_S = (0.001, 0.0025, 0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1.0, 2.5, 5.0)


def gauged_version() -> str:
    """The version of gauged: ``gauged.__version__`` when defined, else the installed metadata."""
    import gauged

    declared = getattr(gauged, "__version__", None)
    if isinstance(declared, str) and declared:
        return declared
    try:
        return version("gauged")
    except PackageNotFoundError:
        return "0+unknown"


class Metrics:
    """The metrics of one gauged daemon, registered on their own registry.

    Names follow the DESIGN contract; prometheus_client appends ``_total`` to counters, so the
    counter ``gauged_frames_received`` is exposed as ``gauged_frames_received_total``.
    """

    def __init__(self, registry: CollectorRegistry | None = None, build_version: str | None = None) -> None:
        self.registry = registry if registry is not None else CollectorRegistry(auto_describe=True)
        r = self.registry
        self.reading_value = Gauge(
            "gauged_reading_value", "Latest published reading of a gauge, in its unit (NaN when unreadable).",
            ["gauge", "unit"], registry=r)
        self.reading_timestamp = Gauge(
            "gauged_reading_timestamp_seconds", "Frame time of the latest published reading (Unix seconds).",
            ["gauge"], registry=r)
        self.reading_quality = Gauge(
            "gauged_reading_quality", "Quality of the latest reading, one-hot over good/uncertain/bad/stale.",
            ["gauge", "quality"], registry=r)
        self.frames_received = Counter(
            "gauged_frames_received", "Frames that arrived from a camera's source.", ["camera"], registry=r)
        self.frames_dropped = Counter(
            "gauged_frames_dropped", "Frames replaced by a newer one before the reader took them.",
            ["camera"], registry=r)
        self.frames_skipped = Counter(
            "gauged_frames_skipped", "Frames skipped on purpose to keep to the camera's max_rate_hz.",
            ["camera"], registry=r)
        self.frames_invalid = Counter(
            "gauged_frames_invalid", "Frames that could not be decoded into an image, by reason.",
            ["camera", "reason"], registry=r)
        self.stage_failures = Counter(
            "gauged_stage_failures", "Reader stage failures, by gauge, stage and machine-readable reason.",
            ["gauge", "stage", "reason"], registry=r)
        self.reads = Counter(
            "gauged_reads", "Frames on which a gauge was read (the denominator of the stage failure ratio).",
            ["gauge"], registry=r)
        self.stage_duration = Histogram(
            "gauged_stage_duration_seconds", "Wall time spent in one reader stage.", ["stage"],
            buckets=STAGE_DURATION_BUCKETS_S, registry=r)
        self.alarm_active = Gauge(
            "gauged_alarm_active", "1 while the alarm of this level is active on the gauge, else 0.",
            ["gauge", "level"], registry=r)
        self.scale_locked = Gauge(
            "gauged_scale_locked", "1 while the gauge's scale is locked, else 0.", ["gauge"], registry=r)
        self.build_info = Gauge(
            "gauged_build_info", "Always 1; the version label names the running gauged.", ["version"], registry=r)
        self.sink_errors = Counter(
            "gauged_sink_errors", "Publish calls of an output that raised.", ["sink"], registry=r)
        self.sink_dropped = Counter(
            "gauged_sink_dropped", "Items an output's buffer dropped because it was full or closing.",
            ["sink"], registry=r)
        self.sink_queue = Gauge(
            "gauged_sink_queue_length", "Items waiting in an output's buffer.", ["sink"], registry=r)
        self.build_info.labels(version=build_version or gauged_version()).set(1)

    def add_camera(self, camera: str) -> None:
        """Create the per-camera frame counters at zero, so dashboards see them before any frame."""
        self.frames_received.labels(camera=camera)
        self.frames_dropped.labels(camera=camera)
        self.frames_skipped.labels(camera=camera)

    def precreate_stage_failures(self, gauges: Iterable[str], pairs: Iterable[tuple[str, str]]) -> None:
        """Create ``gauged_stage_failures_total`` at zero for every gauge x (stage, reason) pair.

        ``rate()`` over a counter that appears only at its first increment misses that increment;
        pre-created series start at 0 and every failure shows.
        """
        pairs = list(pairs)
        for gauge in gauges:
            for stage, reason in pairs:
                self.stage_failures.labels(gauge=gauge, stage=stage, reason=reason)

    def value(self, name: str, **labels: str) -> float | None:
        """Current value of one sample, by its exposed name and labels (None when absent)."""
        return self.registry.get_sample_value(name, labels)
