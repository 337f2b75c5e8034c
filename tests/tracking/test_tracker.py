from __future__ import annotations

from pathlib import Path

import pytest

from gauged.alarms.config import AlarmsConfig
from gauged.alarms.lifecycle import AlarmEvent, AlarmState
from gauged.config.model import GaugeConfig
from gauged.tracking.config import SmoothingConfig
from gauged.tracking.state_file import restore_tracker, save_tracker
from gauged.tracking.tracker import GaugeTracker
from gauged.types import Quality, RawReading, ScaleInfo, StageFailure

NS = 1_000_000_000
FPS = 10


def tracker(smoothing: dict[str, object] | None = None, **alarms: object) -> GaugeTracker:
    return GaugeTracker("boiler", "cam1", SmoothingConfig(**(smoothing or {})),
                        AlarmsConfig(**alarms), ScaleInfo(0.0, 10.0, "bar"))  # type: ignore[arg-type]


def raw(t_s: float, value: float | None) -> RawReading:
    failure = None if value is not None else StageFailure("needle", "no_line")
    return RawReading("boiler", "cam1", round(t_s * NS), value, "bar", 0.95, None, failure)


def feed(t: GaugeTracker, start_s: float, values: list[float | None]) -> list[AlarmEvent]:
    events: list[AlarmEvent] = []
    for i, value in enumerate(values):
        events += t.update(raw(start_s + i / FPS, value))[1]
    return events


def summary(events: list[AlarmEvent]) -> list[tuple[str, str]]:
    return [(e.level, e.transition.value) for e in events]


def test_gauge_tracker_noise_of_half_deadband_at_the_limit_activates_once() -> None:
    t = tracker(high=8.0, deadband=0.2)
    noise = [8.0 + 0.1 * (((i * 7919) % 11) - 5) / 5 for i in range(600)]  # within +/- deadband/2
    events = feed(t, 0.0, [5.0] * 20 + noise)
    assert summary(events) == [("high", "activated")]


@pytest.mark.parametrize("smoothing", [{"method": "none", "hampel_window": 1}, {}], ids=["unfiltered", "defaults"])
def test_gauge_tracker_single_frame_spike_above_high_high_raises_nothing(smoothing: dict[str, object]) -> None:
    t = tracker(smoothing, high=8.0, high_high=9.0, on_delay_s=0.5)
    events = feed(t, 0.0, [5.0] * 20 + [9.8] + [5.0] * 20)
    assert events == []


def test_gauge_tracker_dropout_longer_than_stale_raises_stale_and_leaves_value_alarms() -> None:
    t = tracker(high=8.0, stale_after_s=5.0)
    events = feed(t, 0.0, [8.5] * 20)
    assert summary(events) == [("high", "activated")]
    assert t.command("ack", {"level": "high", "who": "alice"}, 2 * NS)
    dropout: list[AlarmEvent] = []
    for second in range(2, 20):  # no frames for 18 s, the daemon ticks every second
        reading, events = t.tick(second * NS)
        dropout += events
        if reading is not None:
            assert (reading.quality, reading.value) == (Quality.STALE, None)
    assert summary(dropout) == [("stale", "activated")]
    assert t.last_reading is not None and t.last_reading.quality is Quality.STALE
    back = feed(t, 20.0, [8.5] * 10)
    assert summary(back) == [("stale", "cleared")]
    assert t.alarms.alarms["high"].state is AlarmState.ACTIVE_ACKNOWLEDGED


def test_gauge_tracker_failed_frames_never_zero_the_value() -> None:
    t = tracker()
    feed(t, 0.0, [4.0] * 10)
    reading, _ = t.update(raw(1.0, None))
    assert (reading.quality, reading.value, reading.raw_value) == (Quality.UNCERTAIN, pytest.approx(4.0), None)
    assert reading.failure == StageFailure("needle", "no_line")


def test_gauge_tracker_restart_keeps_an_acknowledged_alarm_acknowledged(tmp_path: Path) -> None:
    before = tracker(high=8.0, off_delay_s=1.0)
    feed(before, 0.0, [8.5] * 20)
    ack = before.command("ack", b'{"level": "high", "who": "alice", "why": "known"}', 2 * NS)
    assert ack and before.dirty
    save_tracker(before, tmp_path, 2 * NS)
    assert not before.dirty

    after = tracker(high=8.0, off_delay_s=1.0)
    result = restore_tracker(after, tmp_path, now_ns=60 * NS, max_age_s=3600.0)
    assert result and result.warnings == ()
    assert feed(after, 60.0, [8.5] * 30) == []  # still past the limit: no new annunciation
    assert after.alarms.alarms["high"].state is AlarmState.ACTIVE_ACKNOWLEDGED
    cleared = feed(after, 63.0, [7.0] * 30)
    assert [(e.level, e.state) for e in cleared] == [("high", AlarmState.NORMAL)]


def test_gauge_tracker_camera_dark_from_start_goes_stale() -> None:
    t = tracker(stale_after_s=10.0)
    assert t.tick(1000 * NS) == (None, [])
    reading, events = t.tick(1010 * NS)
    assert reading is not None and reading.quality is Quality.STALE
    assert summary(events) == [("stale", "activated")]


def test_gauge_tracker_time_going_back_starts_a_new_track() -> None:
    t = tracker(high=8.0)
    feed(t, 100.0, [8.5] * 10)
    reading, events = t.update(raw(1.0, 8.5))  # the recording looped
    assert reading.quality is Quality.UNCERTAIN and "recovering" in reading.reasons
    assert events == [] and t.alarms.alarms["high"].active


def test_gauge_tracker_refuses_another_gauges_reading() -> None:
    with pytest.raises(ValueError, match="tank"):
        tracker().update(RawReading("tank", "cam1", 0, 1.0, None, 1.0))


def test_gauge_tracker_from_config_uses_the_configured_scale() -> None:
    config = GaugeConfig(id="boiler", camera="cam1", scale={"min": 0, "max": 600, "unit": "psi"},  # type: ignore[arg-type]
                         alarms={"high": 500})  # type: ignore[arg-type]
    t = GaugeTracker.from_config(config)
    assert (t.smoother.measurement_noise, t.alarms.levels[0]) == (3.0, "high")
    reading, _ = t.update(RawReading("boiler", "cam1", 0, 100.0, None, 1.0))
    assert reading.unit == "psi" and reading.scale.max == 600
