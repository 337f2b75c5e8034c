"""Prometheus sink: a real HTTP scrape of the daemon's own registry."""

from __future__ import annotations

import math
import socket
import urllib.request

import pytest
from prometheus_client.parser import text_string_to_metric_families

from gauged.metrics import Metrics
from gauged.sinks.buffered import BufferedSink
from gauged.sinks.prometheus_sink import PrometheusSink, parse_listen
from gauged.types import Quality, StageFailure

PAIRS = [("detect", "no_gauge"), ("needle", "no_needle"), ("ocr", "no_numbers")]


def scrape(port: int) -> dict[tuple[str, frozenset], float]:
    """{(sample name, labels): value} of one HTTP scrape."""
    with urllib.request.urlopen(f"http://127.0.0.1:{port}/metrics", timeout=5) as response:
        assert response.status == 200
        text = response.read().decode()
    return {(s.name, frozenset(s.labels.items())): s.value
            for family in text_string_to_metric_families(text) for s in family.samples}


def sample(samples: dict, name: str, **labels: str) -> float | None:
    return samples.get((name, frozenset(labels.items())))


@pytest.fixture
def served():
    metrics = Metrics(build_version="1.2.3")
    sink = PrometheusSink(metrics, "127.0.0.1:0", gauges=["a", "b"], failure_pairs=PAIRS)
    yield sink, metrics
    sink.close()


def test_scrape_shows_readings_quality_scale_lock_and_build_info(served, reading):
    sink, _ = served
    sink.publish_reading(reading(3, gauge="a", value=7.25, quality=Quality.UNCERTAIN, locked=True))
    samples = scrape(sink.port)
    assert sample(samples, "gauged_build_info", version="1.2.3") == 1
    assert sample(samples, "gauged_reading_value", gauge="a", unit="bar") == 7.25
    assert sample(samples, "gauged_reading_timestamp_seconds", gauge="a") == pytest.approx(1_700_000_000.3)
    assert {q: sample(samples, "gauged_reading_quality", gauge="a", quality=q)
            for q in ("good", "uncertain", "bad", "stale")} == {"good": 0, "uncertain": 1, "bad": 0, "stale": 0}
    assert sample(samples, "gauged_scale_locked", gauge="a") == 1
    assert sample(samples, "gauged_scale_locked", gauge="b") == 0


def test_failures_start_at_zero_for_every_gauge_and_pair_and_count(served):
    sink, _ = served
    before = scrape(sink.port)
    for gauge in ("a", "b"):
        for stage, reason in PAIRS:
            assert sample(before, "gauged_stage_failures_total", gauge=gauge, stage=stage, reason=reason) == 0
    sink.publish_failure("a", "cam1", 1, StageFailure("needle", "no_needle", "x"))
    sink.publish_failure("a", "cam1", 2, StageFailure("needle", "no_needle", "y"))
    after = scrape(sink.port)
    assert sample(after, "gauged_stage_failures_total", gauge="a", stage="needle", reason="no_needle") == 2
    assert sample(after, "gauged_stage_failures_total", gauge="b", stage="needle", reason="no_needle") == 0


def test_alarm_active_follows_alarm_events(served):
    sink, _ = served
    sink.publish_alarm({"gauge": "a", "level": "high", "state": "active_unacknowledged", "stamp_ns": 1})
    sink.publish_alarm({"gauge": "a", "level": "high_high", "state": "active_unacknowledged", "stamp_ns": 1})
    sink.publish_alarm({"gauge": "a", "level": "high_high", "state": "shelved", "stamp_ns": 2})
    sink.publish_alarm({"gauge": "a", "level": "low", "state": "returned_unacknowledged", "stamp_ns": 3})
    samples = scrape(sink.port)
    assert sample(samples, "gauged_alarm_active", gauge="a", level="high") == 1
    assert sample(samples, "gauged_alarm_active", gauge="a", level="high_high") == 0
    assert sample(samples, "gauged_alarm_active", gauge="a", level="low") == 0


def test_unreadable_value_is_nan_and_a_changed_unit_replaces_the_series(served, reading):
    sink, _ = served
    sink.publish_reading(reading(0, gauge="a", unit="bar"))
    sink.publish_reading(reading(1, gauge="a", unit="psi", value=None, quality=Quality.BAD))
    samples = scrape(sink.port)
    assert sample(samples, "gauged_reading_value", gauge="a", unit="bar") is None
    assert math.isnan(sample(samples, "gauged_reading_value", gauge="a", unit="psi"))
    assert sample(samples, "gauged_reading_quality", gauge="a", quality="bad") == 1


def test_frame_counters_of_sources_are_served_too(served):
    sink, metrics = served
    metrics.add_camera("cam9")
    metrics.frames_received.labels(camera="cam9").inc(3)
    samples = scrape(sink.port)
    assert sample(samples, "gauged_frames_received_total", camera="cam9") == 3
    assert sample(samples, "gauged_frames_dropped_total", camera="cam9") == 0


def test_close_releases_the_port():
    metrics = Metrics()
    sink = BufferedSink(PrometheusSink(metrics, "127.0.0.1:0"), metrics)
    port = sink.sink.port
    assert sample(scrape(port), "gauged_sink_errors_total", sink="prometheus") == 0
    sink.close()
    with socket.socket() as probe:
        assert probe.connect_ex(("127.0.0.1", port)) != 0  # nobody serves it any more
    again = PrometheusSink(Metrics(build_version="9.9.9"), f"127.0.0.1:{port}")  # a restart binds it again
    try:
        assert sample(scrape(port), "gauged_build_info", version="9.9.9") == 1
    finally:
        again.close()


def test_parse_listen_accepts_ipv6_brackets():
    assert parse_listen("[::1]:9464") == ("::1", 9464)
    assert parse_listen("0.0.0.0:80") == ("0.0.0.0", 80)
