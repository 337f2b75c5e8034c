"""The metrics module: one registry per daemon, contract names, pre-created series, version."""

from __future__ import annotations

from prometheus_client import generate_latest

import gauged
from gauged.metrics import Metrics, gauged_version

CONTRACT = ["gauged_reading_value", "gauged_reading_timestamp_seconds", "gauged_reading_quality",
            "gauged_frames_received_total", "gauged_frames_dropped_total", "gauged_stage_failures_total",
            "gauged_stage_duration_seconds", "gauged_alarm_active", "gauged_scale_locked", "gauged_build_info"]


def test_every_contract_metric_is_exposed_with_its_name():
    metrics = Metrics()
    metrics.add_camera("cam1")
    metrics.precreate_stage_failures(["g"], [("ocr", "no_numbers")])
    metrics.reading_value.labels(gauge="g", unit="bar").set(1)
    metrics.reading_timestamp.labels(gauge="g").set(1)
    metrics.reading_quality.labels(gauge="g", quality="good").set(1)
    metrics.stage_duration.labels(stage="ocr").observe(0.02)
    metrics.alarm_active.labels(gauge="g", level="high").set(0)
    metrics.scale_locked.labels(gauge="g").set(1)
    text = generate_latest(metrics.registry).decode()
    for name in CONTRACT:
        assert f"\n{name}{{" in text or text.startswith(f"{name}{{") or f"\n{name}_bucket{{" in text, name
    assert metrics.value("gauged_stage_duration_seconds_count", stage="ocr") == 1


def test_two_daemons_have_independent_registries():
    first, second = Metrics(), Metrics()
    first.frames_received.labels(camera="cam1").inc()
    assert first.value("gauged_frames_received_total", camera="cam1") == 1
    assert second.value("gauged_frames_received_total", camera="cam1") is None


def test_precreated_failures_start_at_zero():
    metrics = Metrics()
    metrics.precreate_stage_failures(["a", "b"], [("detect", "no_gauge"), ("needle", "no_needle")])
    for gauge in ("a", "b"):
        assert metrics.value("gauged_stage_failures_total", gauge=gauge, stage="needle", reason="no_needle") == 0
    assert metrics.value("gauged_stage_failures_total", gauge="c", stage="needle", reason="no_needle") is None


def test_build_info_names_the_package_version(monkeypatch):
    monkeypatch.setattr(gauged, "__version__", "7.7.7", raising=False)
    assert gauged_version() == "7.7.7"
    assert Metrics().value("gauged_build_info", version="7.7.7") == 1
    monkeypatch.delattr(gauged, "__version__", raising=False)
    assert gauged_version()  # installed metadata, or the fallback: never empty
