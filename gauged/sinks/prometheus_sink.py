"""Serve the daemon's metrics over HTTP and keep the reading gauges up to date.

The endpoint serves the daemon's own registry (:class:`gauged.metrics.Metrics`), not the process
default, at ``http://<listen>/metrics`` (any path answers). From each published reading it sets
``gauged_reading_value{gauge,unit}`` (NaN while the reading has no value; the series of a unit the
gauge no longer shows is removed), ``gauged_reading_timestamp_seconds{gauge}`` (frame time),
``gauged_reading_quality{gauge,quality}`` one-hot over good/uncertain/bad/stale and
``gauged_scale_locked{gauge}``; each stage failure increments
``gauged_stage_failures_total{gauge,stage,reason}``, which starts at zero for every configured
gauge and every known (stage, reason) pair; each alarm event sets ``gauged_alarm_active{gauge,level}``.
"""

from __future__ import annotations

import logging
from collections.abc import Iterable
from typing import Any

from prometheus_client import start_http_server

from gauged.metrics import QUALITIES, Metrics
from gauged.sinks.base import AlarmEvent, SinkBase, alarm_is_active
from gauged.sinks.config import PrometheusSinkConfig
from gauged.types import Reading, StageFailure

log = logging.getLogger(__name__)


def parse_listen(listen: str) -> tuple[str, int]:
    """``"127.0.0.1:9464"`` or ``"[::1]:9464"`` to (host, port)."""
    host, _, port = listen.rpartition(":")
    return host.strip("[]"), int(port)


class PrometheusSink(SinkBase):
    """An HTTP endpoint for the registry of ``metrics``, plus the reading/alarm gauges it updates."""

    name = "prometheus"

    def __init__(self, metrics: Metrics, listen: str = "127.0.0.1:9464", *, gauges: Iterable[str] = (),
                 failure_pairs: Iterable[tuple[str, str]] = ()) -> None:
        self.metrics = metrics
        gauges = list(gauges)
        metrics.precreate_stage_failures(gauges, failure_pairs)
        for gauge in gauges:
            metrics.scale_locked.labels(gauge=gauge).set(0)
        self._units: dict[str, str] = {}
        host, port = parse_listen(listen)
        self._server: Any
        self._server, self._thread = start_http_server(port, addr=host, registry=metrics.registry)
        self.address = (host, int(self._server.server_port))
        log.info("prometheus sink: serving metrics on http://%s:%d/metrics", *self.address)

    @classmethod
    def from_config(cls, config: PrometheusSinkConfig, metrics: Metrics, *, gauges: Iterable[str] = (),
                    failure_pairs: Iterable[tuple[str, str]] = ()) -> PrometheusSink:
        return cls(metrics, config.listen, gauges=gauges, failure_pairs=failure_pairs)

    @property
    def port(self) -> int:
        """The port actually bound (useful with port 0)."""
        return self.address[1]

    def publish_reading(self, reading: Reading) -> None:
        m, gauge = self.metrics, reading.gauge
        unit = reading.unit or ""
        previous = self._units.get(gauge)
        if previous is not None and previous != unit:
            m.reading_value.remove(gauge, previous)
        self._units[gauge] = unit
        m.reading_value.labels(gauge=gauge, unit=unit).set(
            float("nan") if reading.value is None else float(reading.value))
        m.reading_timestamp.labels(gauge=gauge).set(reading.stamp_ns / 1e9)
        for quality in QUALITIES:
            m.reading_quality.labels(gauge=gauge, quality=quality).set(1 if reading.quality.value == quality else 0)
        m.scale_locked.labels(gauge=gauge).set(1 if reading.scale.locked else 0)

    def publish_failure(self, gauge: str, camera: str, stamp_ns: int, failure: StageFailure) -> None:
        self.metrics.stage_failures.labels(gauge=gauge, stage=failure.stage, reason=failure.reason).inc()

    def publish_alarm(self, event: AlarmEvent) -> None:
        self.metrics.alarm_active.labels(gauge=str(event["gauge"]), level=str(event.get("level", ""))).set(
            1 if alarm_is_active(event) else 0)

    def close(self) -> None:
        """Stop serving and release the port."""
        self._server.shutdown()
        self._server.server_close()
        self._thread.join(timeout=5.0)
