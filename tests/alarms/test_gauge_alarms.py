from __future__ import annotations

from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gauged.alarms.config import AlarmsConfig
from gauged.alarms.gauge_alarms import GaugeAlarms
from gauged.alarms.lifecycle import AlarmEvent, Transition
from gauged.tracking.config import SmoothingConfig
from gauged.types import FrameOutcome
from gauged.tracking.tracker import GaugeTracker
from gauged.types import Quality, RawReading, Reading, ScaleInfo

NS = 1_000_000_000
VALUE_LEVELS = ("low_low", "low", "high", "high_high", "rate")
HELD, BAD, STALE = "held", "bad", "stale"


def reading(t_s: float, value: float | str) -> tuple[Reading, FrameOutcome]:
    """A published reading as the smoother would give it: a float is a fresh good value; HELD an
    uncertain held 5.0; BAD and STALE failed frames."""
    if isinstance(value, float):
        quality, shown, outcome = Quality.GOOD, value, FrameOutcome.ACCEPTED
    elif value == HELD:
        quality, shown, outcome = Quality.UNCERTAIN, 5.0, FrameOutcome.REJECTED
    else:
        quality, shown, outcome = (Quality.BAD if value == BAD else Quality.STALE), None, FrameOutcome.FAILED
    r = Reading("g", "cam", round(t_s * NS), shown, shown, "bar", quality, 1.0, ScaleInfo(0.0, 10.0, "bar"))
    return r, outcome


def run(alarms: GaugeAlarms, script: list[tuple[float, float | str]]) -> list[tuple[float, str, str]]:
    events: list[AlarmEvent] = []
    for t, value in script:
        events += alarms.update(*reading(t, value))
    return [(round(e.stamp_ns / NS, 6), e.level, e.transition.value) for e in events]


def frames(start: float, stop: float, value: float | str, fps: float = 10.0) -> list[tuple[float, float | str]]:
    n = round((stop - start) * fps)
    return [(round(start + i / fps, 6), value) for i in range(n)]


LIMITS = {"low_low": 1.0, "low": 2.0, "high": 8.0, "high_high": 9.0, "deadband": 0.2}
DELAYED = {**LIMITS, "on_delay_s": 1.0, "off_delay_s": 1.0}

# name, config, script, expected (t s, level, transition) events.
SCRIPTS: list[tuple[str, dict[str, Any], list[tuple[float, float | str]], list[tuple[float, str, str]]]] = [
    ("steady in range", DELAYED, frames(0, 5, 5.0), []),
    ("step up waits the on-delay", DELAYED, frames(0, 1, 5.0) + frames(1, 3, 8.5), [(2.0, "high", "activated")]),
    ("step up and down waits the off-delay", DELAYED,
     frames(0, 1, 5.0) + frames(1, 3, 8.5) + frames(3, 5, 7.7),
     [(2.0, "high", "activated"), (4.0, "high", "cleared")]),
    ("back inside the deadband does not clear", DELAYED,
     frames(0, 1, 5.0) + frames(1, 3, 8.5) + frames(3, 6, 7.85), [(2.0, "high", "activated")]),
    ("single-frame spike above high-high", DELAYED, frames(0, 1, 5.0) + [(1.0, 9.5)] + frames(1.1, 3, 5.0), []),
    ("short excursion under the on-delay", DELAYED, frames(0, 1, 5.0) + frames(1, 1.9, 8.5) + frames(1.9, 4, 5.0), []),
    ("noise of deadband/2 at the limit, no delay", {**LIMITS},
     [(i / 10, 8.0 + (0.1 if i % 2 else -0.1)) for i in range(100)], [(0.1, "high", "activated")]),
    ("noise of deadband/2 at the limit, random phase", {**LIMITS, "off_delay_s": 1.0},
     [(i / 10, 8.0 + 0.1 * ((i * 7919) % 13 - 6) / 6) for i in range(200)], [(0.3, "high", "activated")]),
    ("ramp up crosses high then high-high", DELAYED,
     [(i / 10, 7.0 + 0.1 * i) for i in range(40)], [(2.0, "high", "activated"), (3.0, "high_high", "activated")]),
    ("dip below low but not low-low", DELAYED, frames(0, 1, 5.0) + frames(1, 4, 1.5), [(2.0, "low", "activated")]),
    ("bad frames cancel a pending activation", DELAYED,
     frames(0, 1, 5.0) + frames(1, 1.5, 8.5) + [(1.5, BAD)] + frames(1.6, 3, 8.5), [(2.6, "high", "activated")]),
    ("held frames keep a pending activation", DELAYED,
     frames(0, 1, 5.0) + frames(1, 1.5, 8.5) + frames(1.5, 2, HELD) + frames(2, 3, 8.5), [(2.0, "high", "activated")]),
    # Failed frames also feed the failure ratio (30 s window): once as many failed as read, it fires.
    ("bad and stale values neither raise nor clear", DELAYED,
     frames(0, 3, 8.5) + frames(3, 8, BAD) + frames(8, 20, STALE) + frames(20, 22, 8.5),
     [(1.0, "high", "activated"), (5.9, "failure", "activated"), (8.0, "stale", "activated"),
      (20.0, "stale", "cleared")]),
    ("failing frames while in range give stale and failure alarms only", DELAYED,
     frames(0, 2, 5.0) + frames(2, 14, STALE) + frames(14, 15, 5.0),
     [(2.0, "stale", "activated"), (3.9, "failure", "activated"), (14.0, "stale", "cleared")]),
    ("rate of change", {"max_rate_per_s": 1.0, "rate_window_s": 2.0},
     frames(0, 3, 5.0) + [(3 + i / 10, 5.0 + 0.2 * i) for i in range(1, 21)] + frames(5.1, 9, 9.0),
     [(4.1, "rate", "activated"), (6.0, "rate", "cleared")]),  # 2 units/s over a 2 s window
    ("failure ratio", {"failure_window_s": 2.0, "failure_ratio": 0.5},
     frames(0, 2, 5.0) + [(2 + i / 10, BAD if i % 4 else 5.0) for i in range(40)] + frames(6, 9, 5.0),
     [(3.3, "failure", "activated"), (7.4, "failure", "cleared")]),  # clears below half the ratio
]


