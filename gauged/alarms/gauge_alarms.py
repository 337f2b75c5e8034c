"""All alarm rules of one gauge: limits, rate of change, stale and reading failure.

Input is the stream of published readings with the :class:`FrameOutcome` of each. Value alarms
(limits and rate) are judged only on *fresh* values, those accepted from this frame's measurement;
a ``bad`` or ``stale`` reading neither raises nor clears them and cancels any delay in progress, and
a held (``uncertain``) value leaves them as they are. The stale alarm follows the ``stale`` quality;
the failure alarm watches the share of frames without an accepted value over a time window.
"""

from __future__ import annotations

from collections import deque
from typing import Any

from gauged.alarms.condition import NS_PER_S, DelayedCondition, LimitRule
from gauged.alarms.config import AlarmsConfig
from gauged.alarms.lifecycle import Alarm, AlarmEvent, AlarmStatus
from gauged.types import FrameOutcome, Quality, Reading

RATE_LEVEL = "rate"
STALE_LEVEL = "stale"
FAILURE_LEVEL = "failure"
FAILURE_CLEAR_FRACTION = 0.5  # the failure alarm clears below half its ratio, so it cannot chatter
ALL = "all"


class GaugeAlarms:
    """The alarms of one gauge. Pure logic: time is the reading's ``stamp_ns`` or the ``now_ns`` given."""

    def __init__(self, gauge: str, config: AlarmsConfig) -> None:
        self.gauge = gauge
        self.config = config
        on_ns, off_ns = int(config.on_delay_s * NS_PER_S), int(config.off_delay_s * NS_PER_S)
        self._rules = {level: LimitRule(level, limit, config.deadband_of(level))
                       for level, limit in config.limits().items() if limit is not None}
        self._delays = {level: DelayedCondition(on_ns, off_ns) for level in self._rules}
        self.alarms: dict[str, Alarm] = {level: Alarm(gauge, level, rule.limit) for level, rule in self._rules.items()}
        if config.max_rate_per_s is not None:
            self._delays[RATE_LEVEL] = DelayedCondition(on_ns, off_ns)
            self.alarms[RATE_LEVEL] = Alarm(gauge, RATE_LEVEL, config.max_rate_per_s)
        self.alarms[STALE_LEVEL] = Alarm(gauge, STALE_LEVEL, config.stale_after_s)
        self.alarms[FAILURE_LEVEL] = Alarm(gauge, FAILURE_LEVEL, config.failure_ratio)
        self._recent: deque[tuple[int, float]] = deque()  # (stamp_ns, fresh value) for the rate
        self._frames: deque[tuple[int, bool]] = deque()  # (stamp_ns, failed) for the failure ratio
        self._unit = ""
        self.dirty = False  # an alarm state changed since the last snapshot

    @property
    def levels(self) -> tuple[str, ...]:
        """Configured alarm levels, in display order."""
        return tuple(self.alarms)

    def status(self) -> list[AlarmStatus]:
        return [alarm.status() for alarm in self.alarms.values()]

    def _emit(self, events: list[AlarmEvent], event: AlarmEvent | None) -> None:
        if event is not None:
            events.append(event)
            self.dirty = True

    # --- readings -----------------------------------------------------------------------------

    def update(self, reading: Reading, outcome: FrameOutcome) -> list[AlarmEvent]:
        """Judge one published reading; return the alarm state changes it causes."""
        now = reading.stamp_ns
        self._unit = f" {reading.unit}" if reading.unit else ""
        events = self.tick(now)
        if outcome is not FrameOutcome.NO_FRAME:
            self._judge_failures(now, outcome is not FrameOutcome.ACCEPTED, events)
        stale_alarm = self.alarms[STALE_LEVEL]
        if reading.quality is Quality.STALE:
            message = f"{self.gauge}: no valid reading for {self.config.stale_after_s:g} s"
            self._emit(events, stale_alarm.set_active(True, now, None, message))
        elif outcome is FrameOutcome.ACCEPTED:  # only a valid reading ends staleness, not a failed frame
            self._emit(events, stale_alarm.set_active(False, now, None, f"{self.gauge}: valid readings again"))
        if outcome is FrameOutcome.ACCEPTED and reading.value is not None:
            self._judge_limits(now, reading.value, events)
            self._judge_rate(now, reading.value, events)
        elif reading.quality in (Quality.BAD, Quality.STALE):
            self._lose_values()
        return events

    def _lose_values(self) -> None:
        for delay in self._delays.values():
            delay.cancel_pending()
        self._recent.clear()

    def _judge_limits(self, now: int, value: float, events: list[AlarmEvent]) -> None:
        for level, rule in self._rules.items():
            delay = self._delays[level]
            if delay.observe(rule.past(value, delay.active), now):
                message = (rule.activated_message if delay.active else rule.cleared_message)(self.gauge, value, self._unit)
                self._emit(events, self.alarms[level].set_active(delay.active, now, value, message))

    def _judge_rate(self, now: int, value: float, events: list[AlarmEvent]) -> None:
        limit = self.config.max_rate_per_s
        if limit is None:
            return
        window_ns = int(self.config.rate_window_s * NS_PER_S)
        self._recent.append((now, value))
        while self._recent and self._recent[0][0] < now - window_ns:
            self._recent.popleft()
        first_ns, first_value = self._recent[0]
        if now - first_ns < window_ns // 2:
            return  # too short a baseline: noise would pass for a rate
        rate = (value - first_value) * NS_PER_S / (now - first_ns)
        delay = self._delays[RATE_LEVEL]
        if delay.observe(abs(rate) > limit, now):
            word = "rate" if delay.active else "rate back to normal"
            message = f"{self.gauge} {word}: {rate:+.3g}{self._unit}/s (limit {limit:g}{self._unit}/s)"
            self._emit(events, self.alarms[RATE_LEVEL].set_active(delay.active, now, rate, message))

    def _judge_failures(self, now: int, failed: bool, events: list[AlarmEvent]) -> None:
        window_ns = int(self.config.failure_window_s * NS_PER_S)
        self._frames.append((now, failed))
        while self._frames and self._frames[0][0] <= now - window_ns:
            self._frames.popleft()
        if len(self._frames) < self.config.failure_min_frames:
            return
        ratio = sum(f for _, f in self._frames) / len(self._frames)
        alarm = self.alarms[FAILURE_LEVEL]
        threshold = self.config.failure_ratio * (FAILURE_CLEAR_FRACTION if alarm.active else 1.0)
        active = ratio >= threshold
        message = (f"{self.gauge}: {ratio:.0%} of frames failed over {self.config.failure_window_s:g} s"
                   if active else f"{self.gauge}: reading failures down to {ratio:.0%}")
        self._emit(events, alarm.set_active(active, now, ratio, message))

    def tick(self, now_ns: int) -> list[AlarmEvent]:
        """Let time pass without a reading: timed shelves expire."""
        events: list[AlarmEvent] = []
        for alarm in self.alarms.values():
            self._emit(events, alarm.expire(now_ns))
        return events

    def rebase(self) -> None:
        """Frame time went backwards (a looped recording): drop delays and windows, keep states."""
        self._lose_values()
        self._frames.clear()

    # --- operator actions ---------------------------------------------------------------------

    def _select(self, level: str) -> list[Alarm]:
        if level == ALL:
            return list(self.alarms.values())
        if level not in self.alarms:
            raise KeyError(level)
        return [self.alarms[level]]

    def acknowledge(self, level: str, who: str, why: str | None, now_ns: int) -> list[AlarmEvent]:
        """Acknowledge one level or ``"all"``; alarms not awaiting acknowledgement are left alone."""
        events: list[AlarmEvent] = []
        for alarm in self._select(level):
            self._emit(events, alarm.acknowledge(who, why, now_ns))
        return events

    def shelve(self, level: str, who: str, why: str, now_ns: int, duration_s: float) -> list[AlarmEvent]:
        """Shelve one level or ``"all"`` for ``duration_s`` seconds of frame time."""
        until = now_ns + int(duration_s * NS_PER_S)
        events: list[AlarmEvent] = []
        for alarm in self._select(level):
            self._emit(events, alarm.shelve(who, why, now_ns, until))
        self.dirty = True  # a re-shelve changes the end time without an event
        return events

    def unshelve(self, level: str, who: str, why: str | None, now_ns: int) -> list[AlarmEvent]:
        events: list[AlarmEvent] = []
        for alarm in self._select(level):
            self._emit(events, alarm.unshelve(who, why, now_ns))
        return events

    # --- persistence --------------------------------------------------------------------------

    def snapshot(self) -> dict[str, Any]:
        """Alarm states and shelves by level (delays in progress and windows are not kept)."""
        self.dirty = False
        return {level: alarm.snapshot() for level, alarm in self.alarms.items()}

    def restore(self, saved: dict[str, Any]) -> list[str]:
        """Take back a :meth:`snapshot`; returns notes on levels that could not be restored."""
        notes: list[str] = []
        if not isinstance(saved, dict):
            return [f"alarms: expected a mapping of levels, got {type(saved).__name__}"]
        for level, state in saved.items():
            alarm = self.alarms.get(level)
            if alarm is None:
                notes.append(f"alarm {level!r} is no longer configured; its saved state is dropped")
                continue
            if not isinstance(state, dict):
                notes.append(f"alarm {level!r}: expected a mapping, got {type(state).__name__}; it starts normal")
                continue
            try:
                alarm.restore(state)
            except ValueError as exc:
                notes.append(f"{exc}; it starts normal")
                continue
            if level in self._delays:
                self._delays[level].active = alarm.active
        return notes
