"""The sink wrapper: drop-oldest buffering, error isolation, periodic flush, draining close."""

from __future__ import annotations

import threading
import time

import numpy as np

from gauged.metrics import Metrics
from gauged.sinks.base import SinkBase, alarm_is_active, to_json
from gauged.sinks.buffered import BufferedSink


class Recorder(SinkBase):
    """A real plugin that keeps what it is given; ``gate`` holds the worker to fill the buffer."""

    name = "recorder"

    def __init__(self, flush_interval_s: float | None = None) -> None:
        self.flush_interval_s = flush_interval_s
        self.calls: list[tuple] = []
        self.gate = threading.Event()
        self.gate.set()
        self.threads: set[str] = set()

    def publish_reading(self, reading) -> None:
        self.gate.wait()
        self.threads.add(threading.current_thread().name)
        if reading.value == 13.0:
            raise RuntimeError("unlucky")
        self.calls.append(("reading", reading.stamp_ns))

    def publish_image(self, camera, stamp_ns, image) -> None:
        self.calls.append(("image", stamp_ns))

    def flush(self) -> None:
        self.calls.append(("flush",))

    def close(self) -> None:
        self.threads.add(threading.current_thread().name)
        self.calls.append(("close",))


def test_full_buffer_drops_the_oldest_and_counts(reading):
    metrics, plugin = Metrics(), Recorder()
    plugin.gate.clear()
    sink = BufferedSink(plugin, metrics, capacity=5)
    sink.publish_reading(reading(0))
    time.sleep(0.1)  # the worker took item 0 and waits at the gate
    for i in range(1, 11):
        sink.publish_reading(reading(i))
    plugin.gate.set()
    sink.close()
    stamps = [c[1] for c in plugin.calls if c[0] == "reading"]
    assert stamps == [reading(i).stamp_ns for i in (0, 6, 7, 8, 9, 10)]
    assert metrics.value("gauged_sink_dropped_total", sink="recorder") == 5
    assert plugin.calls[-1] == ("close",) and plugin.threads == {"sink-recorder"}


def test_images_have_their_own_small_cap(reading):
    metrics, plugin = Metrics(), Recorder()
    plugin.gate.clear()
    sink = BufferedSink(plugin, metrics, max_images=2)
    sink.publish_reading(reading(0))
    time.sleep(0.1)
    for i in range(5):
        sink.publish_image("cam1", i, np.zeros((4, 4, 3), np.uint8))
    plugin.gate.set()
    sink.close()
    assert [c for c in plugin.calls if c[0] == "image"] == [("image", 0), ("image", 1)]
    assert metrics.value("gauged_sink_dropped_total", sink="recorder") == 3


def test_a_failing_call_is_counted_and_the_next_goes_through(reading, caplog):
    metrics, plugin = Metrics(), Recorder()
    sink = BufferedSink(plugin, metrics)
    sink.publish_reading(reading(0, value=13.0))
    sink.publish_reading(reading(1))
    sink.close()
    assert plugin.calls == [("reading", reading(1).stamp_ns), ("close",)]
    assert metrics.value("gauged_sink_errors_total", sink="recorder") == 1
    assert any("RuntimeError: unlucky" in r.getMessage() for r in caplog.records)


def test_flush_runs_periodically_while_idle():
    plugin = Recorder(flush_interval_s=0.05)
    sink = BufferedSink(plugin)
    time.sleep(0.4)
    sink.close()
    assert 3 <= plugin.calls.count(("flush",)) <= 10


def test_publish_after_close_is_dropped_and_counted(reading):
    metrics, plugin = Metrics(), Recorder()
    sink = BufferedSink(plugin, metrics)
    sink.close()
    sink.publish_reading(reading(0))
    assert plugin.calls == [("close",)]
    assert metrics.value("gauged_sink_dropped_total", sink="recorder") == 1


def test_json_has_no_nan_and_alarm_states_map_to_active():
    assert to_json({"v": float("nan"), "w": [float("inf"), np.float32(1.5)]}) == b'{"v":null,"w":[null,1.5]}'
    assert alarm_is_active({"state": "active_unacknowledged"}) and alarm_is_active({"state": "active_acknowledged"})
    for state in ("normal", "returned_unacknowledged", "shelved"):
        assert not alarm_is_active({"state": state})