@pytest.mark.parametrize(("name", "config", "script", "expected"), SCRIPTS, ids=[s[0] for s in SCRIPTS])
def test_gauge_alarms_scripted_sequences(
        name: str, config: dict[str, Any], script: list[tuple[float, float | str]],
        expected: list[tuple[float, str, str]]) -> None:
    assert run(GaugeAlarms("g", AlarmsConfig(**config)), script) == expected


def test_gauge_alarms_levels_follow_the_config() -> None:
    assert GaugeAlarms("g", AlarmsConfig(high=3.0, max_rate_per_s=1.0)).levels == ("high", "rate", "stale", "failure")
    assert GaugeAlarms("g", AlarmsConfig()).levels == ("stale", "failure")


def test_gauge_alarms_per_limit_deadband() -> None:
    alarms = GaugeAlarms("g", AlarmsConfig(high=8.0, high_high=9.0, deadband={"high": 1.0, "high_high": 0.1}))
    events = run(alarms, frames(0, 1, 9.5) + frames(1, 2, 8.5))
    assert events == [(0.0, "high", "activated"), (0.0, "high_high", "activated"), (1.0, "high_high", "cleared")]


def test_gauge_alarms_event_carries_value_limit_and_unit() -> None:
    alarms = GaugeAlarms("boiler", AlarmsConfig(high=8.0))
    [event] = alarms.update(*reading(1.0, 8.25))
    assert (event.value, event.limit, event.message) == (8.25, 8.0, "boiler HI: 8.25 bar >= limit 8 bar")


def test_gauge_alarms_stale_clears_only_on_a_valid_reading() -> None:
    alarms = GaugeAlarms("g", AlarmsConfig())
    alarms.restore({"stale": {"state": "active_acknowledged", "active": True}})
    assert run(alarms, [(0.0, BAD), (0.1, HELD), (0.2, 5.0)]) == [(0.2, "stale", "cleared")]


def test_gauge_alarms_rebase_keeps_states_and_drops_delays() -> None:
    alarms = GaugeAlarms("g", AlarmsConfig(**DELAYED))
    run(alarms, frames(0, 3, 8.5) + frames(3, 3.5, 5.0))
    alarms.rebase()
    assert alarms.alarms["high"].active
    assert run(alarms, frames(0, 1.1, 5.0)) == [(1.0, "high", "cleared")]


def test_gauge_alarms_dirty_after_a_change_until_snapshot() -> None:
    alarms = GaugeAlarms("g", AlarmsConfig(high=8.0))
    run(alarms, frames(0, 1, 5.0))
    assert not alarms.dirty
    run(alarms, [(1.0, 9.0)])
    assert alarms.dirty
    alarms.snapshot()
    assert not alarms.dirty


steps = st.lists(
    st.tuples(st.sampled_from([0.05, 0.1, 0.3, 1.0, 4.0]),
              st.one_of(st.floats(0.0, 12.0), st.sampled_from([HELD, BAD, STALE]))),
    min_size=1, max_size=120)


def check_alarm_events(events: list[AlarmEvent], on_delay_s: float, off_delay_s: float,
                       unjudged_ns: set[int]) -> None:
    """Per level, activations and clears alternate (starting with an activation), an activation and
    the clear after it are at least the off-delay apart, a clear and the next activation at least
    the on-delay, and no value alarm changes on a bad or stale reading."""
    by_level: dict[str, list[AlarmEvent]] = {}
    for event in events:
        if event.transition in (Transition.ACTIVATED, Transition.CLEARED):
            by_level.setdefault(event.level, []).append(event)
    for level, changes in by_level.items():
        kinds = [e.transition for e in changes]
        assert kinds == [Transition.ACTIVATED, Transition.CLEARED] * (len(kinds) // 2) + [Transition.ACTIVATED] * (len(kinds) % 2)
        if level in VALUE_LEVELS:
            for before, after in zip(changes, changes[1:]):
                delay = off_delay_s if before.transition is Transition.ACTIVATED else on_delay_s
                assert after.stamp_ns - before.stamp_ns >= delay * NS
            assert not {e.stamp_ns for e in changes} & unjudged_ns


@settings(max_examples=150, deadline=None)
@given(steps, st.sampled_from([0.0, 0.2, 1.0]), st.sampled_from([0.0, 0.5, 2.0]), st.sampled_from([0.0, 0.3]))
def test_gauge_alarms_never_activate_and_clear_within_a_delay(
        script: list[tuple[float, float | str]], on_delay_s: float, off_delay_s: float, deadband: float) -> None:
    alarms = GaugeAlarms("g", AlarmsConfig(low_low=1.0, low=2.0, high=8.0, high_high=9.0, deadband=deadband,
                                           on_delay_s=on_delay_s, off_delay_s=off_delay_s, max_rate_per_s=2.0))
    t, events, unjudged = 0.0, [], set()
    for gap, value in script:
        t += gap
        r, outcome = reading(t, value)
        if value in (BAD, STALE):
            unjudged.add(r.stamp_ns)
        events += alarms.update(r, outcome)
    check_alarm_events(events, on_delay_s, off_delay_s, unjudged)


raw_steps = st.lists(
    st.tuples(st.sampled_from([0.05, 0.1, 0.5, 2.0, 12.0]),
              st.one_of(st.floats(0.0, 12.0), st.none(), st.just("tick"))),
    min_size=1, max_size=150)


@settings(max_examples=100, deadline=None)
@given(raw_steps, st.sampled_from([0.0, 0.5]), st.sampled_from([0.0, 1.0]), st.sampled_from(["kalman", "none"]))
def test_gauge_tracker_alarms_never_activate_and_clear_within_a_delay(
        script: list[tuple[float, float | str | None]], on_delay_s: float, off_delay_s: float, method: str) -> None:
    # The same property end to end: raw readings with failures, gaps and ticks through the smoother.
    tracker = GaugeTracker("g", "cam", SmoothingConfig(method=method),  # type: ignore[arg-type]
                           AlarmsConfig(low=2.0, high=8.0, high_high=9.0, deadband=0.2, on_delay_s=on_delay_s,
                                        off_delay_s=off_delay_s, stale_after_s=5.0, max_rate_per_s=3.0),
                           ScaleInfo(0.0, 10.0, "bar"))
    t, events, unjudged = 0.0, [], set()
    for gap, value in script:
        t += gap
        stamp = round(t * NS)
        if value == "tick":
            shown, new = tracker.tick(stamp)
        else:
            shown, new = tracker.update(RawReading("g", "cam", stamp, value, "bar", 1.0))  # type: ignore[arg-type]
        if shown is not None and shown.quality in (Quality.BAD, Quality.STALE):
            unjudged.add(stamp)
        events += new
    check_alarm_events(events, on_delay_s, off_delay_s, unjudged)
